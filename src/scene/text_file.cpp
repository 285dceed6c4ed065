#include "scene/text_file.h"

#include <algorithm>
#include <cerrno>
#include <climits>
#include <cstdint>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <cstdio>
#include <cstring>
#include <filesystem>

#include <zlib.h>

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
  if (text.size() >= 2 && static_cast<unsigned char>(text[0]) == 0x1f && static_cast<unsigned char>(text[1]) == 0x8b)
    return Gunzip(text, path);
  return text;
}

std::variant<std::string, SourceError> Gunzip(std::string_view data, const std::string& path) {
  z_stream z{};
  // 15 + 16: a gzip stream, the largest window.
  if (inflateInit2(&z, 15 + 16) != Z_OK) return SourceError{path, 0, "cannot start gzip decompression"};
  z.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(data.data()));
  z.avail_in = static_cast<uInt>(std::min<std::size_t>(data.size(), UINT32_MAX));
  std::string text;
  char buf[1 << 16];
  int status = Z_OK;
  std::string error;
  while (status != Z_STREAM_END) {
    z.next_out = reinterpret_cast<Bytef*>(buf);
    z.avail_out = sizeof buf;
    status = inflate(&z, Z_NO_FLUSH);
    if (status != Z_OK && status != Z_STREAM_END) {
      error = status == Z_BUF_ERROR ? "the gzip data ends early" : std::string("gzip data is corrupt") + (z.msg ? std::string(": ") + z.msg : "");
      break;
    }
    text.append(buf, sizeof buf - z.avail_out);
    if (static_cast<long long>(text.size()) > kMaxSceneFileBytes) {
      error = "decompresses to more than 1 GiB, too large for a scene file";
      break;
    }
  }
  inflateEnd(&z);
  if (!error.empty()) return SourceError{path, 0, error};
  return text;
}

std::string Shown(std::string_view t) {
  constexpr size_t kMaxShown = 24;
  std::string s = "'";
  for (size_t i = 0; i < t.size() && i < kMaxShown; ++i) {
    const unsigned char c = static_cast<unsigned char>(t[i]);
    s += (c >= 0x20 && c < 0x7f) ? static_cast<char>(c) : '?';
  }
  if (t.size() > kMaxShown) s += "...";
  return s + "'";
}

std::optional<Number> ParseNumber(std::string_view t) {
  if (!t.empty() && t.front() == '+') t.remove_prefix(1);
  double value = 0.0;
  const auto [end, ec] = std::from_chars(t.data(), t.data() + t.size(), value);
  if (end != t.data() + t.size() || t.empty()) return std::nullopt;
  if (ec == std::errc::result_out_of_range) {
    // Overflow is not finite; underflow reads as the nearest representable (0 or subnormal).
    const std::string copy(t);
    value = std::strtod(copy.c_str(), nullptr);
    return Number{std::isfinite(value), value};
  }
  if (ec != std::errc()) return std::nullopt;
  return Number{std::isfinite(value), value};
}

}  // namespace patchscan
