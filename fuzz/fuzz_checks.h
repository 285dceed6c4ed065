// What every fuzz target asserts of a reader's answer: a scene, or an error that names the
// input and, when it has one, a line within it. Anything else stops the fuzzer.
#pragma once

#include <cstdlib>
#include <string>
#include <string_view>

#include "scene/source_error.h"

namespace patchscan::fuzz {

inline void Require(bool ok) {
  if (!ok) std::abort();
}

inline void CheckError(const SourceError& e, const std::string& name, std::string_view text) {
  Require(!e.file.empty() && !e.message.empty());
  // A line within the text (archives aside: their files do not exist here).
  std::size_t lines = 1;
  for (char c : text) lines += c == '\n';
  Require(e.line >= 0 && (e.file != name || static_cast<std::size_t>(e.line) <= lines + 1));
}

}  // namespace patchscan::fuzz
