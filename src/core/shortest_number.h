// Numbers in messages: the fewest digits that read back as the same double.
#pragma once

#include <charconv>
#include <string>

namespace patchscan {

// x in the fewest digits that read back as x ("0.1", "-1", "1e+300").
inline std::string ShortestNumber(double x) {
  char buffer[32];
  const auto end = std::to_chars(buffer, buffer + sizeof buffer, x).ptr;
  return std::string(buffer, end);
}

}  // namespace patchscan
