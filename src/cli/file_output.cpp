#include "cli/file_output.h"

#include <unistd.h>

#include <filesystem>
#include <fstream>

namespace patchscan::cli {

std::optional<std::string> WriteFileWhole(const std::string& path, std::string_view contents) {
  const std::filesystem::path target(path);
  const std::filesystem::path temp =
      target.parent_path() / ("." + target.filename().string() + ".tmp" + std::to_string(getpid()));
  std::error_code ec;
  {
    std::ofstream f(temp, std::ios::binary);
    f.write(contents.data(), static_cast<std::streamsize>(contents.size()));
    f.close();
    if (!f) {
      std::filesystem::remove(temp, ec);
      return path + ": cannot write";
    }
  }
  std::filesystem::rename(temp, target, ec);
  if (ec) {
    std::filesystem::remove(temp, ec);
    return path + ": cannot rename the finished file into place";
  }
  return std::nullopt;
}

}  // namespace patchscan::cli
