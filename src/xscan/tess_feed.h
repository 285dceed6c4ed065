// Feeds tessellated surfaces to the back end: world-space triangles to homogeneous
// screen space for one camera.
#pragma once

#include "patch/camera.h"
#include "patch/tessellate.h"
#include "raster/mesh.h"

namespace patchscan {

raster::TriangleMesh ToRasterMesh(const TessMesh& mesh, const Camera& camera);

}  // namespace patchscan
