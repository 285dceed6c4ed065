#include "patch/text_file.h"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>

namespace patchscan {

std::variant<std::string, SourceError> ReadTextFile(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) return SourceError{path, 0, "is a directory"};
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) return SourceError{path, 0, std::string("cannot open: ") + std::strerror(errno)};
  std::string text;
  char buf[1 << 16];
  size_t n;
  while ((n = std::fread(buf, 1, sizeof buf, f)) > 0) {
    if (static_cast<long long>(text.size() + n) > kMaxSceneFileBytes) {
      std::fclose(f);
      return SourceError{path, 0, "is larger than 1 GiB, too large for a scene file"};
    }
    text.append(buf, n);
  }
  const bool failed = std::ferror(f) != 0;
  std::fclose(f);
  if (failed) return SourceError{path, 0, "read error"};
  return text;
}

}  // namespace patchscan
