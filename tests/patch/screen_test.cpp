// Screen space: derivatives carried through the perspective projection, the silhouette
// function J against the analytic silhouette of a sphere, and conservative screen bounds.
#include <gtest/gtest.h>

#include <sstream>

#include "all_surfaces.h"
#include "patch/screen.h"
#include "test_util.h"

namespace patchscan {
namespace {

Camera TestCamera() {
  Camera c;
  c.width = 640;
  c.height = 480;
  c.eye = Vec3(2.5, -7.0, 3.0);
  c.lookAt = Vec3(0.4, 0.2, -0.1);
  c.up = Vec3(0.1, 0, 1);
  c.fovDeg = 40;
  c.hither = 0.1;
  return c;
}

Affine3 TestPlacement() {
  Affine3 t = Affine3::Identity();
  t.translate(Vec3(0.3, -0.2, 0.4));
  t.rotate(Eigen::AngleAxisd(0.7, Vec3(1, 2, 3).normalized()));
  t.scale(Vec3(1.2, 0.9, 1.1));
  return t;
}

TEST(Screen, DerivativesMatchDifferences) {
  const Camera cam = TestCamera();
  for (auto kind : test::AllSurfaceKinds()) {
    // Named, not bound: a lambda may not capture a structured binding (clang 14).
    const std::string& name = kind.first;
    Surface& surface = kind.second;
    surface.worldFromObject = TestPlacement();
    const ScreenMap map(cam, surface.worldFromObject);
    for (auto [u, v] : test::SampleParams(30)) {
      test::ExpectDerivativesMatchDifferences(
          [&](double a, double b, DerivOrder o, SurfaceDerivs* d) {
            ScreenDerivs s;
            EvaluateScreen(surface, map, a, b, o, &s);
            *d = s;
          },
          u, v, name + " (screen x, y, depth)");
      // Depth is ~1e-3 the size of x and y: check it on its own scale.
      test::ExpectDerivativesMatchDifferences(
          [&](double a, double b, DerivOrder o, SurfaceDerivs* d) {
            ScreenDerivs s;
            EvaluateScreen(surface, map, a, b, o, &s);
            auto z = [](const Vec3& q) { return Vec3(q.z(), q.z(), q.z()); };
            *d = {z(s.p), z(s.dpdu), z(s.dpdv), z(s.d2pdu2), z(s.d2pduv), z(s.d2pdv2)};
          },
          u, v, name + " (screen depth)");
    }
  }
}

TEST(Screen, DepthIsLinearInInverseDistance) {
  const Camera cam = TestCamera();
  const ScreenMap map(cam, Affine3::Identity());
  const Vec3 forward = (cam.lookAt - cam.eye).normalized();
  for (double z : {0.1, 0.5, 1.0, 7.0, 1e3}) {
    ScreenDerivs s;
    const Sphere point(0.0, 0, 0, 360);  // a sphere of radius 0 is the origin
    Surface at{point, Affine3(Eigen::Translation3d(cam.eye + z * forward))};
    const ScreenMap m(cam, at.worldFromObject);
    EvaluateScreen(at, m, 0.5, 0.5, DerivOrder::Position, &s);
    EXPECT_NEAR(s.w, z, 1e-12 * z);
    EXPECT_NEAR(s.p.z(), 1.0 - cam.hither / z, 1e-14);
    EXPECT_NEAR(s.p.x(), 320.0, 1e-9);  // on the view axis: the image centre
    EXPECT_NEAR(s.p.y(), 240.0, 1e-9);
  }
  (void)map;
}

// Points (x, y) where J changes sign along v, found by bisection to the last bit.
std::vector<Vec2> SilhouettePoints(const Surface& s, const ScreenMap& map) {
  auto j = [&](double u, double v) {
    ScreenDerivs d;
    EvaluateScreen(s, map, u, v, DerivOrder::First, &d);
    return SilhouetteJ(d);
  };
  std::vector<Vec2> pts;
  constexpr int kU = 180, kV = 400;
  for (int i = 0; i < kU; ++i) {
    const double u = (i + 0.5) / kU;
    for (int k = 0; k < kV; ++k) {
      // Stay off the poles, where dp/du = 0 makes J vanish identically.
      double a = 0.01 + 0.98 * k / kV, b = 0.01 + 0.98 * (k + 1) / kV;
      double ja = j(u, a);
      if ((ja > 0) == (j(u, b) > 0)) continue;
      for (int it = 0; it < 200 && a < b; ++it) {
        const double m = 0.5 * (a + b);
        if (m <= a || m >= b) break;
        if ((j(u, m) > 0) == (ja > 0)) a = m; else b = m;
      }
      ScreenDerivs d;
      EvaluateScreen(s, map, u, a, DerivOrder::Position, &d);
      pts.emplace_back(d.p.x(), d.p.y());
    }
  }
  return pts;
}

TEST(Screen, SphereSilhouetteIsTheAnalyticConic) {
  // The silhouette of a sphere (centre c, radius r) seen from e is where the view ray makes
  // the angle alpha with c - e, sin(alpha) = r / |c - e|: a conic on screen. Each J = 0
  // point is compared with the conic point on the ray from the projected centre.
  constexpr double kSilhouetteTolPx = 1e-9;  // the bound; rounding is ~1e-12 px
  const Camera cam = TestCamera();
  const Vec3 centre(0.5, 0.3, -0.2);
  const double radius = 1.5;
  const Surface sphere{Sphere(radius, -radius, radius, 360),
                       Affine3(Eigen::Translation3d(centre))};
  const ScreenMap map(cam, sphere.worldFromObject);
  const Mat4 m = ScreenFromWorld(cam);
  // The view ray through pixel (x, y): the intersection of the planes X = xW and Y = yW.
  auto ray = [&](const Vec2& q) {
    const Vec4 a = m.row(0) - q.x() * m.row(3), b = m.row(1) - q.y() * m.row(3);
    return Vec3(a.head<3>().cross(b.head<3>()));
  };
  const Vec3 toCentre = centre - cam.eye;
  const double cos2 = 1.0 - radius * radius / toCentre.squaredNorm();
  auto g = [&](const Vec2& q) {  // > 0 inside the silhouette, < 0 outside
    const Vec3 d = ray(q);
    return std::pow(d.dot(toCentre), 2) / (d.squaredNorm() * toCentre.squaredNorm()) - cos2;
  };
  const Vec4 hc = m * centre.homogeneous();
  const Vec2 q0 = hc.head<2>() / hc.w();

  const std::vector<Vec2> pts = SilhouettePoints(sphere, map);
  ASSERT_GE(pts.size(), 170u);  // the silhouette crosses nearly every meridian
  double worst = 0.0;
  for (const Vec2& q : pts) {
    // Bisect g along q0 + t (q - q0) for t in [0.5, 2].
    double lo = 0.5, hi = 2.0;
    ASSERT_GT(g(q0 + lo * (q - q0)), 0);
    ASSERT_LT(g(q0 + hi * (q - q0)), 0);
    for (int it = 0; it < 200; ++it) {
      const double t = 0.5 * (lo + hi);
      if (t <= lo || t >= hi) break;
      (g(q0 + t * (q - q0)) > 0 ? lo : hi) = t;
    }
    const double err = std::abs(lo - 1.0) * (q - q0).norm();
    worst = std::max(worst, err);
    EXPECT_LE(err, kSilhouetteTolPx) << "silhouette point " << q.transpose();
  }
  std::ostringstream w;
  w << std::scientific << worst;
  RecordProperty("worst_silhouette_error_px", w.str());
}

TEST(Screen, BoundsContainTheSurfaceOrAreRefused) {
  const Camera cam = TestCamera();
  for (auto kind : test::AllSurfaceKinds()) {
    // Named, not bound: a lambda may not capture a structured binding (clang 14).
    const std::string& name = kind.first;
    Surface& surface = kind.second;
    surface.worldFromObject = TestPlacement();
    const ScreenMap map(cam, surface.worldFromObject);
    const auto box = ScreenBounds(surface, map);
    ASSERT_TRUE(box) << name;
    for (auto [u, v] : test::SampleParams(200)) {
      ScreenDerivs d;
      EvaluateScreen(surface, map, u, v, DerivOrder::Position, &d);
      EXPECT_TRUE((d.p.array() >= box->lo.array() - 1e-9).all() &&
                  (d.p.array() <= box->hi.array() + 1e-9).all())
          << name << " " << test::Where(u, v);
    }
  }
  // A sphere around the eye has hull points behind it: no finite bounds.
  const Surface around{Sphere(1.0, -1, 1, 360), Affine3(Eigen::Translation3d(cam.eye))};
  EXPECT_FALSE(ScreenBounds(around, ScreenMap(cam, around.worldFromObject)));
}

}  // namespace
}  // namespace patchscan
