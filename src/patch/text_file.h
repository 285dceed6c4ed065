// Whole-file reading for the scene readers.
#pragma once

#include <variant>
#include <string>

#include "patch/source_error.h"

namespace patchscan {

// The whole content of `path`, or the error that prevented reading it (no line number).
// Refuses files larger than kMaxSceneFileBytes.
std::variant<std::string, SourceError> ReadTextFile(const std::string& path);

// Scene files are text; one of more than 1 GiB is not a scene this program can hold.
constexpr long long kMaxSceneFileBytes = 1LL << 30;

}  // namespace patchscan
