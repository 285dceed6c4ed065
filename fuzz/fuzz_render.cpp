// libFuzzer target: a RIB scene that reads is rendered at 16x12 in every mode (exact, θ
// per row and in slabs, tessellated), framed from its bounds; every render finishes and
// every channel of every pixel is finite (depth +inf where nothing is seen). Scenes of
// more than kMaxSurfaces surfaces (or polygon requests) are cut to their first ones, to
// keep each run short.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string_view>
#include <variant>
#include <vector>

#include "fuzz_checks.h"
#include "scene/rib/reader.h"
#include "raster/scanline_renderer.h"
#include "xscan/exact_scan.h"
#include "xscan/polygon_feed.h"
#include "render/load.h"
#include "xscan/tess_feed.h"

namespace {

using namespace patchscan;

constexpr std::size_t kMaxSurfaces = 16;

class CheckRows final : public raster::RowSink {
 public:
  explicit CheckRows(int width) : width_(width) {}
  bool WriteRow(int, const float* px) override {
    for (int x = 0; x < width_; ++x)
      for (int c = 0; c < raster::kChannels; ++c) {
        const float v = px[x * raster::kChannels + c];
        fuzz::Require(std::isfinite(v) || (c == raster::kChannelZ && v == INFINITY));
      }
    return true;
  }

 private:
  int width_;
};


}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  auto read = ParseRib(text, "/nonexistent-fuzz-dir/fuzz.rib");
  auto* scene = std::get_if<Scene>(&read);
  if (!scene || scene->Ids() == 0) return 0;
  if (scene->surfaces.size() > kMaxSurfaces)
    scene->surfaces.erase(scene->surfaces.begin() + static_cast<std::ptrdiff_t>(kMaxSurfaces), scene->surfaces.end());
  if (scene->polygons.size() > kMaxSurfaces)
    scene->polygons.erase(scene->polygons.begin() + static_cast<std::ptrdiff_t>(kMaxSurfaces), scene->polygons.end());
  const Bounds3 box = scene->WorldBounds();
  if (!box.lo.allFinite() || !box.hi.allFinite()) return 0;
  Camera camera;
  camera.width = 16;
  camera.height = 12;
  camera = FrameBounds(box, camera, DefaultViewDirection(Vec3(0, 0, 1)));
  if (ValidateCamera(camera)) return 0;
  scene->FaceCamera(camera);
  const raster::RenderSettings settings = render::SettingsFor(camera, 2);
  const raster::TriangleMesh polygons = render::PolygonTriangles(*scene, camera);
  for (const auto& [theta, slabs] : {std::pair{0, 0}, {16, 0}, {16, 2}}) {
    ExactScanOptions o;
    o.thetaSteps = theta;
    o.slabRows = slabs;
    ExactScan scan(scene->surfaces, camera, o);
    PolygonFeed fed(scan, polygons);
    CheckRows rows(camera.width);
    fuzz::Require(raster::RenderFragments(fed, settings, rows).has_value());
  }
  auto mesh = TessellateScene(scene->surfaces, camera, TessSettings{}, 1, [] { return false; });
  fuzz::Require(mesh.has_value());
  CheckRows rows(camera.width);
  raster::TriangleMesh triangles = ToRasterMesh(*mesh, camera);
  render::AppendScenePolygons(*scene, camera, &triangles);
  fuzz::Require(raster::RenderMesh(triangles, settings, rows).has_value());
  return 0;
}
