// CAD models (scene/cad_reader.h) through a module loaded on first use. Open CASCADE and the
// libraries it brings (some 60: its toolkits, FreeImage, X11, fonts) took 0.1 s to load and
// relocate at every start of the program, a quarter of a 2048x1536 teapot's render on two
// threads, whether or not the scene was a CAD model; so the reader and Open CASCADE live in
// patchscan-cad.so, which a run loads the first time it reads a CAD file. The module links
// its own copy of the patch layer and hands back a Scene: it and the program must be built
// from the same headers, which the interface string (a hash of them) checks.
#pragma once

#include <string>
#include <variant>

#include "scene/scene.h"

namespace patchscan {

// Whether `extension` (with its dot, any case) names a CAD file ReadCadModel reads: .step,
// .stp, .iges, .igs, .brep.
bool IsCadExtension(const std::string& extension);

// The module's interface.
class CadLibrary {
 public:
  virtual ~CadLibrary() = default;
  // ReadCad (scene/cad_reader.h).
  virtual std::variant<Scene, SourceError> Read(const std::string& path, bool asNurbs) const = 0;
};

// The CAD file `path` read through the module (loaded on the first call, from any thread;
// once); an error naming the file when the module cannot be loaded.
std::variant<Scene, SourceError> ReadCadModel(const std::string& path, bool asNurbs);

// Whether the module has been loaded in this process (a run that read no CAD file never
// loads it).
bool CadLoaded();

}  // namespace patchscan

// The module's one entry point: the library when `interface` is the one the module was
// built with, else null.
extern "C" const patchscan::CadLibrary* patchscan_cad_library(const char* interface);
