// A scene as read from a file: surfaces placed in the world, each remembering the line it
// came from. Readers are chosen by file extension.
#pragma once

#include <string>
#include <variant>
#include <vector>

#include "patch/source_error.h"
#include "patch/surface.h"

namespace patchscan {

struct Scene {
  std::string source;             // the file it was read from
  std::vector<Surface> surfaces;
  std::vector<int> sourceLines;   // per surface, the line that defines it

  // A conservative world-space box of the whole scene.
  Bounds3 WorldBounds() const;
};

// Read a scene file. Known extensions: .bpt (Bézier patch text). Errors name file:line.
std::variant<Scene, SourceError> LoadScene(const std::string& path);

}  // namespace patchscan
