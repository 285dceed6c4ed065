// Basis identities for every RenderMan basis, and patches in each basis against an
// independent tensor-product evaluation.
#include <gtest/gtest.h>

#include "patch/basis.h"
#include "patch/bicubic.h"
#include "test_util.h"

namespace patchscan {
namespace {

// Basis functions are sums of a few products of numbers below 10: their rounding error is
// a few ulps of 1.
constexpr double kBasisTol = 1e-14;

const Basis* const kAllBases[] = {&BezierBasis(), &BSplineBasis(), &CatmullRomBasis(),
                                  &HermiteBasis(), &PowerBasis()};

void ExpectVec4Near(const Vec4& a, const Vec4& b, const std::string& what) {
  EXPECT_LE((a - b).cwiseAbs().maxCoeff(), kBasisTol)
      << what << "\n got " << a.transpose() << "\n want " << b.transpose();
}

TEST(Basis, NamesAndSteps) {
  const std::pair<const char*, int> expected[] = {
      {"bezier", 3}, {"b-spline", 1}, {"catmull-rom", 1}, {"hermite", 2}, {"power", 4}};
  for (const auto& [name, step] : expected) {
    const auto b = BasisByName(name);
    ASSERT_TRUE(b) << name;
    EXPECT_EQ(b->step, step) << name;
    EXPECT_EQ(b->name, name);
  }
  EXPECT_FALSE(BasisByName("bspline"));
  EXPECT_FALSE(BasisByName(""));
}

TEST(Basis, PartitionOfUnity) {
  // Bézier, B-spline and Catmull-Rom weights sum to 1 (so derivatives sum to 0);
  // Hermite's two point weights sum to 1.
  for (double t = 0.0; t <= 1.0; t += 1.0 / 64) {
    for (const Basis* b : {&BezierBasis(), &BSplineBasis(), &CatmullRomBasis()}) {
      const BasisWeights w = EvaluateBasis(*b, t);
      EXPECT_NEAR(w.w.sum(), 1.0, kBasisTol) << b->name << " t=" << t;
      EXPECT_NEAR(w.dw.sum(), 0.0, kBasisTol) << b->name << " t=" << t;
      EXPECT_NEAR(w.d2w.sum(), 0.0, kBasisTol) << b->name << " t=" << t;
    }
    const BasisWeights h = EvaluateBasis(HermiteBasis(), t);
    EXPECT_NEAR(h.w[0] + h.w[2], 1.0, kBasisTol) << "hermite t=" << t;
    ExpectVec4Near(EvaluateBasis(PowerBasis(), t).w, Vec4(t * t * t, t * t, t, 1), "power");
  }
}

TEST(Basis, EndValues) {
  ExpectVec4Near(EvaluateBasis(BezierBasis(), 0).w, Vec4(1, 0, 0, 0), "bezier w(0)");
  ExpectVec4Near(EvaluateBasis(BezierBasis(), 1).w, Vec4(0, 0, 0, 1), "bezier w(1)");
  ExpectVec4Near(EvaluateBasis(BezierBasis(), 0).dw, Vec4(-3, 3, 0, 0), "bezier w'(0)");
  ExpectVec4Near(EvaluateBasis(HermiteBasis(), 0).w, Vec4(1, 0, 0, 0), "hermite w(0)");
  ExpectVec4Near(EvaluateBasis(HermiteBasis(), 1).w, Vec4(0, 0, 1, 0), "hermite w(1)");
  ExpectVec4Near(EvaluateBasis(HermiteBasis(), 0).dw, Vec4(0, 1, 0, 0), "hermite w'(0)");
  ExpectVec4Near(EvaluateBasis(HermiteBasis(), 1).dw, Vec4(0, 0, 0, 1), "hermite w'(1)");
  ExpectVec4Near(EvaluateBasis(CatmullRomBasis(), 0).w, Vec4(0, 1, 0, 0), "catmull-rom w(0)");
  ExpectVec4Near(EvaluateBasis(CatmullRomBasis(), 1).w, Vec4(0, 0, 1, 0), "catmull-rom w(1)");
  ExpectVec4Near(EvaluateBasis(CatmullRomBasis(), 0).dw, Vec4(-0.5, 0, 0.5, 0),
                 "catmull-rom w'(0)");
  ExpectVec4Near(EvaluateBasis(BSplineBasis(), 0).w, Vec4(1, 4, 1, 0) / 6, "b-spline w(0)");
  ExpectVec4Near(EvaluateBasis(BSplineBasis(), 1).w, Vec4(0, 1, 4, 1) / 6, "b-spline w(1)");
  ExpectVec4Near(EvaluateBasis(PowerBasis(), 0).w, Vec4(0, 0, 0, 1), "power w(0)");
  ExpectVec4Near(EvaluateBasis(PowerBasis(), 1).w, Vec4(1, 1, 1, 1), "power w(1)");
}

std::array<Vec3, 16> RandomControlPoints(unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> d(-2.0, 2.0);
  std::array<Vec3, 16> cv;
  for (Vec3& p : cv) p = Vec3(d(rng), d(rng), d(rng));
  return cv;
}

// The patch is sum_ij wu_i(u) wv_j(v) G(i,j): evaluated here straight from the basis
// weights, independently of the power form the patch prepares.
Vec3 TensorProduct(const std::array<Vec3, 16>& cv, const Basis& bu, const Basis& bv, double u,
                   double v) {
  const Vec4 wu = EvaluateBasis(bu, u).w, wv = EvaluateBasis(bv, v).w;
  Vec3 p = Vec3::Zero();
  for (int j = 0; j < 4; ++j)
    for (int i = 0; i < 4; ++i) p += wu[i] * wv[j] * cv[4 * j + i];
  return p;
}

// Control points are in [-2, 2]; a patch point is a sum of 16 weighted points with weights
// of size up to a few units (Hermite tangents): rounding of order 1e-14.
constexpr double kPatchTol = 1e-12;

TEST(Basis, PatchInEveryBasisMatchesTensorProduct) {
  unsigned seed = test::kSeed;
  for (const Basis* bu : kAllBases)
    for (const Basis* bv : kAllBases) {
      const auto cv = RandomControlPoints(++seed);
      const BicubicPatch patch(cv, *bu, *bv);
      for (auto [u, v] : test::SampleParams(20, seed)) {
        SurfaceDerivs d;
        patch.Evaluate(u, v, DerivOrder::Position, &d);
        EXPECT_LE((d.p - TensorProduct(cv, *bu, *bv, u, v)).norm(), kPatchTol)
            << bu->name << " x " << bv->name << " " << test::Where(u, v);
      }
    }
}

TEST(Basis, CornerInterpolation) {
  const auto cv = RandomControlPoints(7);
  SurfaceDerivs d;
  // Bézier and Hermite patches pass through their corner points: Bézier points 0, 3, 12,
  // 15; Hermite's points sit at geometry indices 0 and 2 in each direction.
  const BicubicPatch bezier(cv, BezierBasis(), BezierBasis());
  const BicubicPatch hermite(cv, HermiteBasis(), HermiteBasis());
  const BicubicPatch catmull(cv, CatmullRomBasis(), CatmullRomBasis());
  const std::tuple<double, double, int, int, int> corners[] = {
      {0, 0, 0, 0, 5}, {1, 0, 3, 2, 6}, {0, 1, 12, 8, 9}, {1, 1, 15, 10, 10}};
  for (const auto& [u, v, iBez, iHerm, iCr] : corners) {
    bezier.Evaluate(u, v, DerivOrder::Position, &d);
    EXPECT_LE((d.p - cv[iBez]).norm(), kPatchTol) << "bezier corner " << test::Where(u, v);
    hermite.Evaluate(u, v, DerivOrder::Position, &d);
    EXPECT_LE((d.p - cv[iHerm]).norm(), kPatchTol) << "hermite corner " << test::Where(u, v);
    // Catmull-Rom interpolates the inner four points at the corners.
    catmull.Evaluate(u, v, DerivOrder::Position, &d);
    EXPECT_LE((d.p - cv[iCr]).norm(), kPatchTol) << "catmull-rom corner " << test::Where(u, v);
  }
  // Bézier: the edge tangent at (0,0) is 3 (P1 - P0).
  bezier.Evaluate(0, 0, DerivOrder::First, &d);
  EXPECT_LE((d.dpdu - 3 * (cv[1] - cv[0])).norm(), kPatchTol);
  EXPECT_LE((d.dpdv - 3 * (cv[4] - cv[0])).norm(), kPatchTol);
}

// de Casteljau evaluation of a Bézier patch: repeated linear interpolation, sharing nothing
// with the power-form evaluation under test.
Vec3 DeCasteljau(const std::array<Vec3, 16>& b, double u, double v) {
  Vec3 rows[4];
  for (int j = 0; j < 4; ++j) {
    Vec3 q[4] = {b[4 * j], b[4 * j + 1], b[4 * j + 2], b[4 * j + 3]};
    for (int k = 3; k > 0; --k)
      for (int i = 0; i < k; ++i) q[i] = (1 - u) * q[i] + u * q[i + 1];
    rows[j] = q[0];
  }
  for (int k = 3; k > 0; --k)
    for (int i = 0; i < k; ++i) rows[i] = (1 - v) * rows[i] + v * rows[i + 1];
  return rows[0];
}

TEST(Basis, BSplinePatchEqualsItsBezierConversion) {
  // The B-spline patch's Bézier points (prepared by a change of basis) evaluated by
  // de Casteljau reproduce the B-spline patch; so for every other basis.
  unsigned seed = 99;
  for (const Basis* b : kAllBases) {
    const auto cv = RandomControlPoints(++seed);
    const BicubicPatch patch(cv, *b, *b);
    for (auto [u, v] : test::SampleParams(50, seed)) {
      SurfaceDerivs d;
      patch.Evaluate(u, v, DerivOrder::Position, &d);
      EXPECT_LE((d.p - DeCasteljau(patch.BezierPoints(), u, v)).norm(), kPatchTol)
          << b->name << " " << test::Where(u, v);
      EXPECT_LE((d.p - TensorProduct(cv, *b, *b, u, v)).norm(), kPatchTol)
          << b->name << " " << test::Where(u, v);
    }
  }
  // A uniform B-spline's Bézier points: the first is (P0 + 4 P1 + P2)/6 along each
  // direction; check the corner (0,0) of the tensor product directly.
  const auto cv = RandomControlPoints(5);
  const BicubicPatch patch(cv, BSplineBasis(), BSplineBasis());
  Vec3 corner = Vec3::Zero();
  const double w[3] = {1.0 / 6, 4.0 / 6, 1.0 / 6};
  for (int j = 0; j < 3; ++j)
    for (int i = 0; i < 3; ++i) corner += w[i] * w[j] * cv[4 * j + i];
  EXPECT_LE((patch.BezierPoints()[0] - corner).norm(), kPatchTol);
}

}  // namespace
}  // namespace patchscan
