// The camera: where known points land on screen, validation, automatic framing.
#include <gtest/gtest.h>

#include <numbers>

#include <Eigen/Geometry>

#include "patch/camera.h"
#include "patch/quadrics.h"

namespace patchscan {
namespace {

// Pixel positions are sums of products of numbers near 1e3: rounding ~1e-12 px.
constexpr double kPixelTol = 1e-9;

Vec3 Project(const Camera& c, const Vec3& p) {
  const Vec4 h = ScreenFromWorld(c) * p.homogeneous();
  return h.head<3>() / h.w();
}

TEST(Camera, KnownPointsLandWhereExpected) {
  Camera c;
  c.width = 800;
  c.height = 600;
  c.eye = Vec3(0, -10, 0);
  c.lookAt = Vec3(0, 0, 0);
  c.up = Vec3(0, 0, 1);
  c.fovDeg = 60;
  const Vec3 centre = Project(c, c.lookAt);
  EXPECT_NEAR(centre.x(), 400, kPixelTol);
  EXPECT_NEAR(centre.y(), 300, kPixelTol);
  // +x is to the right, +z (up) is towards smaller y (y points down the image).
  EXPECT_GT(Project(c, Vec3(1, 0, 0)).x(), 400);
  EXPECT_LT(Project(c, Vec3(0, 0, 1)).y(), 300);
  // A point at half the field of view above the axis lands on the top edge, y = 0.
  const double half = 30.0 * std::numbers::pi / 180.0;
  EXPECT_NEAR(Project(c, Vec3(0, 0, 10 * std::tan(half))).y(), 0.0, kPixelTol);
  EXPECT_NEAR(FocalPixels(c), 300.0 / std::tan(half), kPixelTol);
}

TEST(Camera, ValidationNamesTheProblem) {
  Camera c;
  EXPECT_FALSE(ValidateCamera(c));
  Camera bad = c;
  bad.lookAt = bad.eye;
  EXPECT_EQ(*ValidateCamera(bad), "eye and look-at are the same point");
  bad = c;
  bad.up = c.lookAt - c.eye;
  EXPECT_EQ(*ValidateCamera(bad), "up vector is zero or along the view direction");
  bad = c;
  bad.fovDeg = 180;
  EXPECT_EQ(*ValidateCamera(bad), "field of view 180 degrees is outside 1e-06 to 179");
  bad = c;
  bad.width = 0;
  EXPECT_EQ(*ValidateCamera(bad), "image size 0x480 is outside 1x1 to 65536x65536");
  bad = c;
  bad.hither = 0;
  EXPECT_EQ(*ValidateCamera(bad), "hither distance must be positive and finite");
}

TEST(Camera, FramingKeepsTheBoxInView) {
  // Boxes of very different sizes and places, framed in wide and tall images.
  const std::pair<Vec3, Vec3> boxes[] = {{Vec3(-3, -2, 0), Vec3(3.525, 2, 3.15)},
                                         {Vec3(1e6, 1e6, 1e6), Vec3(1e6 + 1, 1e6 + 2, 1e6 + 3)},
                                         {Vec3(-1e-6, 0, 0), Vec3(1e-6, 1e-6, 2e-6)},
                                         {Vec3(5, 5, 5), Vec3(5, 5, 5)}};
  for (const auto& [lo, hi] : boxes)
    for (auto [w, h] : {std::pair{640, 480}, std::pair{200, 900}}) {
      Camera base;
      base.width = w;
      base.height = h;
      Bounds3 box;
      box.Extend(lo);
      box.Extend(hi);
      const Camera c = FrameBounds(box, base, DefaultViewDirection(base.up));
      ASSERT_FALSE(ValidateCamera(c)) << *ValidateCamera(c);
      for (const Vec3& p : BoxCorners(box)) {
        const Vec4 hp = ScreenFromWorld(c) * p.homogeneous();
        ASSERT_GT(hp.w(), c.hither) << "corner in front of the hither plane";
        const Vec3 q = hp.head<3>() / hp.w();
        EXPECT_TRUE(q.x() >= 0 && q.x() <= w && q.y() >= 0 && q.y() <= h)
            << "corner " << p.transpose() << " at " << q.transpose() << " in " << w << "x" << h;
      }
    }
}

TEST(Camera, DefaultDirectionIsFrontRightAbove) {
  const Vec3 zUp = DefaultViewDirection(Vec3(0, 0, 1));
  EXPECT_LT(zUp.y(), 0);  // in front (-y) of a z-up scene
  EXPECT_GT(zUp.z(), 0);  // above
  const Vec3 yUp = DefaultViewDirection(Vec3(0, 1, 0));
  EXPECT_GT(yUp.z(), 0);  // in front (+z) of a y-up scene
  EXPECT_GT(yUp.y(), 0);
}

}  // namespace
}  // namespace patchscan
