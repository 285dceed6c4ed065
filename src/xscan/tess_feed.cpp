#include "xscan/tess_feed.h"

#include <Eigen/Geometry>
#include <oneapi/tbb/info.h>

#include <atomic>
#include <exception>
#include <mutex>
#include <thread>

namespace patchscan {

raster::TriangleMesh ToRasterMesh(const TessMesh& mesh, const Camera& camera) {
  const Mat4 screenFromWorld = ScreenFromWorld(camera);
  const Vec4 depthRow = ViewDepthRow(camera);
  raster::TriangleMesh r;
  r.vertices.reserve(mesh.vertices.size());
  for (const TessVertex& v : mesh.vertices) {
    const Vec4 h = screenFromWorld * v.position.homogeneous();
    r.vertices.push_back({Vec3(h.x(), h.y(), h.w()), v.position, v.normal, v.st, depthRow.dot(v.position.homogeneous())});
  }
  r.triangles.reserve(mesh.triangles.size());
  for (size_t k = 0; k < mesh.triangles.size(); ++k)
    r.triangles.push_back({{mesh.triangles[k][0], mesh.triangles[k][1], mesh.triangles[k][2]},
                           mesh.surfaceOf[k]});
  return r;
}

std::optional<TessMesh> TessellateScene(std::span<const Surface> surfaces, const Camera& camera,
                                        const TessSettings& settings, int threads,
                                        const std::function<bool()>& stop) {
  std::vector<TessMesh> parts(surfaces.size());
  std::atomic<bool> stopped = false;
  auto one = [&](std::size_t k) {
    if (stopped || (stop && stop())) {
      stopped = true;
      return;
    }
    const auto id = static_cast<std::uint32_t>(k);
    if (settings.pixels > 0)
      TessellateToScreen(surfaces[k], camera, settings.pixels, id, &parts[k]);
    else if (settings.rate > 0)
      TessellateUniform(surfaces[k], settings.rate, id, &parts[k]);
    else
      TessellateToChordError(surfaces[k], camera, settings.chordPx, id, &parts[k]);
  };
  // Plain threads, joined before the back end starts: a pool's workers would go on
  // spinning for a while and take cycles from the back end's thread.
  threads = std::min(threads, tbb::info::default_concurrency());
  std::atomic<std::size_t> next = 0;
  std::mutex failure;
  std::exception_ptr error;  // the first thread's exception, rethrown once all are joined
  auto drain = [&] {
    try {
      for (std::size_t k; (k = next++) < surfaces.size();) one(k);
    } catch (...) {
      stopped = true;
      std::lock_guard lock(failure);
      if (!error) error = std::current_exception();
    }
  };
  std::vector<std::thread> pool;
  for (int t = 1; t < threads; ++t) pool.emplace_back(drain);
  drain();
  for (std::thread& t : pool) t.join();
  if (error) std::rethrow_exception(error);
  if (stopped) return std::nullopt;
  // Appended in surface order, each part's vertex indices moved past those before it.
  TessMesh mesh;
  for (TessMesh& part : parts) {
    const auto base = static_cast<std::uint32_t>(mesh.vertices.size());
    mesh.vertices.insert(mesh.vertices.end(), part.vertices.begin(), part.vertices.end());
    for (auto t : part.triangles) mesh.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
    mesh.surfaceOf.insert(mesh.surfaceOf.end(), part.surfaceOf.begin(), part.surfaceOf.end());
    part = TessMesh();
  }
  return mesh;
}

}  // namespace patchscan
