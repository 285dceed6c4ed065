#include "raster/cube_environment.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <numbers>

#include "core/vec.h"

namespace patchscan::raster {
namespace {

// The lat-long image is four face sides wide: at a face's centre a face texel spans 2 / side
// radians and a lat-long texel pi / (2 side), so it keeps a face's detail there (towards a
// face's corners, where face texels shrink to a third of that, the 2 x 2 samples a texel
// average it). Faces wider than this are sampled at this side, which bounds the lat-long
// image at 4096 x 2048 texels (100 MB of floats).
constexpr int kMaxFaceSide = 1024;

// Where direction d falls: its face (px, nx, py, ny, pz, nz) and the face's s, t in [-1, 1]
// for a 90-degree face (table 8.19 of the OpenGL 4.6 specification; see the header).
struct FacePoint {
  int face;
  double s, t;
};
FacePoint FaceOf(const Vec3& d) {
  const double ax = std::abs(d.x()), ay = std::abs(d.y()), az = std::abs(d.z());
  if (ax >= ay && ax >= az) return d.x() > 0 ? FacePoint{0, -d.z() / ax, -d.y() / ax} : FacePoint{1, d.z() / ax, -d.y() / ax};
  if (ay >= az) return d.y() > 0 ? FacePoint{2, d.x() / ay, d.z() / ay} : FacePoint{3, d.x() / ay, -d.z() / ay};
  return d.z() > 0 ? FacePoint{4, d.x() / az, -d.y() / az} : FacePoint{5, -d.x() / az, -d.y() / az};
}

// Channel c of `image` at (s, t) in [0, 1] (0: left, top), bilinear between texel centres,
// clamped to the face's edge texels.
float Bilinear(const imageio::Image& image, double s, double t, int c) {
  const int w = image.spec.width, h = image.spec.height, n = image.spec.channels;
  const int channel = n < 3 ? 0 : c;
  const double x = std::clamp(s * w - 0.5, 0.0, w - 1.0), y = std::clamp(t * h - 0.5, 0.0, h - 1.0);
  const int x0 = std::min(static_cast<int>(x), w - 1), y0 = std::min(static_cast<int>(y), h - 1);
  const int x1 = std::min(x0 + 1, w - 1), y1 = std::min(y0 + 1, h - 1);
  const double fx = x - x0, fy = y - y0;
  const auto at = [&](int i, int j) {
    return static_cast<double>(image.pixels[(static_cast<std::size_t>(j) * w + i) * n + channel]);
  };
  return static_cast<float>((1 - fy) * ((1 - fx) * at(x0, y0) + fx * at(x1, y0)) +
                            fy * ((1 - fx) * at(x0, y1) + fx * at(x1, y1)));
}

}  // namespace

std::vector<float> LatLongOfCubeFaces(const CubeFaceImages& faces, double fovDeg, int width, int height,
                                      int channels) {
  const double pi = std::numbers::pi, tanHalf = std::tan(fovDeg / 2 * pi / 180);
  std::vector<float> texels(static_cast<std::size_t>(width) * height * channels, 0.0f);
  constexpr int kSub = 2;  // samples per texel side
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      float* out = &texels[(static_cast<std::size_t>(y) * width + x) * channels];
      for (int j = 0; j < kSub; ++j)
        for (int i = 0; i < kSub; ++i) {
          const double lat = pi / 2 - pi * (y + (j + 0.5) / kSub) / height;
          const double lon = pi - 2 * pi * (x + (i + 0.5) / kSub) / width;
          const FacePoint f = FaceOf(Vec3(std::cos(lat) * std::sin(lon), std::sin(lat), std::cos(lat) * std::cos(lon)));
          const double s = 0.5 + 0.5 * f.s / tanHalf, t = 0.5 + 0.5 * f.t / tanHalf;
          for (int c = 0; c < channels; ++c) out[c] += Bilinear(faces[f.face], s, t, c) / (kSub * kSub);
        }
    }
  return texels;
}

std::optional<std::string> MakeCubeFaceEnvironment(const std::array<std::string, 6>& inputs, double fovDeg,
                                                   const std::string& output) {
  const auto library = imageio::Get();
  if (const auto* why = std::get_if<std::string>(&library)) return inputs[0] + ": " + *why;
  const imageio::Library& io = *std::get<const imageio::Library*>(library);
  CubeFaceImages faces;
  int side = 1, channels = 1;
  for (int k = 0; k < 6; ++k) {
    std::error_code ec;
    if (!std::filesystem::exists(inputs[k], ec)) return inputs[k] + ": no such file";
    auto header = io.Read(inputs[k], 0, false);
    if (const auto* why = std::get_if<std::string>(&header)) return inputs[k] + ": cannot read the face: " + *why;
    const imageio::FileSpec& spec = std::get<imageio::Image>(header).spec;
    if (spec.width <= 0 || spec.height <= 0 || spec.depth != 1 || spec.channels <= 0 ||
        static_cast<long long>(spec.width) * spec.height > (1LL << 28))
      return inputs[k] + ": a face of " + std::to_string(spec.width) + "x" + std::to_string(spec.height) +
             " texels is not supported";
    auto image = io.Read(inputs[k], 3, false);
    if (const auto* why = std::get_if<std::string>(&image)) return inputs[k] + ": cannot read the face: " + *why;
    faces[k] = std::move(std::get<imageio::Image>(image));
    side = std::max(side, std::min(std::max(spec.width, spec.height), kMaxFaceSide));
    if (faces[k].spec.channels >= 3) channels = 3;
  }
  const int width = 4 * side, height = 2 * side;
  const std::vector<float> texels = LatLongOfCubeFaces(faces, fovDeg, width, height, channels);

  // The lat-long image goes through a float OpenEXR file beside the output (maketx reads
  // files), removed whatever happens.
  const std::filesystem::path target(output);
  std::string tempName = ".";
  tempName += target.filename().string();
  tempName += ".faces-" + std::to_string(::getpid()) + ".exr";
  const std::filesystem::path temp = target.parent_path() / tempName;
  struct Remove {
    std::filesystem::path path;
    ~Remove() {
      std::error_code ec;
      std::filesystem::remove(path, ec);
    }
  } remove{temp};
  imageio::FileSpec spec;
  spec.width = width;
  spec.height = height;
  spec.channels = channels;
  auto created = io.Create("exr", temp.string(), spec, imageio::PixelType::kFloat);
  if (const auto* why = std::get_if<std::string>(&created)) return output + ": cannot make the environment texture: " + *why;
  imageio::Output& out = *std::get<std::unique_ptr<imageio::Output>>(created);
  const std::size_t pixelBytes = sizeof(float) * static_cast<std::size_t>(channels);
  for (int y = 0; y < height; ++y)
    if (!out.WriteRow(y, imageio::PixelType::kFloat, &texels[static_cast<std::size_t>(y) * width * channels], pixelBytes))
      return output + ": cannot make the environment texture: " + out.Error();
  if (!out.Close()) return output + ": cannot make the environment texture: " + out.Error();
  if (auto why = io.MakeLatLongTexture(temp.string(), output)) return output + ": cannot make the environment texture: " + *why;
  return std::nullopt;
}

}  // namespace patchscan::raster
