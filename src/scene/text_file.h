// Whole-file reading for the scene readers.
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <variant>

#include "core/shortest_number.h"
#include "scene/source_error.h"

namespace patchscan {

// The whole content of `path`, or the error that prevented reading it (no line number).
// Refuses files larger than kMaxSceneFileBytes.
// A gzip-compressed file (by its magic bytes, as `.rib.gz` archives are) is decompressed.
std::variant<std::string, SourceError> ReadTextFile(const std::string& path);
// The decompressed contents of gzip data read from `path` (for messages); at most 1 GiB.
std::variant<std::string, SourceError> Gunzip(std::string_view data, const std::string& path);

// Scene files are text; one of more than 1 GiB is not a scene this program can hold.
constexpr long long kMaxSceneFileBytes = 1LL << 30;

// A token as the user should see it in a message: quoted, at most 24 characters,
// non-printable bytes as '?'.
std::string Shown(std::string_view token);

// A decimal number as the whole token (a leading '+' allowed); nullopt if the token is
// not one, and {false, ...} for a number that is not finite (nan, inf, or beyond the
// range of double). Underflow reads as the nearest representable value.
struct Number {
  bool finite;
  double value;
};
std::optional<Number> ParseNumber(std::string_view token);

}  // namespace patchscan
