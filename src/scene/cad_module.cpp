// patchscan-cad.so's entry point (scene/cad_library.h): the CAD reader behind the interface.
#include <cstring>

#include "scene/cad_library.h"
#include "scene/cad_reader.h"

namespace patchscan {
namespace {

class Reader final : public CadLibrary {
 public:
  std::variant<Scene, SourceError> Read(const std::string& path, bool asNurbs) const override {
    return ReadCad(path, asNurbs);
  }
};

}  // namespace
}  // namespace patchscan

extern "C" __attribute__((visibility("default"))) const patchscan::CadLibrary* patchscan_cad_library(
    const char* interface) {
  static const patchscan::Reader reader;
  return std::strcmp(interface, PATCHSCAN_CAD_INTERFACE) == 0 ? &reader : nullptr;
}
