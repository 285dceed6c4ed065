// A CAD model rendered against the same shape given independently: a STEP cylinder (its side
// a rational B-spline with its caps' circles as trim curves; in tess mode Open CASCADE's
// mesh) against RenderMan's Cylinder and two Disks of the same pose, in every mode; and a CAD
// file through `info` and `convert`; the same pixels for any number of threads.
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iostream>
#include <string>

#include "cli/folder.h"
#include "scene/cad_models.h"

namespace {

constexpr int kWidth = 160, kHeight = 120;
constexpr int kChannels = 11, kA = 3, kId = 5, kN = 8;  // R G B A Z id u v N.xyz, as OpenEXR orders them
const std::string kCamera = " --size 160x120 --eye 7,-9,8 --look-at 0,0,2.5 --fov 35 --aa 3 --aov";

struct Agreement {
  double worstCoverage = 0.0, meanCoverage = 0.0;  // alpha
  double worstNormalRad = 0.0;                     // over pixels both cover wholly
  int whole = 0;
};

Agreement Compare(const std::vector<float>& a, const std::vector<float>& b) {
  Agreement g;
  for (int k = 0; k < kWidth * kHeight; ++k) {
    const float* p = &a[static_cast<std::size_t>(k) * kChannels];
    const float* q = &b[static_cast<std::size_t>(k) * kChannels];
    const double d = std::abs(p[kA] - q[kA]);
    g.worstCoverage = std::max(g.worstCoverage, d);
    g.meanCoverage += d / (kWidth * kHeight);
    // Normals where both see the same surface over the whole pixel (as `compare` measures).
    if (p[kA] < 1.0f || q[kA] < 1.0f || p[kId] != q[kId]) continue;
    // The angle as atan2(|n x m|, |n . m|): acos of the dot product would turn the float
    // channels' rounding (6e-8) into 3e-4 rad near zero.
    const Eigen::Vector3d n(p[kN], p[kN + 1], p[kN + 2]), m(q[kN], q[kN + 1], q[kN + 2]);
    g.worstNormalRad = std::max(g.worstNormalRad, std::atan2(n.cross(m).norm(), std::abs(n.dot(m))));
    ++g.whole;
  }
  return g;
}

TEST(CadRender, AStepCylinderIsRenderManCylinderAndDisks) {
  Folder dir("cad_cylinder");
  ASSERT_TRUE(cad_models::WriteStep(cad_models::Cylinder(), (dir.path / "c.step").string()));
  std::ofstream(dir.path / "c.rib") << "WorldBegin\nCylinder 2 0 5 360\nDisk 0 2 360\nTranslate 0 0 5\nDisk 0 2 360\n"
                                       "WorldEnd\n";
  for (const char* mode : {"exact", "theta", "tess"}) {
    SCOPED_TRACE(mode);
    ASSERT_EQ(dir.Run(std::string("render c.step -o step.exr --mode ") + mode + kCamera), 0) << dir.Err();
    ASSERT_EQ(dir.Run(std::string("render c.rib -o rib.exr --mode ") + mode + kCamera), 0) << dir.Err();
    const Agreement g = Compare(Pixels((dir.path / "step.exr").string()), Pixels((dir.path / "rib.exr").string()));
    std::cout << mode << ": coverage worst " << g.worstCoverage << " mean " << g.meanCoverage << ", normals worst "
              << g.worstNormalRad << " rad over " << g.whole << " pixels\n";
    EXPECT_GT(g.whole, 3000);
    if (std::string(mode) == "tess") {
      // Open CASCADE's mesh of the STEP file against Bfr's of the quadrics, each within 0.4 px
      // (--tess-error) of the shape: they differ along the outline by less than a pixel's
      // width (measured: a mean of 5.6e-4).
      EXPECT_LT(g.meanCoverage, 2e-3);
      continue;
    }
    // One sample of 9 at a pixel's edge of the shape may fall either way where the two
    // surfaces' boundaries agree to rounding: 1/9 at the most, in a handful of pixels.
    EXPECT_LE(g.worstCoverage, 1.0 / 9 + 1e-6);
    EXPECT_LT(g.meanCoverage, 1e-3);
  }
  // The normal of one sample at each pixel's centre (an AOV pixel's normal is the mean over
  // its main surface's samples, and the NURBS side is four pieces where the quadric is one).
  const std::string centre = " --size 160x120 --eye 7,-9,8 --look-at 0,0,2.5 --fov 35 --aa 1 --aov";
  ASSERT_EQ(dir.Run("render c.step -o step.exr" + centre), 0) << dir.Err();
  ASSERT_EQ(dir.Run("render c.rib -o rib.exr" + centre), 0) << dir.Err();
  const Agreement g = Compare(Pixels((dir.path / "step.exr").string()), Pixels((dir.path / "rib.exr").string()));
  std::cout << "exact, aa 1: normals worst " << g.worstNormalRad << " rad over " << g.whole << " pixels\n";
  // The STEP cylinder's side is RenderMan's Cylinder 2 0 5 360 itself (its wire runs round
  // its parameters' box: no trim), its caps bilinear patches trimmed by circles where the
  // RIB has Disks: the 1e-6 rad, with the channels' float rounding to spare.
  EXPECT_LT(g.worstNormalRad, 1e-6);
}

// The rules every scene keeps (tests/cli/cli_test.cpp): the same pixels, AOVs included, for
// any --threads, in every mode; a CAD model's trimmed pieces (a box with a hole through it)
// and its own mesh in tess mode (a torus) among them.
TEST(CadRender, SamePixelsForAnyNumberOfThreads) {
  Folder dir("cad_threads");
  ASSERT_TRUE(cad_models::WriteStep(cad_models::BoxWithHole(), (dir.path / "h.step").string()));
  ASSERT_TRUE(cad_models::WriteStep(cad_models::Torus(), (dir.path / "t.step").string()));
  for (const char* model : {"h.step", "t.step"})
    for (const char* mode : {"exact", "theta", "tess"}) {
      const std::string common = std::string("render ") + model + " --size 96x72 --aa 2 --aov --mode " + mode;
      ASSERT_EQ(dir.Run(common + " --threads 1 -o one.exr"), 0) << dir.Err();
      for (int n : {2, 3}) {
        ASSERT_EQ(dir.Run(common + " --threads " + std::to_string(n) + " -o many.exr"), 0) << dir.Err();
        EXPECT_EQ(Pixels((dir.path / "one.exr").string()), Pixels((dir.path / "many.exr").string()))
            << model << " " << mode << ", --threads " << n;
      }
    }
}

TEST(CadRender, InfoAndConvertOfAStepFile) {
  Folder dir("cad_info");
  ASSERT_TRUE(cad_models::WriteStep(cad_models::BoxWithHole(), (dir.path / "h.step").string()));
  const Result info = Patchscan("info " + (dir.path / "h.step").string());
  ASSERT_EQ(info.code, 0) << info.err;
  EXPECT_NE(info.out.find("CAD model: 7 faces (cylinder 1, plane 6)"), std::string::npos) << info.out;
  EXPECT_NE(info.out.find("widest gap between faces along an edge"), std::string::npos);
  ASSERT_EQ(dir.Run("convert h.step -o h.rib"), 0) << dir.Err();
  ASSERT_EQ(dir.Run("render h.rib -o rib.exr" + kCamera), 0) << dir.Err();
  ASSERT_EQ(dir.Run("render h.step -o step.exr" + kCamera), 0) << dir.Err();
  const Agreement g = Compare(Pixels((dir.path / "step.exr").string()), Pixels((dir.path / "rib.exr").string()));
  EXPECT_LT(g.meanCoverage, 1e-4);  // NuPatch and TrimCurve written with every digit
}

// Open CASCADE lives in a module (scene/cad_library.h) that a run loads when it reads a CAD
// file, and only then.
TEST(CadRender, TheCadModuleIsLoadedForACadFileOnly) {
  Folder dir("cad_module");
  ASSERT_TRUE(cad_models::WriteStep(cad_models::BoxWithHole(), (dir.path / "h.step").string()));
  const auto loaded = [&](const std::string& scene) {
    EXPECT_EQ(dir.Run("render " + scene + " -o a.png --size 8x6 --stats-json s.json"), 0) << dir.Err();
    const std::string json = Slurp(dir.path / "s.json");
    EXPECT_NE(json.find("\"cad_library_loaded\": "), std::string::npos) << json;
    return json.find("\"cad_library_loaded\": true") != std::string::npos;
  };
  EXPECT_TRUE(loaded("h.step"));
  EXPECT_FALSE(loaded(PATCHSCAN_SURFACES_DIR "/teapot.bpt"));
}

}  // namespace
