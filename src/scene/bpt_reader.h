// Reader for the Bézier patch text format (.bpt; surfaces/README.md): a patch count, then
// per patch its dimensions, `3 3` (degrees) or `4 4` (point counts), and 16 control points
// x y z with u varying fastest. Tokens are separated by any whitespace (CRLF and tabs
// included); `#` starts a comment that runs to the end of the line.
//
// Two layouts are accepted. When the count stands alone on its line, the next line holds
// at most three numbers and the line after it fewer than six, the file is read line by line and every record must fill exactly its own line (so a
// missing or extra number is reported on the line where it is). Otherwise the tokens are
// read as one free stream (for example, everything on one line).
#pragma once

#include <array>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "patch/geometry.h"
#include "scene/source_error.h"

namespace patchscan {

// Upper bound on a file's patch count: a thousand teapots are 32,000 patches; a count
// beyond this is taken as a corrupt file, not as a request to read a billion patches.
constexpr long long kMaxBptPatches = 10'000'000;

struct BptPatch {
  std::array<Vec3, 16> cv;  // Bézier control points, u fastest
  int line = 0;             // line of the patch's dimensions
};

struct BptFile {
  std::vector<BptPatch> patches;
};

// Parse .bpt text; `name` is used in error messages. Memory grows with the text, never
// with the count the text claims. Never throws on bad input.
std::variant<BptFile, SourceError> ParseBpt(std::string_view text, const std::string& name);

// Read and parse a .bpt file.
std::variant<BptFile, SourceError> ReadBpt(const std::string& path);

}  // namespace patchscan
