#include "scene/cad_library.h"

#include <atomic>

#include "core/ascii.h"
#include "core/module.h"
#include "scene/occt_leaks.h"

namespace patchscan {

bool IsCadExtension(const std::string& extension) {
  const std::string e = AsciiLower(extension);
  return e == ".step" || e == ".stp" || e == ".iges" || e == ".igs" || e == ".brep";
}

namespace {
std::atomic<bool> loaded = false;
}  // namespace

bool CadLoaded() { return loaded; }

std::variant<Scene, SourceError> ReadCadModel(const std::string& path, bool asNurbs) {
  static const std::variant<const CadLibrary*, std::string> library = [] {
    static constexpr ModulePlaces kPlaces{PATCHSCAN_CAD_NAME, PATCHSCAN_CAD_FROM_BINDIR, PATCHSCAN_CAD_INSTALLED,
                                          PATCHSCAN_CAD_BUILT};
    auto result = LoadModule<CadLibrary>(kPlaces, "patchscan_cad_library", PATCHSCAN_CAD_INTERFACE);
    loaded = std::holds_alternative<const CadLibrary*>(result);
    return result;
  }();
  if (const auto* tried = std::get_if<std::string>(&library))
    return SourceError{path, 0,
                       "cannot load the CAD module " PATCHSCAN_CAD_NAME " (Open CASCADE's reader)" +
                           (tried->empty() ? std::string(": not installed beside patchscan") : ":" + *tried)};
  return std::get<const CadLibrary*>(library)->Read(path, asNurbs);
}

}  // namespace patchscan
