// An error in a user's input file, located by file and line.
#pragma once

#include <string>

namespace patchscan {

struct SourceError {
  std::string file;
  int line = 0;  // 1-based; 0 when the error is about the whole file (it cannot be read)
  std::string message;

  // "file:line: message", or "file: message" without a line.
  std::string What() const {
    return line > 0 ? file + ":" + std::to_string(line) + ": " + message : file + ": " + message;
  }
};

}  // namespace patchscan
