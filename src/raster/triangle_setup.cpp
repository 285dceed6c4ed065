#include "raster/triangle_setup.h"

#include <algorithm>
#include <cmath>

namespace patchscan::raster {

std::optional<TriangleSetup> SetupTriangle(const Vec3& h0, const Vec3& h1, const Vec3& h2,
                                           bool cullBackFaces, double width, double height) {
  // Step 1: the rows of adj(M) are the lines through pairs of vertices. A cross product
  // of the same two vectors in the opposite order is the exact negative in IEEE
  // arithmetic, which makes the tie rule consistent between neighbours.
  TriangleSetup t;
  t.edge[0] = h1.cross(h2);
  t.edge[1] = h2.cross(h0);
  t.edge[2] = h0.cross(h1);
  const double det = h0.dot(t.edge[0]);
  const double scale = h0.norm() * h1.norm() * h2.norm();
  if (!(std::abs(det) > kMinRelativeDet * scale)) return std::nullopt;
  t.frontFacing = det > 0.0;
  if (cullBackFaces && !t.frontFacing) return std::nullopt;
  // Step 2: orient every edge so that inside (b_i / w >= 0) is non-negative: the edge
  // function proper is edge[i] / det; only its sign matters for coverage.
  t.invDet = 1.0 / det;
  if (det < 0.0)
    for (Vec3& e : t.edge) e = -e;
  // Step 3: screen bounds. With every w > 0 the triangle is the usual bounded one;
  // otherwise it is external (or crosses the eye plane) and may reach any pixel.
  if (h0.z() > 0 && h1.z() > 0 && h2.z() > 0) {
    const double x[3] = {h0.x() / h0.z(), h1.x() / h1.z(), h2.x() / h2.z()};
    const double y[3] = {h0.y() / h0.z(), h1.y() / h1.z(), h2.y() / h2.z()};
    // Widened by kBoundsSlackPx: the divisions round, and a sample exactly on an edge level
    // with a row of samples (x or y equal at both ends) must still be tested by both
    // triangles that share the edge, whose edge values then give it to exactly one.
    t.xMin = std::min({x[0], x[1], x[2]}) - kBoundsSlackPx;
    t.xMax = std::max({x[0], x[1], x[2]}) + kBoundsSlackPx;
    t.yMin = std::min({y[0], y[1], y[2]}) - kBoundsSlackPx;
    t.yMax = std::max({y[0], y[1], y[2]}) + kBoundsSlackPx;
  } else {
    t.xMin = 0;
    t.xMax = width;
    t.yMin = 0;
    t.yMax = height;
  }
  return t;
}

}  // namespace patchscan::raster
