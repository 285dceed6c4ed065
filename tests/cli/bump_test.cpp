// Bump mapping end to end (RenderMan's Displacement "bumpy", --bump, --normal-map): a plane
// with a sinusoidal height texture, its rendered normals (the N AOV) against the analytic
// bumped normal in every mode, and the same pixels for any thread count.
#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <iostream>
#include <numbers>
#include <string>
#include <vector>

#include "cli/folder.h"

namespace {

constexpr double kPi = std::numbers::pi;
// The height texture: kWaves waves along s and along t, kTexels texels a side.
constexpr int kWaves = 2, kTexels = 128;
constexpr double kAmplitude = 0.01;  // world units; the plane is 2 units wide

double Height(double s, double t) { return std::sin(2 * kPi * kWaves * s) * std::sin(2 * kPi * kWaves * t); }
// (dh/ds, dh/dt).
std::pair<double, double> HeightGradient(double s, double t) {
  const double k = 2 * kPi * kWaves;
  return {k * std::cos(k * s) * std::sin(k * t), k * std::sin(k * s) * std::cos(k * t)};
}

// A folder with the height texture (h.tif: float, one channel, texel centres at
// ((i + 1/2) / n, (j + 1/2) / n), t down the image) and b.rib: the plane z = 0 from
// (-1, -1) to (1, 1), s along x and t along y, bumped by it, seen at a slant; flat.rib the
// same without the bump.
struct BumpScene : Folder {
  BumpScene() : Folder("bump") {
    std::vector<float> texels(kTexels * kTexels);
    for (int j = 0; j < kTexels; ++j)
      for (int i = 0; i < kTexels; ++i)
        texels[static_cast<std::size_t>(j) * kTexels + i] =
            static_cast<float>(Height((i + 0.5) / kTexels, (j + 0.5) / kTexels));
    auto out = OIIO::ImageOutput::create("tif");
    EXPECT_TRUE(out && out->open((path / "h.tif").string(), OIIO::ImageSpec(kTexels, kTexels, 1, OIIO::TypeDesc::FLOAT)));
    EXPECT_TRUE(out->write_image(OIIO::TypeDesc::FLOAT, texels.data()));
    out->close();
    const std::string camera = "Format 160 120 1\nProjection \"perspective\" \"fov\" 40\n"
                               "Translate 0 0 3.2\nRotate -25 1 0 0\nWorldBegin\n";
    const std::string plane = "Surface \"matte\"\nPatch \"bilinear\" \"P\" [-1 -1 0 1 -1 0 -1 1 0 1 1 0]\nWorldEnd\n";
    std::ofstream(path / "b.rib") << camera << "Displacement \"bumpy\" \"amplitude\" [" << kAmplitude
                                  << "] \"texturename\" \"h.tif\"\n" << plane;
    std::ofstream(path / "flat.rib") << camera << plane;
  }
};

// The largest angle between the rendered normal (an AOV render's N) and the analytic one
// at the pixel's (u, v), over the pixels the plane covers wholly, off its edges; and how
// many pixels count.
std::pair<double, int> WorstNormal(const std::vector<float>& px) {
  constexpr int kChannels = 11, kUv = 6, kN = 8;  // R G B A Z id u v N.xyz, as OpenEXR orders them
  double worst = 0.0;
  int counted = 0;
  for (std::size_t k = 0; k + kChannels <= px.size(); k += kChannels) {
    const float* p = &px[k];
    const double s = p[kUv], t = p[kUv + 1];
    if (p[3] < 1.0f || s < 0.02 || s > 0.98 || t < 0.02 || t > 0.98) continue;
    // The plane's normal (0, 0, +-1) as the AOV gives its side, less the height's gradient:
    // d/dx = (dh/ds) / 2 with s = (x + 1) / 2, likewise y.
    const auto [hs, ht] = HeightGradient(s, t);
    const double sign = p[kN + 2] < 0 ? -1.0 : 1.0;
    double want[3] = {-kAmplitude * hs / 2, -kAmplitude * ht / 2, sign};
    const double len = std::sqrt(want[0] * want[0] + want[1] * want[1] + 1.0);
    double dot = 0.0, got = 0.0;
    for (int c = 0; c < 3; ++c) dot += want[c] / len * p[kN + c], got += p[kN + c] * p[kN + c];
    worst = std::max(worst, std::acos(std::min(1.0, dot / std::sqrt(got))));
    ++counted;
  }
  return {worst, counted};
}

TEST(Bump, SinusoidalPlaneMatchesTheAnalyticNormalInEveryMode) {
  BumpScene dir;
  // Exact: the plane and its footprint are exact; what is left is OpenImageIO's filtered
  // gradient of the texture (its bicubic B-spline smooths a wave 64 texels long by 0.3%).
  // theta and tess take the same plane exactly too (flat, its uv perspective-correct).
  for (const char* mode : {"exact", "theta", "tess"}) {
    ASSERT_EQ(dir.Run(std::string("render b.rib -o b.exr --aov --aa 1 --mode ") + mode), 0) << dir.Err();
    const auto [worst, counted] = WorstNormal(Pixels((dir.path / "b.exr").string()));
    std::cout << mode << ": largest normal error " << worst << " rad over " << counted << " pixels\n";
    EXPECT_GT(counted, 5000) << mode;
    EXPECT_LT(worst, 1e-3) << mode;
  }
  // Without the bump the normals are the plane's: the test sees the bump.
  ASSERT_EQ(dir.Run("render flat.rib -o f.exr --aov --aa 1"), 0) << dir.Err();
  EXPECT_GT(WorstNormal(Pixels((dir.path / "f.exr").string())).first, 0.05);
}

// A tangent-space normal map of the same bump (n = (-a B_s / 2, a B_t / 2, 1) normalised in
// the frame P_s, -P_t, N: green towards the image's top) on the flat plane gives the bumped
// normals: the map's frame is the surface's in every mode.
TEST(Bump, NormalMapOfTheBumpGivesItsNormals) {
  BumpScene dir;
  std::vector<float> texels(kTexels * kTexels * 3);
  for (int j = 0; j < kTexels; ++j)
    for (int i = 0; i < kTexels; ++i) {
      const auto [hs, ht] = HeightGradient((i + 0.5) / kTexels, (j + 0.5) / kTexels);
      const double n[3] = {-kAmplitude * hs / 2, kAmplitude * ht / 2, 1.0};
      const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + 1.0);
      for (int c = 0; c < 3; ++c)
        texels[(static_cast<std::size_t>(j) * kTexels + i) * 3 + c] = static_cast<float>(0.5 + 0.5 * n[c] / len);
    }
  auto out = OIIO::ImageOutput::create("tif");
  ASSERT_TRUE(out && out->open((dir.path / "n.tif").string(), OIIO::ImageSpec(kTexels, kTexels, 3, OIIO::TypeDesc::FLOAT)));
  ASSERT_TRUE(out->write_image(OIIO::TypeDesc::FLOAT, texels.data()));
  out->close();
  for (const char* mode : {"exact", "theta", "tess"}) {
    ASSERT_EQ(dir.Run(std::string("render flat.rib -o n.exr --aov --aa 1 --normal-map n.tif --mode ") + mode), 0)
        << dir.Err();
    const auto [worst, counted] = WorstNormal(Pixels((dir.path / "n.exr").string()));
    std::cout << mode << ": normal map, largest normal error " << worst << " rad\n";
    EXPECT_GT(counted, 5000) << mode;
    EXPECT_LT(worst, 1e-3) << mode;
  }
  EXPECT_EQ(dir.Run("render flat.rib -o f.png --normal-map none.tif"), kExitUsage);
  EXPECT_NE(dir.Err().find("--normal-map: no such file 'none.tif'"), std::string::npos) << dir.Err();
}

