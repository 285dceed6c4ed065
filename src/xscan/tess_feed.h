// Feeds tessellated surfaces to the back end: world-space triangles to homogeneous
// screen space for one camera.
#pragma once

#include <functional>
#include <optional>
#include <span>

#include "patch/camera.h"
#include "patch/tessellate.h"
#include "raster/mesh.h"

namespace patchscan {

raster::TriangleMesh ToRasterMesh(const TessMesh& mesh, const Camera& camera);

// How a scene is tessellated, to the screen of the camera: with edges about `pixels` long
// (pixels > 0), else uniformly at `rate` segments per patch edge (rate > 0), else with a
// chord error of at most `chordPx` pixels (the default).
struct TessSettings {
  int rate = 0;
  double pixels = 0.0;
  double chordPx = kDefaultChordErrorPx;
};

// Every surface of the scene tessellated, on up to `threads` threads, the surfaces' meshes
// appended in surface order (the same mesh for any number of threads); shared boundary
// vertices are not welded yet. nullopt if stop() said so between surfaces.
std::optional<TessMesh> TessellateScene(std::span<const Surface> surfaces, const Camera& camera,
                                        const TessSettings& settings, int threads,
                                        const std::function<bool()>& stop);

}  // namespace patchscan
