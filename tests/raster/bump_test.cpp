// Blinn's bump (raster/bump.h) against the surface it imitates: a sphere moved along its
// normal by a small height, whose normal is measured by finite differences. No texture:
// the height and its derivatives are a formula, so the geometry alone is tested.
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <numbers>

#include "raster/bump.h"

namespace patchscan::raster {
namespace {

constexpr double kPi = std::numbers::pi;

// A perspective camera at the origin looking along +z, y up, focal length f pixels and the
// image centre (cx, cy): x = (f X + cx Z) / Z, y = (-f Y + cy Z) / Z.
ScreenRows Perspective(double f, double cx, double cy) {
  ScreenRows m;
  m << f, 0, cx, 0,  //
      0, -f, cy, 0,  //
      0, 0, 1, 0;
  return m;
}

Vec2 Project(const ScreenRows& m, const Vec3& p) {
  const Vec3 h = m * p.homogeneous();
  return {h.x() / h.z(), h.y() / h.z()};
}

// The sphere of radius r about c: u around the y axis, v from the pole at -y to that at +y
// (u = 3/4 faces an eye on the -z side).
struct Sphere {
  Vec3 c;
  double r;
  Vec3 At(double u, double v) const {
    const double theta = 2 * kPi * u, phi = kPi * (v - 0.5);
    return c + r * Vec3(std::cos(phi) * std::cos(theta), std::sin(phi), std::cos(phi) * std::sin(theta));
  }
  Vec3 Normal(double u, double v) const { return (At(u, v) - c) / r; }
};

// A height of 12 waves around and 6 from pole to pole, and its derivatives in u and v.
double Height(double u, double v) { return std::sin(2 * kPi * 12 * u) * std::cos(2 * kPi * 6 * v); }
Vec2 HeightGradient(double u, double v) {
  return {2 * kPi * 12 * std::cos(2 * kPi * 12 * u) * std::cos(2 * kPi * 6 * v),
          -2 * kPi * 6 * std::sin(2 * kPi * 12 * u) * std::sin(2 * kPi * 6 * v)};
}

double Angle(const Vec3& a, const Vec3& b) { return std::atan2(a.cross(b).norm(), a.dot(b)); }

// Over the sphere's side facing the eye: Blinn's normal against the normal of the sphere
// truly moved by eps * Height along its normal, by central differences. On a sphere the
// term Blinn leaves out (eps h dn/du, along the tangents) stretches both tangents alike and
// does not turn the normal to first order: the two agree to the tilt times eps h / r.
TEST(Bump, MatchesATinyDisplacementOfASphere) {
  const ScreenRows screen = Perspective(400, 160, 120);
  const Sphere sphere{Vec3(0.3, -0.2, 5.0), 1.0};
  const double eps = 1e-3 * sphere.r;  // the displacement's amplitude
  // The differences' step in u and v: their error (step^2 times the third derivative, with
  // waves 2 pi 12 per unit of u) and rounding (1e-16 / step) both stay below 1e-8.
  constexpr double kStep = 1e-5;
  // Relative to the tilt: Blinn's dropped term, eps |h| / r (1e-3 here, |h| <= 1), with a
  // fifth for the differences and the tilts near 1e-3 measured against 1e-3.
  const double tolerance = 1.2 * eps / sphere.r;
  double worst = 0.0, largestTilt = 0.0;
  int tested = 0;
  for (double u = 0.55; u < 0.95; u += 0.013)
    for (double v = 0.15; v < 0.85; v += 0.017) {
      const Vec3 p = sphere.At(u, v), n = sphere.Normal(u, v);
      if (n.dot(-p) < 0.2 * p.norm()) continue;  // the side facing the eye, off the silhouette
      // The texture footprint: d(u, v)/d(x, y), the inverse of the screen's Jacobian,
      // itself by central differences of the projection.
      Eigen::Matrix2d jacobian;
      jacobian.col(0) = (Project(screen, sphere.At(u + kStep, v)) - Project(screen, sphere.At(u - kStep, v))) / (2 * kStep);
      jacobian.col(1) = (Project(screen, sphere.At(u, v + kStep)) - Project(screen, sphere.At(u, v - kStep))) / (2 * kStep);
      const Eigen::Matrix2d footprint = jacobian.inverse();
      const Vec3 bumped =
          BumpedNormal(screen, p, n, eps * HeightGradient(u, v), footprint.col(0), footprint.col(1)).normalized();
      const auto moved = [&](double a, double b) -> Vec3 { return sphere.At(a, b) + eps * Height(a, b) * sphere.Normal(a, b); };
      const Vec3 du = (moved(u + kStep, v) - moved(u - kStep, v)) / (2 * kStep);
      const Vec3 dv = (moved(u, v + kStep) - moved(u, v - kStep)) / (2 * kStep);
      Vec3 truth = du.cross(dv).normalized();
      if (truth.dot(n) < 0) truth = -truth;
      const double tilt = Angle(truth, n);
      const double error = Angle(bumped, truth) / std::max(tilt, 1e-3);
      ASSERT_TRUE(std::isfinite(tilt) && std::isfinite(error)) << u << ' ' << v;
      largestTilt = std::max(largestTilt, tilt);
      worst = std::max(worst, error);

      ++tested;
    }
  EXPECT_GT(tested, 300);
  EXPECT_GT(largestTilt, 0.02);  // 0.024 rad: a bump that shows
  EXPECT_LT(worst, tolerance) << "relative to the tilt";
  std::cout << "bump against displacement on a sphere: " << tested << " points, largest tilt " << largestTilt
            << " rad, largest error " << worst << " of the tilt\n";
}

// On a plane seen at a slant in an orthographic view, the bump of a linear height h = a s
// turns the normal by atan(a |grad s|), towards -grad s.
TEST(Bump, TiltsAPlaneByTheHeightsSlope) {
  // Orthographic: x = 10 X + 50, y = -10 (Y cos 30 deg + Z sin 30 deg) + 40.
  const double c = std::cos(kPi / 6), s = std::sin(kPi / 6);
  ScreenRows screen;
  screen << 10, 0, 0, 50,  //
      0, -10 * c, -10 * s, 40,  //
      0, 0, 0, 1;
  // The plane z = 0, texture s = X / 4, t = Y / 4: per pixel in x, ds = 1 / 40; in y,
  // Y changes by -1 / (10 cos 30 deg).
  const Vec2 duvdx(1.0 / 40, 0), duvdy(0, -1.0 / (40 * c));
  const Vec3 n(0, 0, 1);
  for (const double slope : {0.0, 0.1, 1.0, 4.0}) {
    const Vec3 bumped = BumpedNormal(screen, Vec3(1, 2, 0), n, Vec2(slope, 0), duvdx, duvdy);
    const Vec3 want = Vec3(-slope / 4, 0, 1).normalized();
    EXPECT_LT(Angle(bumped.normalized(), want), 1e-12) << slope;
  }
  // And along t, with the normal any length.
  const Vec3 bumped = BumpedNormal(screen, Vec3(1, 2, 0), 3.0 * n, Vec2(0, 2.0), duvdx, duvdy);
  EXPECT_LT(Angle(bumped.normalized(), Vec3(0, -0.5, 1).normalized()), 1e-12);
}

TEST(Bump, NoScreenNoBump) {
  const Vec3 n(0, 0.6, 0.8);
  EXPECT_EQ(BumpedNormal(ScreenRows::Zero(), Vec3(1, 2, 3), n, Vec2(5, 5), Vec2(1, 0), Vec2(0, 1)), n);
}

}  // namespace
}  // namespace patchscan::raster
