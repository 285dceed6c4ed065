// The scan-line loop allocates nothing per row (STYLE.md, "Hot loops"): rendering the
// same mesh into images of different heights performs the same number of allocations.
#include <gtest/gtest.h>

#include "alloc_counter.h"
#include "raster/scanline_renderer.h"

namespace patchscan::raster {
namespace {

struct NullSink : RowSink {
  bool WriteRow(int, const float*) override { return true; }
};

long AllocationsFor(int height, int aa, double opacity) {
  // A fan of triangles filling the image, so every row has active triangles.
  TriangleMesh m;
  m.vertices.push_back({Vec3(32, height / 2.0, 1), Vec3(0, 0, 5), Vec3(0, 0, -1), Vec2(0, 0)});
  for (int k = 0; k <= 16; ++k) {
    const double a = k * 2 * 3.14159265358979 / 16;
    m.vertices.push_back({Vec3(32 + 40 * std::cos(a), height / 2.0 + height * std::sin(a), 1),
                          Vec3(std::cos(a), std::sin(a), 5), Vec3(0, 0, -1), Vec2(k / 16.0, 1)});
  }
  for (std::uint32_t k = 1; k <= 16; ++k) m.triangles.push_back({{0, k, k + 1}, k % 3});
  RenderSettings s;
  s.width = 64;
  s.height = height;
  s.aa = aa;
  s.hither = 0.01;
  s.opacity = opacity;
  s.lights = DefaultLightRig(Vec3(0, 0, 1), Vec3(0, -1, 0), Vec3(1, 0, 0));
  NullSink sink;
  const long before = test::gAllocations.load();
  EXPECT_TRUE(RenderMesh(m, s, sink));
  return test::gAllocations.load() - before;
}

TEST(RenderAllocations, IndependentOfTheNumberOfRows) {
  for (int aa : {1, 3})
    for (double opacity : {1.0, 0.5})
      EXPECT_EQ(AllocationsFor(32, aa, opacity), AllocationsFor(256, aa, opacity))
          << "aa " << aa << " opacity " << opacity;
}

}  // namespace
}  // namespace patchscan::raster
