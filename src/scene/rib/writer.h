// Writing scenes as RenderMan Interface Bytestream (.rib) that patchscan's RIB reader
// renders to the same image: the camera as Format, PixelSamples, Projection, Clipping and
// an explicit world-to-camera Transform, the scene's lights, then each surface with its
// appearance (Color, Opacity, Sides, ReverseOrientation, Surface) as a Patch, a quadric or
// a SubdivisionMesh.
#pragma once

#include <string>
#include <variant>

#include "patch/camera.h"
#include "scene/scene.h"

namespace patchscan {

struct RibWriteError {
  std::string message;
};

struct RibWriteOptions {
  int pixelSamples = 3;      // the side of the supersampling grid
  std::string displayName;   // Display's file name; empty: no Display
};

// The RIB text of `scene` seen by `camera` (a valid camera), or why it cannot be written
// (a surface kind with no RIB form here: the test saddles). Bicubic patches are written
// in Bézier form, bilinear patches as they are, quadrics by their own requests, a
// subdivision cage once, as the SubdivisionMesh it was read as (an .obj cage too);
// numbers with 17 significant digits, so they read back exactly.
std::variant<std::string, RibWriteError> WriteRib(const Scene& scene, const Camera& camera,
                                                const RibWriteOptions& options);

}  // namespace patchscan
