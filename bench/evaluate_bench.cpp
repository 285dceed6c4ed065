// Surface evaluation with first and second derivatives, object and screen space, for
// every basis and quadric: the cost every tracker step pays.
#include <benchmark/benchmark.h>

#include "patch/screen.h"

namespace patchscan {
namespace {

std::vector<std::pair<std::string, Surface>> Kinds() {
  std::array<Vec3, 16> cv;
  for (int j = 0; j < 4; ++j)
    for (int i = 0; i < 4; ++i) cv[4 * j + i] = Vec3(i, j, (i * j) % 3);
  std::vector<std::pair<std::string, Surface>> k;
  for (const Basis* b : {&BezierBasis(), &BSplineBasis(), &CatmullRomBasis(), &HermiteBasis(),
                         &PowerBasis()})
    k.emplace_back(std::string(b->name), Surface{BicubicPatch(cv, *b, *b)});
  k.emplace_back("bilinear", Surface{BilinearPatch({cv[0], cv[3], cv[12], cv[15]})});
  k.emplace_back("sphere", Surface{Sphere(1, -1, 1, 360)});
  k.emplace_back("cylinder", Surface{Cylinder(1, -1, 1, 360)});
  k.emplace_back("cone", Surface{Cone(1, 1, 360)});
  k.emplace_back("paraboloid", Surface{Paraboloid(1, 0, 1, 360)});
  k.emplace_back("hyperboloid", Surface{Hyperboloid(Vec3(1, 0, -1), Vec3(0, 1, 1), 360)});
  k.emplace_back("disk", Surface{Disk(0, 1, 360)});
  k.emplace_back("torus", Surface{Torus(1, 0.3, 0, 360, 360)});
  k.emplace_back("saddle", Surface{Saddle(1)});
  k.emplace_back("monkey-saddle", Surface{MonkeySaddle(1)});
  return k;
}

void BM_EvaluateScreen(benchmark::State& state, Surface surface, DerivOrder order) {
  Camera cam;
  cam.eye = Vec3(2, -9, 4);
  const ScreenMap map(cam, surface.worldFromObject);
  VisitShape(surface, [&](const auto& shape) {
    double u = 0.1, v = 0.2;
    for (auto _ : state) {
      ScreenDerivs d;
      EvaluateScreen(shape, map, u, v, order, &d);
      benchmark::DoNotOptimize(d);
      u = u < 0.9 ? u + 0.013 : 0.1;
      v = v < 0.9 ? v + 0.007 : 0.1;
    }
  });
}

const bool kRegistered = [] {
  for (auto& [name, s] : Kinds()) {
    benchmark::RegisterBenchmark(("EvaluateScreen/position/" + name).c_str(), BM_EvaluateScreen, s,
                                 DerivOrder::Position);
    benchmark::RegisterBenchmark(("EvaluateScreen/second/" + name).c_str(), BM_EvaluateScreen, s,
                                 DerivOrder::Second);
  }
  return true;
}();

}  // namespace
}  // namespace patchscan
