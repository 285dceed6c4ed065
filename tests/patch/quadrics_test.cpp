// Quadrics and test surfaces: positions against their closed forms, derivatives against
// central differences, and object hulls that contain every sampled point.
#include <gtest/gtest.h>

#include <numbers>

#include "all_surfaces.h"
#include "patch/quadrics.h"
#include "test_util.h"

namespace patchscan {
namespace {

// Closed forms are a few trigonometric evaluations of unit-sized numbers: rounding ~1e-15.
constexpr double kClosedFormTol = 1e-13;
constexpr double kPi = std::numbers::pi;

Vec3 At(const auto& shape, double u, double v) {
  SurfaceDerivs d;
  shape.Evaluate(u, v, DerivOrder::Position, &d);
  return d.p;
}
double Rho(const Vec3& p) { return std::hypot(p.x(), p.y()); }

TEST(Quadrics, SphereClosedForm) {
  const Sphere s(2.0, -1.0, 1.5, 270);
  for (auto [u, v] : test::SampleParams(100)) {
    const Vec3 p = At(s, u, v);
    EXPECT_NEAR(p.norm(), 2.0, kClosedFormTol) << test::Where(u, v);
    EXPECT_NEAR(std::atan2(p.y(), p.x()), std::remainder(u * 1.5 * kPi, 2 * kPi), kClosedFormTol);
    // z sweeps from zmin to zmax linearly in latitude phi.
    const double phi = std::asin(-0.5) + v * (std::asin(0.75) - std::asin(-0.5));
    EXPECT_NEAR(p.z(), 2.0 * std::sin(phi), kClosedFormTol) << test::Where(u, v);
  }
  EXPECT_NEAR(At(s, 0, 0).z(), -1.0, kClosedFormTol);
  EXPECT_NEAR(At(s, 0, 1).z(), 1.5, kClosedFormTol);
}

TEST(Quadrics, CylinderConeDiskClosedForms) {
  const Cylinder cyl(0.7, -1.0, 1.2, 360);
  const Cone cone(2.0, 0.8, 360);
  const Disk disk(0.5, 1.3, 360);
  for (auto [u, v] : test::SampleParams(100)) {
    const Vec3 c = At(cyl, u, v);
    EXPECT_NEAR(Rho(c), 0.7, kClosedFormTol);
    EXPECT_NEAR(c.z(), -1.0 + 2.2 * v, kClosedFormTol);
    const Vec3 k = At(cone, u, v);
    EXPECT_NEAR(Rho(k), 0.8 * (1 - v), kClosedFormTol);
    EXPECT_NEAR(k.z(), 2.0 * v, kClosedFormTol);
    const Vec3 d = At(disk, u, v);
    EXPECT_NEAR(Rho(d), 1.3 * (1 - v), kClosedFormTol);
    EXPECT_NEAR(d.z(), 0.5, kClosedFormTol);
  }
  EXPECT_LE((At(cone, 0.3, 1.0) - Vec3(0, 0, 2)).norm(), kClosedFormTol);  // apex
}

TEST(Quadrics, ParaboloidClosedForm) {
  const Paraboloid p(1.2, 0.5, 1.5, 200);
  for (auto [u, v] : test::SampleParams(100)) {
    const Vec3 q = At(p, u, v);
    EXPECT_NEAR(q.z(), 1.5 * Rho(q) * Rho(q) / (1.2 * 1.2), kClosedFormTol);  // z = zmax rho^2 / rmax^2
    EXPECT_NEAR(q.z(), 0.5 + v, kClosedFormTol);
  }
}

TEST(Quadrics, HyperboloidClosedForm) {
  const Vec3 a(1, -0.5, -1), b(-0.3, 1, 1);
  const Hyperboloid h(a, b, 360);
  for (auto [u, v] : test::SampleParams(100)) {
    const Vec3 q = At(h, u, v), l = a + v * (b - a);
    EXPECT_NEAR(Rho(q), Rho(l), kClosedFormTol);  // rotation keeps the distance from z
    EXPECT_NEAR(q.z(), l.z(), kClosedFormTol);
    const double turned = std::remainder(std::atan2(q.y(), q.x()) - std::atan2(l.y(), l.x()), 2 * kPi);
    EXPECT_NEAR(turned, std::remainder(u * 2 * kPi, 2 * kPi), 1e-9) << test::Where(u, v);
  }
}

TEST(Quadrics, TorusAndSaddlesClosedForms) {
  const Torus t(1.5, 0.4, 0, 360, 360);
  const Saddle s(1.0);
  const MonkeySaddle m(0.9);
  for (auto [u, v] : test::SampleParams(100)) {
    const Vec3 q = At(t, u, v);
    EXPECT_NEAR(std::pow(Rho(q) - 1.5, 2) + q.z() * q.z(), 0.16, kClosedFormTol);
    const Vec3 p = At(s, u, v);
    EXPECT_NEAR(p.z(), p.x() * p.x() - p.y() * p.y(), kClosedFormTol);
    EXPECT_NEAR(p.x(), 2 * u - 1, kClosedFormTol);
    const Vec3 r = At(m, u, v);
    EXPECT_NEAR(r.z(), r.x() * r.x() * r.x() - 3 * r.x() * r.y() * r.y(), kClosedFormTol);
  }
}

TEST(Surfaces, DerivativesMatchDifferences) {
  for (const auto& kind : test::AllSurfaceKinds()) {
    const auto& surface = kind.second;  // a lambda may not capture a structured binding (clang 14)
    for (auto [u, v] : test::SampleParams(40))
      test::ExpectDerivativesMatchDifferences(
          [&](double a, double b, DerivOrder o, SurfaceDerivs* d) {
            EvaluateObject(surface, a, b, o, d);
          },
          u, v, kind.first);
  }
}

TEST(Surfaces, HullContainsSurfaceAndIsTight) {
  // Hull boxes are analytic: every point lies inside, and the box is no more than
  // kTightness larger than the sampled extent (sampling finds the extremes to within the
  // grid's spacing squared).
  constexpr double kInside = 1e-12, kTightness = 0.02;
  for (const auto& [name, surface] : test::AllSurfaceKinds()) {
    Bounds3 hull, seen;
    for (const Vec3& p : ObjectHull(surface)) hull.Extend(p);
    constexpr int kGrid = 200;
    for (int j = 0; j <= kGrid; ++j)
      for (int i = 0; i <= kGrid; ++i) {
        SurfaceDerivs d;
        EvaluateObject(surface, double(i) / kGrid, double(j) / kGrid, DerivOrder::Position, &d);
        seen.Extend(d.p);
      }
    const double size = seen.Diagonal().norm();
    EXPECT_TRUE((seen.lo.array() >= hull.lo.array() - kInside).all() &&
                (seen.hi.array() <= hull.hi.array() + kInside).all())
        << name << ": hull " << hull.lo.transpose() << " .. " << hull.hi.transpose()
        << ", surface " << seen.lo.transpose() << " .. " << seen.hi.transpose();
    const bool controlHull =
        std::holds_alternative<BicubicPatch>(surface.shape) || std::holds_alternative<NurbsPiece>(surface.shape);
    if (!controlHull && name != "hyperboloid") {  // control hulls and the full annulus are looser
      EXPECT_LE((hull.Diagonal() - seen.Diagonal()).norm(), kTightness * size) << name;
    }
  }
}

TEST(Quadrics, AFullTurnClosesBitForBit) {
  // u = 0 and u = 1 of a full turn are one curve (and v = 0 and 1 of a full torus tube):
  // the same bits, so tessellations and scans see no seam between them.
  const std::vector<Shape> shapes = {Sphere(1.3, -1.3, 1.3, 360.0), Cylinder(0.7, -1, 2, 360.0), Cone(2, 0.9, 360.0),
                                     Paraboloid(1.1, 0.2, 2.0, 360.0),
                                     Hyperboloid(Vec3(1, 0.3, -1), Vec3(0.2, 1, 1), 360.0), Disk(0.5, 1.5, 360.0),
                                     Torus(1.0, 0.3, 0.0, 360.0, 360.0)};
  for (const Shape& shape : shapes)
    for (double t : {0.0, 0.125, 0.5, 0.7, 1.0}) {
      SurfaceDerivs a, b;
      EvaluateObject(Surface{shape, Affine3::Identity()}, 0.0, t, DerivOrder::First, &a);
      EvaluateObject(Surface{shape, Affine3::Identity()}, 1.0, t, DerivOrder::First, &b);
      EXPECT_EQ(a.p, b.p) << "at v = " << t;
      EXPECT_EQ(a.dpdv, b.dpdv) << "at v = " << t;
    }
  const Surface torus{Torus(1.0, 0.3, -180.0, 180.0, 360.0), Affine3::Identity()};
  for (double u : {0.0, 0.3, 1.0}) {
    SurfaceDerivs a, b;
    EvaluateObject(torus, u, 0.0, DerivOrder::Position, &a);
    EvaluateObject(torus, u, 1.0, DerivOrder::Position, &b);
    EXPECT_EQ(a.p, b.p) << "tube ends at u = " << u;
  }
}

TEST(Quadrics, ParaboloidApexIsFinite) {
  const Paraboloid p(1.0, 0.0, 2.0, 360);
  SurfaceDerivs d;
  p.Evaluate(0.3, 0.0, DerivOrder::Second, &d);
  EXPECT_TRUE(d.p.allFinite() && d.dpdu.allFinite() && d.dpdv.allFinite() &&
              d.d2pdu2.allFinite() && d.d2pduv.allFinite() && d.d2pdv2.allFinite());
  EXPECT_LE(d.p.norm(), 1e-15);
}

TEST(Quadrics, SectorBoxIsExact) {
  // A quarter annulus from 30 to 120 degrees.
  const Bounds2 b = SectorBox(1.0, 2.0, kPi / 6, 2 * kPi / 3);
  EXPECT_NEAR(b.lo.x(), 2 * std::cos(2 * kPi / 3), kClosedFormTol);
  EXPECT_NEAR(b.hi.x(), 2 * std::cos(kPi / 6), kClosedFormTol);
  EXPECT_NEAR(b.lo.y(), 1 * std::sin(kPi / 6), kClosedFormTol);
  EXPECT_NEAR(b.hi.y(), 2.0, kClosedFormTol);
  // A turn or more, however many (a sweep of 1e300 radians once walked its quarter turns
  // one by one): the whole annulus's box, at once.
  for (double sweep : {2 * kPi, 7.0, 1e300}) {
    const Bounds2 w = SectorBox(1.0, 2.0, -1.0, -1.0 + sweep);
    EXPECT_EQ(w.lo, Vec2(-2, -2)) << sweep;
    EXPECT_EQ(w.hi, Vec2(2, 2)) << sweep;
  }
}

}  // namespace
}  // namespace patchscan
