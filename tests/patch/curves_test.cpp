// Curve ribbons (patch/curves.h): exact derivatives against central differences, facing
// the eye (across the curve and across the line of sight, full width), inside their hull,
// and the RIB Curves request: segments, bases, widths, errors.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <random>

#include "patch/basis.h"
#include "patch/curves.h"
#include "scene/rib/reader.h"
#include "patch/surface.h"
#include "test_util.h"

namespace patchscan {
namespace {

// A bent cubic segment that tapers.
CurveRibbon Bent() { return CurveRibbon({Vec3(0, 0, 0), Vec3(1, 0.5, 0.3), Vec3(2, -0.4, 0.9), Vec3(3, 0.2, 0.4)}, 0.3, 0.1); }

TEST(CurveRibbon, DerivativesMatchDifferences) {
  for (int view = 0; view < 2; ++view) {
    CurveRibbon r = Bent();
    if (view == 0) r.FaceEye(Vec3(1.5, -6.0, 2.0));
    else r.FaceAxis(Vec3(0.2, 1.0, -0.3));
    for (const auto& [u, v] : test::SampleParams(64))
      test::ExpectDerivativesMatchDifferences(
          [&](double uu, double vv, DerivOrder o, SurfaceDerivs* d) { r.Evaluate(uu, vv, o, d); }, u, v,
          view == 0 ? "perspective" : "orthographic");
  }
}

TEST(CurveRibbon, FacesTheEyeAtItsFullWidth) {
  CurveRibbon r = Bent();
  const Vec3 eye(1.5, -6.0, 2.0);
  r.FaceEye(eye);
  for (const auto& [u, v] : test::SampleParams(64)) {
    SurfaceDerivs d, centre;
    r.Evaluate(u, v, DerivOrder::First, &d);
    r.Evaluate(0.5, v, DerivOrder::First, &centre);
    const Vec3 across = d.dpdu;
    // Across the curve and across the line of sight to the curve's centre line.
    EXPECT_NEAR(across.normalized().dot(centre.dpdv.normalized()), 0.0, 1e-12);
    EXPECT_NEAR(across.normalized().dot((centre.p - eye).normalized()), 0.0, 1e-12);
    // Its full width: w(v) from 0.3 to 0.1.
    EXPECT_NEAR(across.norm(), 0.3 + (0.1 - 0.3) * v, 1e-12);
  }
  // Seen end-on (the curve heading straight at the eye), still finite.
  CurveRibbon line({Vec3(0, 0, 0), Vec3(0, 0, 1), Vec3(0, 0, 2), Vec3(0, 0, 3)}, 0.2, 0.2);
  line.FaceEye(Vec3(0, 0, 10));
  SurfaceDerivs d;
  line.Evaluate(0.3, 0.5, DerivOrder::Second, &d);
  EXPECT_TRUE(d.p.allFinite() && d.dpdu.allFinite() && d.dpdv.allFinite() && d.d2pdv2.allFinite());
}

TEST(CurveRibbon, TheHullHoldsTheRibbon) {
  CurveRibbon r = Bent();
  r.FaceEye(Vec3(1.5, -6.0, 2.0));
  Bounds3 box;
  for (const Vec3& p : r.Hull()) box.Extend(p);
  for (int j = 0; j <= 20; ++j)
    for (int i = 0; i <= 4; ++i) {
      SurfaceDerivs d;
      r.Evaluate(i / 4.0, j / 20.0, DerivOrder::Position, &d);
      EXPECT_TRUE((d.p.array() >= box.lo.array()).all() && (d.p.array() <= box.hi.array()).all());
    }
}

Scene Parse(const std::string& body) {
  auto r = ParseRib("WorldBegin\n" + body + "\nWorldEnd\n", "t.rib");
  if (auto* e = std::get_if<SourceError>(&r)) ADD_FAILURE() << e->What();
  return std::get_if<Scene>(&r) ? std::get<Scene>(r) : Scene{};
}

std::string Error(const std::string& body) {
  auto r = ParseRib("WorldBegin\n" + body + "\nWorldEnd\n", "t.rib");
  if (auto* e = std::get_if<SourceError>(&r)) return e->What();
  return "(accepted)";
}

const CurveRibbon& Ribbon(const Scene& s, std::size_t k) { return std::get<CurveRibbon>(s.surfaces[k].shape); }

TEST(RibCurves, SegmentsFollowTheBasisAndTheWrap) {
  // b-spline step 1: nonperiodic 6 vertices = 3 segments (4 varying widths); periodic 6 = 6.
  const std::string six = "\"P\" [0 0 0  1 0 0  2 1 0  3 1 1  4 0 1  5 0 0]";
  Scene s = Parse("Basis \"b-spline\" 1 \"b-spline\" 1\nCurves \"cubic\" [6] \"nonperiodic\" " + six +
                  " \"width\" [0.1 0.2 0.3 0.4]");
  ASSERT_EQ(s.surfaces.size(), 3u);
  // The ribbon's centre line is the b-spline: segment 1 at t is the basis at t.
  const BasisWeights bw = EvaluateBasis(BSplineBasis(), 0.4);
  const Vec3 g[4] = {Vec3(1, 0, 0), Vec3(2, 1, 0), Vec3(3, 1, 1), Vec3(4, 0, 1)};
  const Vec3 want = bw.w[0] * g[0] + bw.w[1] * g[1] + bw.w[2] * g[2] + bw.w[3] * g[3];
  SurfaceDerivs d;
  EvaluateObject(s.surfaces[1], 0.5, 0.4, DerivOrder::Position, &d);
  EXPECT_LT((d.p - want).norm(), 1e-14);
  EXPECT_DOUBLE_EQ(Ribbon(s, 1).Width0(), 0.2);
  EXPECT_DOUBLE_EQ(Ribbon(s, 1).Width1(), 0.3);
  s = Parse("Basis \"b-spline\" 1 \"b-spline\" 1\nCurves \"cubic\" [6] \"periodic\" " + six);
  ASSERT_EQ(s.surfaces.size(), 6u);
  // Consecutive segments share their edge bit for bit (the loop's last and first too), so
  // no sample falls between them.
  Camera camera;
  camera.eye = Vec3(2, -8, 3);
  s.FaceCamera(camera);
  for (std::size_t k = 0; k < 6; ++k)
    for (const double u : {0.0, 0.3, 1.0}) {
      SurfaceDerivs end, start;
      EvaluateObject(s.surfaces[k], u, 1.0, DerivOrder::First, &end);
      EvaluateObject(s.surfaces[(k + 1) % 6], u, 0.0, DerivOrder::First, &start);
      EXPECT_EQ(end.p, start.p) << "segment " << k << " at u " << u;
      EXPECT_EQ(end.dpdu, start.dpdu) << "segment " << k << " at u " << u;
    }
  EXPECT_DOUBLE_EQ(Ribbon(s, 5).Width0(), 1.0);  // RenderMan's default width
  // Bézier (the default basis, step 3): 7 vertices = 2 segments; linear: 5 = 4, periodic 5.
  s = Parse("Curves \"cubic\" [7] \"nonperiodic\" \"P\" [0 0 0 1 0 0 2 0 0 3 0 0 4 0 0 5 0 0 6 0 0] \"constantwidth\" 0.5");
  ASSERT_EQ(s.surfaces.size(), 2u);
  EXPECT_EQ(Ribbon(s, 1).Bezier()[0], Vec3(3, 0, 0));
  EXPECT_DOUBLE_EQ(Ribbon(s, 1).Width1(), 0.5);
  s = Parse("Curves \"linear\" [5] \"nonperiodic\" \"P\" [0 0 0 1 0 0 1 1 0 0 1 0 0 2 0] \"vertex float width\" [1 2 3 4 5]");
  ASSERT_EQ(s.surfaces.size(), 4u);
  EXPECT_DOUBLE_EQ(Ribbon(s, 3).Width0(), 4.0);
  EXPECT_DOUBLE_EQ(Ribbon(s, 3).Width1(), 5.0);
  s = Parse("Curves \"linear\" [3 2] \"periodic\" \"P\" [0 0 0 1 0 0 1 1 0  5 5 5 6 6 6] \"uniform float width\" [0.5 0.25]");
  ASSERT_EQ(s.surfaces.size(), 5u);
  EXPECT_EQ(Ribbon(s, 2).Bezier()[3], Vec3(0, 0, 0));  // the loop closes
  EXPECT_DOUBLE_EQ(Ribbon(s, 4).Width0(), 0.25);
  // In world space, widths scaled with the transformation.
  s = Parse("Translate 1 2 3\nScale 2 2 2\nCurves \"linear\" [2] \"nonperiodic\" \"P\" [0 0 0 1 0 0] \"constantwidth\" 0.1");
  ASSERT_EQ(s.surfaces.size(), 1u);
  EXPECT_EQ(Ribbon(s, 0).Bezier()[3], Vec3(3, 2, 3));
  EXPECT_DOUBLE_EQ(Ribbon(s, 0).Width0(), 0.2);
  EXPECT_TRUE(s.surfaces[0].worldFromObject.matrix().isIdentity(0.0));
}

TEST(RibCurves, MalformedCurvesAreRefusedWithFileAndLine) {
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"Curves \"quintic\" [2] \"nonperiodic\" \"P\" [0 0 0 1 0 0]", "t.rib:2: Curves: type is \"linear\" or \"cubic\", not 'quintic'"},
      {"Curves \"linear\" [2] \"sideways\" \"P\" [0 0 0 1 0 0]", "t.rib:2: Curves: wrap is \"periodic\" or \"nonperiodic\", not 'sideways'"},
      {"Curves \"cubic\" [5] \"nonperiodic\" \"P\" [0 0 0 1 0 0 2 0 0 3 0 0 4 0 0]",
       "t.rib:2: Curves: a nonperiodic cubic curve has 4 + 3 k vertices in this basis, curve 1 has 5"},
      {"Curves \"linear\" [1] \"nonperiodic\" \"P\" [0 0 0]", "t.rib:2: Curves: a linear curve has 2 vertices at least, curve 1 has 1"},
      {"Curves \"linear\" [2] \"nonperiodic\" \"P\" [0 0 0 1 0]", "t.rib:2: Curves: \"P\" expects 6 numbers (2 points), found 5"},
      {"Curves \"linear\" [2] \"nonperiodic\" \"P\" [0 0 0 1 0 0] \"width\" [1 2 3]",
       "t.rib:2: Curves: \"width\" expects 2 values (varying), 2 (vertex), 1 (uniform) or 1, found 3"},
      {"Curves \"linear\" [2] \"nonperiodic\" \"P\" [0 0 0 1 0 0] \"width\" [1 -2]", "t.rib:2: Curves: widths are not negative"},
      {"Curves \"linear\" [2] \"nonperiodic\"", "t.rib:2: Curves: no \"P\""},
      {"Curves [2] \"nonperiodic\"", "t.rib:2: Curves expects a type, the vertex counts and a wrap, then its parameters"},
  };
  for (const auto& [body, want] : cases) EXPECT_EQ(Error(body), want) << body;
}

}  // namespace
}  // namespace patchscan
