#include "xscan/tess_feed.h"

#include <Eigen/Geometry>

namespace patchscan {

raster::TriangleMesh ToRasterMesh(const TessMesh& mesh, const Camera& camera) {
  const Mat4 screenFromWorld = ScreenFromWorld(camera);
  const Vec4 depthRow = ViewDepthRow(camera);
  raster::TriangleMesh r;
  r.vertices.reserve(mesh.vertices.size());
  for (const TessVertex& v : mesh.vertices) {
    const Vec4 h = screenFromWorld * v.position.homogeneous();
    r.vertices.push_back({Vec3(h.x(), h.y(), h.w()), v.position, v.normal, v.uv, depthRow.dot(v.position.homogeneous())});
  }
  r.triangles.reserve(mesh.triangles.size());
  for (size_t k = 0; k < mesh.triangles.size(); ++k)
    r.triangles.push_back({{mesh.triangles[k][0], mesh.triangles[k][1], mesh.triangles[k][2]},
                           mesh.surfaceOf[k]});
  return r;
}

}  // namespace patchscan
