// Letters of file names and keywords: ASCII only, whatever the locale.
#pragma once

#include <string>

namespace patchscan {

// s with A-Z made a-z, every other byte as it is (a file's extension ".STEP" reads ".step").
inline std::string AsciiLower(std::string s) {
  for (char& c : s)
    if (c >= 'A' && c <= 'Z') c = static_cast<char>(c - 'A' + 'a');
  return s;
}

}  // namespace patchscan
