// Environment maps end to end (Blinn and Newell 1976; RenderMan's MakeLatLongEnvironment and
// shinymetal, --environment): a mirror sphere reflecting a lat-long map whose colour is its
// own direction, each pixel against the analytic lookup of the reflected view ray.
#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <numbers>
#include <string>
#include <vector>

#include "cli/folder.h"

namespace {

constexpr double kPi = std::numbers::pi;
constexpr int kWidth = 200, kHeight = 150;
constexpr double kFovDeg = 40, kDistance = 5;

// Writes a float RGB OpenEXR image of w x h texels whose colour at texel (x, y) is
// (1 + d) / 2 for d = direction(x, y) of unit length.
template <class Direction>
void WriteDirections(const std::filesystem::path& file, int w, int h, Direction&& direction) {
  std::vector<float> texels(static_cast<std::size_t>(w) * h * 3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const std::array<double, 3> d = direction(x, y);
      const double l = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
      for (int c = 0; c < 3; ++c) texels[(static_cast<std::size_t>(y) * w + x) * 3 + c] = static_cast<float>(0.5 + 0.5 * d[c] / l);
    }
  auto out = OIIO::ImageOutput::create("exr");
  EXPECT_TRUE(out && out->open(file.string(), OIIO::ImageSpec(w, h, 3, OIIO::TypeDesc::FLOAT)));
  EXPECT_TRUE(out->write_image(OIIO::TypeDesc::FLOAT, texels.data()));
  out->close();
}

// A folder with a map of the surroundings whose colour at direction d is (1 + d) / 2, and
// m.rib: a mirror sphere (shinymetal, nothing but Kr) at the origin, its poles along y, seen
// from -kDistance along z. With cubeFovDeg 0 the map is dir.exr, a lat-long image (OpenEXR's
// layout: +y up, longitude pi at the left edge, longitude 0 along +z), made into dir.tx by
// MakeLatLongEnvironment; otherwise six cube faces px.exr ... nz.exr of that field of view,
// oriented as the RenderMan Interface's cube faces (OpenGL's cube map table: on face +x,
// s = -z / x and t = -y / x, from -1 at the left and top edges), made into dir.tx by
// MakeCubeFaceEnvironment.
struct MirrorScene : Folder {
  explicit MirrorScene(double cubeFovDeg = 0) : Folder("environment") {
    std::string make = "MakeLatLongEnvironment \"dir.exr\" \"dir.tx\" \"gaussian\" 1 1";
    if (cubeFovDeg == 0) {
      constexpr int w = 256, h = 128;
      WriteDirections(path / "dir.exr", w, h, [&](int x, int y) {
        const double lat = kPi / 2 - kPi * (y + 0.5) / h, lon = kPi - 2 * kPi * (x + 0.5) / w;
        return std::array<double, 3>{std::cos(lat) * std::sin(lon), std::sin(lat), std::cos(lat) * std::cos(lon)};
      });
    } else {
      constexpr int n = 64;
      const double tanHalf = std::tan(cubeFovDeg / 2 * kPi / 180);
      const char* names[6] = {"px", "nx", "py", "ny", "pz", "nz"};
      for (int face = 0; face < 6; ++face)
        WriteDirections(path / (std::string(names[face]) + ".exr"), n, n, [&](int x, int y) {
          const double s = (2 * (x + 0.5) / n - 1) * tanHalf, t = (2 * (y + 0.5) / n - 1) * tanHalf;
          switch (face) {
            case 0: return std::array<double, 3>{1, -t, -s};
            case 1: return std::array<double, 3>{-1, -t, s};
            case 2: return std::array<double, 3>{s, 1, t};
            case 3: return std::array<double, 3>{s, -1, -t};
            case 4: return std::array<double, 3>{s, -t, 1};
            default: return std::array<double, 3>{-s, -t, -1};
          }
        });
      make = "MakeCubeFaceEnvironment \"px.exr\" \"nx.exr\" \"py.exr\" \"ny.exr\" \"pz.exr\" \"nz.exr\" \"dir.tx\" " +
             std::to_string(cubeFovDeg) + " \"gaussian\" 1 1";
    }
    std::ofstream(path / "m.rib") << "Format " << kWidth << ' ' << kHeight << " 1\nProjection \"perspective\" \"fov\" ["
                                  << kFovDeg << "]\nTranslate 0 0 " << kDistance << '\n' << make
                                  << "\nWorldBegin\n"
                                     "Surface \"shinymetal\" \"Ka\" [0] \"Ks\" [0] \"Kr\" [1] \"texturename\" \"dir.tx\"\n"
                                     "Rotate 90 1 0 0\nSphere 1 -1 1 360\nWorldEnd\n";
  }
};

// The largest colour error, over the pixels the sphere covers wholly, against (1 + R) / 2 with
// R the view ray through the pixel's centre reflected in the rendered normal (an --aov
// render at aa 1: colour and normal of one sample); and how many pixels count.
std::pair<double, int> WorstReflection(const std::vector<float>& px) {
  constexpr int kChannels = 11, kN = 8;  // R G B A Z id u v N.xyz, as OpenEXR orders them
  const double tanHalf = std::tan(kFovDeg / 2 * kPi / 180), aspect = static_cast<double>(kWidth) / kHeight;
  double worst = 0.0;
  int counted = 0;
  for (int y = 0; y < kHeight; ++y)
    for (int x = 0; x < kWidth; ++x) {
      const float* p = &px[(static_cast<std::size_t>(y) * kWidth + x) * kChannels];
      if (p[3] < 1.0f) continue;
      // The view ray in world space (world is camera space moved kDistance back).
      double i[3] = {(2 * (x + 0.5) / kWidth - 1) * aspect * tanHalf, (1 - 2 * (y + 0.5) / kHeight) * tanHalf, 1};
      const double li = std::sqrt(i[0] * i[0] + i[1] * i[1] + 1);
      double n[3] = {p[kN], p[kN + 1], p[kN + 2]}, ni = 0, ln = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
      for (int c = 0; c < 3; ++c) i[c] /= li, n[c] /= ln, ni += n[c] * i[c];
      for (int c = 0; c < 3; ++c) {
        const double r = i[c] - 2 * ni * n[c];
        worst = std::max(worst, std::abs(p[c] - (0.5 + 0.5 * r)));
      }
      ++counted;
    }
  return {worst, counted};
}

TEST(Environment, MirrorSphereReflectsTheAnalyticDirectionInEveryMode) {
  MirrorScene dir;
  // The map's colour is smooth in the direction: what is left is its bilinear interpolation
  // between texels 1.4 degrees apart (its second derivative, about 1e-4), the filter over the
  // footprint, and the normal each mode gives (the AOV's, the same the lookup took).
  constexpr double kTolerance = 2e-3;
  for (const char* mode : {"exact", "theta", "tess"}) {
    ASSERT_EQ(dir.Run(std::string("render m.rib -o m.exr --aov --aa 1 --mode ") + mode), 0) << dir.Err();
    const auto [worst, counted] = WorstReflection(Pixels((dir.path / "m.exr").string()));
    std::cout << mode << ": largest colour error " << worst << " over " << counted << " pixels\n";
    EXPECT_GT(counted, 2500) << mode;
    EXPECT_LT(worst, kTolerance) << mode;
  }
}

// MakeCubeFaceEnvironment: six faces resampled into the lat-long map the lookups read; faces
// of 90 degrees and, overlapping, of 100 (the images then span tan 50 degrees).
TEST(Environment, CubeFacesReflectTheAnalyticDirection) {
  // As above, with the faces' 64 x 64 texels (2 to 0.7 degrees apart) bilinearly resampled
  // once more into the lat-long image before it is filtered.
  constexpr double kTolerance = 3e-3;
  for (const double fov : {90.0, 100.0}) {
    MirrorScene cube(fov);
    ASSERT_EQ(cube.Run("render m.rib -o m.exr --aov --aa 1"), 0) << cube.Err();
    EXPECT_EQ(cube.Err().find("warning"), std::string::npos) << cube.Err();
    const auto [worst, counted] = WorstReflection(Pixels((cube.path / "m.exr").string()));
    std::cout << "cube faces of " << fov << " degrees: largest colour error " << worst << " over " << counted
              << " pixels\n";
    EXPECT_GT(counted, 2500);
    EXPECT_LT(worst, kTolerance) << fov;
    // The lat-long image went through a temporary file, which is gone.
    for (const auto& entry : std::filesystem::directory_iterator(cube.path))
      EXPECT_EQ(entry.path().filename().string().find(".dir.tx"), std::string::npos) << entry.path();
  }
}

TEST(Environment, OptionReflectsOnMetalAndPlasticNotOnMatte) {
  MirrorScene dir;
  ASSERT_EQ(dir.Run("render m.rib -o m.exr --aa 1"), 0) << dir.Err();  // makes dir.tx
  const auto scene = [&](const std::string& surface) {
    std::ofstream(dir.path / "s.rib") << "Format 64 48 1\nProjection \"perspective\" \"fov\" [40]\nTranslate 0 0 5\n"
                                         "WorldBegin\nLightSource \"ambientlight\" 1 \"intensity\" [0.2]\n"
                                      << surface << "\nSphere 1 -1 1 360\nWorldEnd\n";
  };
  for (const std::string surface : {"Surface \"metal\"", "Surface \"plastic\"", "Surface \"matte\""}) {
    scene(surface);
    ASSERT_EQ(dir.Run("render s.rib -o plain.exr --aa 1"), 0) << dir.Err();
    ASSERT_EQ(dir.Run("render s.rib -o env.exr --aa 1 --environment dir.tx:0.5"), 0) << dir.Err();
    const std::vector<float> plain = Pixels((dir.path / "plain.exr").string()), env = Pixels((dir.path / "env.exr").string());
    ASSERT_EQ(plain.size(), env.size());
    double added = 0;
    for (std::size_t k = 0; k < plain.size(); ++k) added = std::max(added, static_cast<double>(env[k] - plain[k]));
    if (surface == "Surface \"matte\"")
      EXPECT_EQ(added, 0.0) << surface;
    else
      EXPECT_GT(added, 0.2) << surface;  // half of a map whose colours reach 1
  }
  EXPECT_EQ(dir.Run("render s.rib -o f.png --environment dir.tx:x"), kExitUsage);
  EXPECT_NE(dir.Err().find("--environment: expected FILE or FILE:KR"), std::string::npos) << dir.Err();
  EXPECT_EQ(dir.Run("render s.rib -o f.png --environment none.tx"), kExitUsage);
  EXPECT_NE(dir.Err().find("--environment: no such file 'none.tx'"), std::string::npos) << dir.Err();
}

// A shinymetal whose map was never made: exit 1 naming it; a MakeLatLongEnvironment whose
// input is missing: a warning, the frame still rendered (then failing on the missing map).
TEST(Environment, MissingMapsAreNamed) {
  MirrorScene dir;
  std::filesystem::remove(dir.path / "dir.exr");
  EXPECT_EQ(dir.Run("render m.rib -o m.png"), 1);
  EXPECT_NE(dir.Err().find("MakeLatLongEnvironment: dir.exr: no such file"), std::string::npos) << dir.Err();
  EXPECT_NE(dir.Err().find("shinymetal environment map 'dir.tx' not found"), std::string::npos) << dir.Err();
  EXPECT_FALSE(std::filesystem::exists(dir.path / "m.png"));

  MirrorScene cube(90);
  std::filesystem::remove(cube.path / "ny.exr");
  EXPECT_EQ(cube.Run("render m.rib -o m.png"), 1);
  EXPECT_NE(cube.Err().find("m.rib:4: MakeCubeFaceEnvironment: ny.exr: no such file (no frame of m.rib writes ny.exr); "
                            "dir.tx is not made"),
            std::string::npos)
      << cube.Err();
  EXPECT_FALSE(std::filesystem::exists(cube.path / "m.png"));
}

}  // namespace
