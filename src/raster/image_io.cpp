#include "raster/image_io.h"

#include <dlfcn.h>
#include <unistd.h>

#include <atomic>
#include <filesystem>
#include <mutex>

namespace patchscan::raster::imageio {
namespace {

std::atomic<bool> loaded = false;

// The places the module may be, in order (image_io.h).
std::vector<std::filesystem::path> Candidates() {
  std::vector<std::filesystem::path> places;
  std::error_code ec;
  const std::filesystem::path self = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (!ec) places.push_back(self.parent_path() / PATCHSCAN_IMAGEIO_FROM_BINDIR / PATCHSCAN_IMAGEIO_NAME);
  places.push_back(std::filesystem::path(PATCHSCAN_IMAGEIO_INSTALLED) / PATCHSCAN_IMAGEIO_NAME);
  places.push_back(std::filesystem::path(PATCHSCAN_IMAGEIO_BUILT) / PATCHSCAN_IMAGEIO_NAME);
  return places;
}

std::variant<const Library*, std::string> Load() {
  std::string tried;
  for (const std::filesystem::path& place : Candidates()) {
    std::error_code ec;
    if (!std::filesystem::exists(place, ec)) continue;
    // Never closed: the library's objects live until the process ends.
    void* handle = ::dlopen(place.c_str(), RTLD_NOW | RTLD_LOCAL);
    if (!handle) {
      const char* why = ::dlerror();
      tried += std::string("\n  ") + (why ? why : place.string());
      continue;
    }
    using Entry = const Library* (*)(const char*);
    auto entry = reinterpret_cast<Entry>(::dlsym(handle, "patchscan_imageio_library"));
    const Library* library = entry ? entry(PATCHSCAN_IMAGEIO_INTERFACE) : nullptr;
    if (library) return library;
    tried += "\n  " + place.string() + ": built from another version of patchscan";
  }
  return "cannot load OpenImageIO's module " PATCHSCAN_IMAGEIO_NAME
         " (needed to read images and write formats other than PNG)" +
         (tried.empty() ? std::string(": not installed beside patchscan") : ":" + tried);
}

}  // namespace

std::variant<const Library*, std::string> Get() {
  static const std::variant<const Library*, std::string> library = [] {
    auto result = Load();
    loaded = std::holds_alternative<const Library*>(result);
    return result;
  }();
  return library;
}

bool Loaded() { return loaded; }

}  // namespace patchscan::raster::imageio