TEST(Bump, SamePixelsForAnyThreadCount) {
  BumpScene dir;
  ASSERT_EQ(dir.Run("render b.rib -o one.exr --aov --aa 3 --threads 1"), 0) << dir.Err();
  ASSERT_EQ(dir.Run("render b.rib -o three.exr --aov --aa 3 --threads 3"), 0) << dir.Err();
  const std::vector<float> one = Pixels((dir.path / "one.exr").string());
  EXPECT_FALSE(one.empty());
  EXPECT_EQ(one, Pixels((dir.path / "three.exr").string()));
}

// convert writes the bump as bumpy with the texture's absolute path: the same pixels.
TEST(Bump, ConvertKeepsTheBump) {
  BumpScene dir;
  ASSERT_EQ(dir.Run("convert b.rib -o c.rib"), 0) << dir.Err();
  ASSERT_EQ(dir.Run("render b.rib -o b.exr --aov --aa 1"), 0) << dir.Err();
  ASSERT_EQ(dir.Run("render c.rib -o c.exr --aov --aa 1"), 0) << dir.Err();
  const std::vector<float> b = Pixels((dir.path / "b.exr").string());
  EXPECT_FALSE(b.empty());
  EXPECT_EQ(b, Pixels((dir.path / "c.exr").string()));
}

TEST(Bump, TheBumpOptionBumpsEverySurface) {
  BumpScene dir;
  ASSERT_EQ(dir.Run("render flat.rib -o f.exr --aov --aa 1 --bump h.tif:" + std::to_string(kAmplitude)), 0)
      << dir.Err();
  EXPECT_LT(WorstNormal(Pixels((dir.path / "f.exr").string())).first, 1e-3);
  // Its mistakes name the option.
  EXPECT_EQ(dir.Run("render flat.rib -o f.png --bump h.tif:x"), kExitUsage);
  EXPECT_NE(dir.Err().find("--bump: expected FILE or FILE:AMPLITUDE"), std::string::npos) << dir.Err();
  EXPECT_EQ(dir.Run("render flat.rib -o f.png --bump nothere.tif"), kExitUsage);
  EXPECT_NE(dir.Err().find("--bump: no such file 'nothere.tif'"), std::string::npos) << dir.Err();
  EXPECT_FALSE(std::filesystem::exists(dir.path / "f.png"));
}

}  // namespace
