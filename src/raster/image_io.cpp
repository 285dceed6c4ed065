#include "raster/image_io.h"

#include <atomic>

#include "core/module.h"

namespace patchscan::raster::imageio {
namespace {

std::atomic<bool> loaded = false;

std::variant<const Library*, std::string> Load() {
  static constexpr ModulePlaces kPlaces{PATCHSCAN_IMAGEIO_NAME, PATCHSCAN_IMAGEIO_FROM_BINDIR,
                                        PATCHSCAN_IMAGEIO_INSTALLED, PATCHSCAN_IMAGEIO_BUILT};
  auto module = LoadModule<Library>(kPlaces, "patchscan_imageio_library", PATCHSCAN_IMAGEIO_INTERFACE);
  if (const auto* library = std::get_if<const Library*>(&module)) return *library;
  const std::string& tried = std::get<std::string>(module);
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
