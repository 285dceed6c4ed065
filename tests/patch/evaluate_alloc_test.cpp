// Evaluation in object and screen space allocates nothing (STYLE.md, "Hot loops"): this
// binary counts every call of the global operator new.
#include <gtest/gtest.h>

#include "alloc_counter.h"
#include "patch/all_surfaces.h"
#include "patch/screen.h"

namespace patchscan {
namespace {

TEST(Evaluate, AllocatesNothing) {
  const auto surfaces = test::AllSurfaceKinds();
  Camera cam;
  cam.eye = Vec3(1, -8, 3);
  double sink = 0.0;
  for (const auto& [name, surface] : surfaces) {
    const ScreenMap map(cam, surface.worldFromObject);
    const long before = test::gAllocations.load();
    VisitShape(surface, [&](const auto& shape) {
      for (int i = 0; i < 1000; ++i) {
        ScreenDerivs d;
        EvaluateScreen(shape, map, (i % 37) / 37.0, (i % 41) / 41.0, DerivOrder::Second, &d);
        sink += d.p.x() + SilhouetteJ(d);
      }
    });
    EXPECT_EQ(test::gAllocations.load() - before, 0) << name;
  }
  EXPECT_TRUE(std::isfinite(sink));
}

}  // namespace
}  // namespace patchscan
