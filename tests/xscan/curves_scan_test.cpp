// Curve ribbons through the exact scan, against the ray caster sample by sample: tapered
// b-spline hairs, a Catmull-Rom spiral that turns towards the eye and away, a linear
// zigzag, each facing the camera it is seen by (perspective and orthographic).
#include <gtest/gtest.h>

#include <cmath>
#include <sstream>
#include <variant>

#include "scene/rib/reader.h"
#include "xscan/agreement.h"

namespace patchscan {
namespace {

std::string Numbers(const std::vector<double>& v) {
  std::ostringstream s;
  s.precision(17);
  for (const double x : v) s << x << ' ';
  return s.str();
}

Scene Curves() {
  std::vector<double> hairs, spiral, zigzag;
  for (int k = 0; k < 6; ++k)
    for (int i = 0; i < 5; ++i) {
      const double a = k * 1.1, t = i / 4.0;
      hairs.insert(hairs.end(), {std::cos(a) * (0.3 + t), std::sin(a) * (0.3 + t), 0.6 * t * t - 0.3});
    }
  for (int i = 0; i < 14; ++i) {
    const double t = i / 13.0, a = 3.0 * std::numbers::pi * t;
    spiral.insert(spiral.end(), {0.8 * std::cos(a), 0.8 * std::sin(a), -0.8 + 1.6 * t});
  }
  for (int i = 0; i < 6; ++i) zigzag.insert(zigzag.end(), {-1.0 + 0.4 * i, 0.9, (i % 2) ? 0.6 : 0.2});
  const std::string rib =
      "WorldBegin\n"
      "AttributeBegin\nBasis \"b-spline\" 1 \"b-spline\" 1\nCurves \"cubic\" [5 5 5 5 5 5] \"nonperiodic\" \"P\" [" +
      Numbers(hairs) + "] \"width\" [" + Numbers({0.12, 0.06, 0.01, 0.12, 0.06, 0.01, 0.12, 0.06, 0.01, 0.12, 0.06, 0.01, 0.12, 0.06, 0.01, 0.12, 0.06, 0.01}) +
      "]\nAttributeEnd\n"
      "AttributeBegin\nBasis \"catmull-rom\" 1 \"catmull-rom\" 1\nCurves \"cubic\" [14] \"nonperiodic\" \"P\" [" + Numbers(spiral) +
      "] \"constantwidth\" 0.1\nAttributeEnd\n"
      "Curves \"linear\" [6] \"nonperiodic\" \"P\" [" + Numbers(zigzag) + "] \"constantwidth\" 0.08\n"
      "WorldEnd\n";
  auto r = ParseRib(rib, "curves.rib");
  EXPECT_TRUE(std::holds_alternative<Scene>(r)) << std::get<SourceError>(r).What();
  return std::holds_alternative<Scene>(r) ? std::get<Scene>(std::move(r)) : Scene{};
}

TEST(CurvesScan, RibbonsAgreeWithTheRayCaster) {
  Scene scene = Curves();
  ASSERT_EQ(scene.surfaces.size(), 6u * 2 + 11 + 5);
  for (const Vec3& eye : {Vec3(0.4, -4.5, 1.5), Vec3(3.5, 1.0, 3.0)}) {
    for (const bool orthographic : {false, true}) {
      const Camera camera = orthographic ? test::Orthographic(eye, 1.6, 96) : test::View(eye, 96);
      scene.FaceCamera(camera);
      test::ExpectAgree(scene.surfaces, camera, orthographic ? "curves, orthographic" : "curves", 300);
    }
  }
}

}  // namespace
}  // namespace patchscan
