// Evaluation in object and screen space allocates nothing (STYLE.md, "Hot loops"): this
// binary counts every call of the global operator new.
#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <new>

#include "patch/all_surfaces.h"
#include "patch/screen.h"

namespace {
std::atomic<long> gAllocations{0};
}

void* operator new(std::size_t n) {
  ++gAllocations;
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }

namespace patchscan {
namespace {

TEST(Evaluate, AllocatesNothing) {
  const auto surfaces = test::AllSurfaceKinds();
  Camera cam;
  cam.eye = Vec3(1, -8, 3);
  double sink = 0.0;
  for (const auto& [name, surface] : surfaces) {
    const ScreenMap map(cam, surface.worldFromObject);
    const long before = gAllocations.load();
    VisitShape(surface, [&](const auto& shape) {
      for (int i = 0; i < 1000; ++i) {
        ScreenDerivs d;
        EvaluateScreen(shape, map, (i % 37) / 37.0, (i % 41) / 41.0, DerivOrder::Second, &d);
        sink += d.p.x() + SilhouetteJ(d);
      }
    });
    EXPECT_EQ(gAllocations.load() - before, 0) << name;
  }
  EXPECT_TRUE(std::isfinite(sink));
}

}  // namespace
}  // namespace patchscan
