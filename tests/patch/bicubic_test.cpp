// Bicubic and bilinear patches: derivatives, the Bézier control hull, collapsed edges.
#include <gtest/gtest.h>

#include "patch/bicubic.h"
#include "scene/bpt_reader.h"
#include "test_util.h"

namespace patchscan {
namespace {

BptFile Teapot() {
  auto r = ReadBpt(PATCHSCAN_SURFACES_DIR "/teapot.bpt");
  EXPECT_TRUE(std::holds_alternative<BptFile>(r));
  return std::get<BptFile>(r);
}

TEST(Bicubic, TeapotDerivativesMatchDifferences) {
  const BptFile teapot = Teapot();
  for (size_t k = 0; k < teapot.patches.size(); ++k) {
    const BicubicPatch patch(teapot.patches[k].cv);
    for (auto [u, v] : test::SampleParams(25, test::kSeed + static_cast<unsigned>(k)))
      test::ExpectDerivativesMatchDifferences(
          [&](double a, double b, DerivOrder o, SurfaceDerivs* d) { patch.Evaluate(a, b, o, d); },
          u, v, "teapot patch " + std::to_string(k + 1));
  }
}

TEST(Bicubic, BezierInputKeepsItsControlPointsExactly) {
  for (const BptPatch& p : Teapot().patches) {
    const BicubicPatch patch(p.cv);
    for (int k = 0; k < 16; ++k) EXPECT_EQ(patch.BezierPoints()[k], p.cv[k]);
  }
}

TEST(Bicubic, ControlHullContainsThePatch) {
  // Points are convex combinations of the Bézier points; the box allows rounding only.
  constexpr double kHullTol = 1e-12;
  for (const BptPatch& p : Teapot().patches) {
    const BicubicPatch patch(p.cv);
    Bounds3 box;
    for (const Vec3& q : patch.Hull()) box.Extend(q);
    for (auto [u, v] : test::SampleParams(100)) {
      SurfaceDerivs d;
      patch.Evaluate(u, v, DerivOrder::Position, &d);
      EXPECT_TRUE((d.p.array() >= box.lo.array() - kHullTol).all() &&
                  (d.p.array() <= box.hi.array() + kHullTol).all())
          << test::Where(u, v);
    }
  }
}

TEST(Bicubic, CollapsedEdges) {
  // The teapot's lid apex and bottom centre: 8 collapsed edges in all (data/README.md).
  int total = 0;
  for (const BptPatch& p : Teapot().patches) total += std::popcount(CollapsedEdges(BicubicPatch(p.cv)));
  EXPECT_EQ(total, 8);

  // A patch with its v=0 row collapsed, and nothing else.
  std::array<Vec3, 16> cv;
  for (int j = 0; j < 4; ++j)
    for (int i = 0; i < 4; ++i) cv[4 * j + i] = j == 0 ? Vec3(1, 2, 3) : Vec3(i, j, i * j);
  EXPECT_EQ(CollapsedEdges(BicubicPatch(cv)), 1u << static_cast<int>(PatchEdge::V0));
  // All 16 points equal: every edge collapsed.
  cv.fill(Vec3(4, 5, 6));
  EXPECT_EQ(CollapsedEdges(BicubicPatch(cv)), 0xFu);
}

TEST(Bilinear, CornersAndDerivatives) {
  const std::array<Vec3, 4> c = {Vec3(0, 0, 0), Vec3(2, 0, 1), Vec3(0, 3, -1), Vec3(2, 3, 4)};
  const BilinearPatch patch(c);
  SurfaceDerivs d;
  const std::tuple<double, double, int> corners[] = {{0, 0, 0}, {1, 0, 1}, {0, 1, 2}, {1, 1, 3}};
  for (const auto& [u, v, k] : corners) {
    patch.Evaluate(u, v, DerivOrder::Position, &d);
    EXPECT_LE((d.p - c[k]).norm(), 1e-15) << test::Where(u, v);
  }
  for (auto [u, v] : test::SampleParams(50))
    test::ExpectDerivativesMatchDifferences(
        [&](double a, double b, DerivOrder o, SurfaceDerivs* q) { patch.Evaluate(a, b, o, q); }, u,
        v, "bilinear");
}

}  // namespace
}  // namespace patchscan
