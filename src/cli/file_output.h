// Text outputs written whole or not at all (STYLE.md): a temporary file beside the target,
// renamed into place when complete.
#pragma once

#include <optional>
#include <string>
#include <string_view>

namespace patchscan::cli {

// Writes `contents` to `path` through a temporary file beside it. On failure nothing is
// left at `path` or beside it, and the result is the message for the user (naming `path`).
std::optional<std::string> WriteFileWhole(const std::string& path, std::string_view contents);

}  // namespace patchscan::cli
