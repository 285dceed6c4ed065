// Micro-benchmarks of the pipeline's steps on the teapot at 1024×768: one tracker step
// (edge and silhouette trackers advanced one scan line, per tracker), one triangle set-up,
// and one scan line of visibility (the back end over the tessellated teapot, per pixel row).
#include <benchmark/benchmark.h>

#include <iostream>
#include <random>
#include <sstream>

#include "render/load.h"
#include "patch/tessellate.h"
#include "raster/scanline_renderer.h"
#include "raster/triangle_setup.h"
#include "tracker/edge_scan.h"
#include "tracker/maxima.h"
#include "tracker/silhouette_scan.h"
#include "xscan/tess_feed.h"

namespace patchscan {
namespace {

const render::LoadedScene& Teapot() {
  static const render::LoadedScene loaded = [] {
    render::CameraOptions opts;
    opts.size = "1024x768";
    std::ostringstream err;
    auto r = render::LoadSceneAndCamera(PATCHSCAN_SURFACES_DIR "/teapot.bpt", opts, err);
    if (const auto* failed = std::get_if<render::Failure>(&r)) {
      std::cerr << err.str() << failed->message << '\n';
      std::abort();
    }
    return std::get<render::LoadedScene>(std::move(r));
  }();
  return loaded;
}

// Every edge and silhouette tracker of the teapot advanced over every scan line; the
// counter is per tracker step (one tracker moved to the next scan line). Set-up (the
// maxima pre-pass) is outside the timing.
void BM_TrackerStep(benchmark::State& state) {
  const auto& t = Teapot();
  const bool extrapolate = state.range(0) != 0;
  long steps = 0, iterations = 0, bisections = 0, searches = 0;
  for (auto _ : state) {
    state.PauseTiming();
    std::vector<std::unique_ptr<EdgeScan>> edges;
    std::vector<std::unique_ptr<SilhouetteScan>> silhouettes;
    std::vector<ScreenMap> maps;
    Counters counters;
    maps.reserve(t.scene.surfaces.size());  // the scans keep references to their maps
    for (const Surface& s : t.scene.surfaces) {
      maps.emplace_back(t.view.camera, s.worldFromObject);
      edges.push_back(std::make_unique<EdgeScan>(s, maps.back(), counters, extrapolate));
      silhouettes.push_back(std::make_unique<SilhouetteScan>(s, maps.back(), FindStationaryPoints(s, maps.back()), counters));
    }
    state.ResumeTiming();
    for (int y = 0; y < t.view.camera.height; ++y) {
      const double yScan = y + 0.5;
      for (std::size_t k = 0; k < edges.size(); ++k) {
        edges[k]->Advance(yScan);
        silhouettes[k]->Advance(yScan, *edges[k]);
        steps += static_cast<long>(edges[k]->Trackers().size() + silhouettes[k]->Trackers().size());
      }
    }
    iterations += counters[Counter::EdgeNewtonIterations] + counters[Counter::SilhouetteNewtonIterations];
    bisections += counters[Counter::EdgeRepairs];
    searches += counters[Counter::RepairSearches];
  }
  state.SetItemsProcessed(steps);
  const double runs = static_cast<double>(state.iterations());
  state.counters["iterations_per_step"] = static_cast<double>(iterations) / static_cast<double>(steps);
  state.counters["edge_bisections"] = static_cast<double>(bisections) / runs;
  state.counters["repair_searches"] = static_cast<double>(searches) / runs;
}
BENCHMARK(BM_TrackerStep)->Arg(1)->Arg(0)->ArgName("extrapolate")->Unit(benchmark::kMillisecond);

// Triangle set-up (Olano–Greer): random small triangles in homogeneous screen space.
void BM_TriangleSetup(benchmark::State& state) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> pos(0, 1000), w(1, 3), d(-8, 8);
  std::vector<std::array<Vec3, 3>> tris(1024);
  for (auto& tri : tris) {
    const double x = pos(rng), y = pos(rng);
    for (auto& h : tri) {
      const double wi = w(rng);
      h = Vec3((x + d(rng)) * wi, (y + d(rng)) * wi, wi);
    }
  }
  std::size_t i = 0;
  for (auto _ : state) {
    const auto& tri = tris[i++ & 1023];
    benchmark::DoNotOptimize(raster::SetupTriangle(tri[0], tri[1], tri[2], false, 1024, 1024));
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_TriangleSetup);

class NullSink final : public raster::RowSink {
 public:
  bool WriteRow(int, const float*) override { return true; }
};

// The back end over the teapot tessellated at rate 8 (4096 triangles): per pixel row, with
// set-up, visibility, shading and the row's AOVs, at aa 1 and 4.
void BM_ScanLineVisibility(benchmark::State& state) {
  const auto& t = Teapot();
  TessMesh tess;
  for (std::size_t k = 0; k < t.scene.surfaces.size(); ++k)
    TessellateUniform(t.scene.surfaces[k], 8, static_cast<std::uint32_t>(k), &tess);
  const raster::TriangleMesh mesh = ToRasterMesh(tess, t.view.camera);
  raster::RenderSettings s;
  s.width = t.view.camera.width;
  s.height = t.view.camera.height;
  s.aa = static_cast<int>(state.range(0));
  s.hither = t.view.camera.hither;
  s.eye = t.view.camera.eye;
  NullSink sink;
  for (auto _ : state) benchmark::DoNotOptimize(raster::RenderMesh(mesh, s, sink));
  state.SetItemsProcessed(state.iterations() * s.height);
}
BENCHMARK(BM_ScanLineVisibility)->Arg(1)->Arg(4)->ArgName("aa")->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace patchscan
