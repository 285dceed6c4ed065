// What the back end eats: triangles whose vertices carry homogeneous screen position,
// world position and normal, and uv, tagged with the surface they come from. The back
// end never sees a surface: tessellated and direct renders differ only in
// where these come from.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <vector>

#include "core/vec.h"

namespace patchscan::raster {

struct RasterVertex {
  Vec3 h;         // homogeneous screen position (X, Y, W): x = X/W, y = Y/W pixels, W = eye depth
  Vec3 position;  // world space, for lighting
  Vec3 normal;    // world space, not necessarily unit
  Vec2 uv;
  double depth = 0.0;  // orthographic renders: distance along the view axis (W is 1)
  Vec3 colour = Vec3::Ones();  // multiplies the surface's colour (a polygon's "Cs")
};

struct RasterTriangle {
  std::uint32_t v[3];
  std::uint32_t surfaceId;
};

struct TriangleMesh {
  std::vector<RasterVertex> vertices;
  std::vector<RasterTriangle> triangles;
};

}  // namespace patchscan::raster
