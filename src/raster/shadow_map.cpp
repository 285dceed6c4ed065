#include "raster/shadow_map.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <system_error>

#include "raster/image_io.h"

namespace patchscan::raster {
namespace {

// OpenImageIO keeps matrices as RenderMan does, for row vectors: the transpose of ours.
bool ReadMatrix(const imageio::FileSpec& spec, const char* name, Mat4* out) {
  for (const auto& [key, m] : spec.matrices)
    if (key == name) {
      for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) (*out)(j, i) = m[static_cast<std::size_t>(4 * i + j)];
      return true;
    }
  return false;
}

bool HasMatrices(const imageio::FileSpec& spec, ShadowCamera* camera) {
  return ReadMatrix(spec, "worldtocamera", &camera->worldToCamera) &&
         ReadMatrix(spec, "worldtoscreen", &camera->worldToScreen);
}

}  // namespace

std::variant<std::unique_ptr<ShadowMap>, std::string> ShadowMap::Load(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) return path + ": no such file";
  const auto library = imageio::Get();
  if (const auto* why = std::get_if<std::string>(&library)) return path + ": " + *why;
  // The description first: the size is checked before the texels are read.
  auto header = std::get<const imageio::Library*>(library)->Read(path, 0, false);
  if (const auto* why = std::get_if<std::string>(&header)) return path + ": cannot read the shadow map: " + *why;
  const imageio::FileSpec& spec = std::get<imageio::Image>(header).spec;
  ShadowCamera camera;
  if (!HasMatrices(spec, &camera)) return path + ": not a shadow map (no worldtocamera and worldtoscreen matrices)";
  if (spec.width <= 0 || spec.height <= 0 || static_cast<long long>(spec.width) * spec.height > (1LL << 28))
    return path + ": a shadow map of " + std::to_string(spec.width) + "x" + std::to_string(spec.height) + " texels is not supported";
  auto image = std::get<const imageio::Library*>(library)->Read(path, 1, false);
  if (const auto* why = std::get_if<std::string>(&image)) return path + ": cannot read the shadow map: " + *why;
  return std::make_unique<ShadowMap>(spec.width, spec.height, std::move(std::get<imageio::Image>(image).pixels), camera);
}

std::optional<std::string> MakeShadowTexture(const std::string& input, const std::string& output) {
  std::error_code ec;
  if (!std::filesystem::exists(input, ec)) return input + ": no such file";
  const auto library = imageio::Get();
  if (const auto* why = std::get_if<std::string>(&library)) return input + ": " + *why;
  auto header = std::get<const imageio::Library*>(library)->Read(input, 0, false);
  if (const auto* why = std::get_if<std::string>(&header)) return input + ": cannot read the depth map: " + *why;
  ShadowCamera unused;
  if (!HasMatrices(std::get<imageio::Image>(header).spec, &unused))
    return input + ": not a depth map (no worldtocamera and worldtoscreen matrices)";
  if (auto why = std::get<const imageio::Library*>(library)->MakeShadowTexture(input, output))
    return output + ": cannot make the shadow texture: " + *why;
  return std::nullopt;
}

ShadowMap::ShadowMap(int width, int height, std::vector<float> depth, const ShadowCamera& camera)
    : width_(width), height_(height), depth_(std::move(depth)), camera_(camera) {}

bool ShadowMap::Holds(const Vec3& p) const {
  const Vec4 s = camera_.worldToScreen * p.homogeneous();
  if (!(s.w() > 0.0) || !((camera_.worldToCamera * p.homogeneous()).z() > 0.0)) return false;
  return std::abs(s.x() / s.w()) <= 1.0 && std::abs(s.y() / s.w()) <= 1.0;
}

double ShadowMap::Visibility(const Vec3& p, double bias, double blur, int samples) const {
  const Vec4 s = camera_.worldToScreen * p.homogeneous();
  const double z = (camera_.worldToCamera * p.homogeneous()).z();
  if (!(s.w() > 0.0) || !(z > 0.0)) return 1.0;
  // Texel coordinates (continuous, texel centres at half-integers), y down.
  const double tx = (s.x() / s.w() + 1.0) * 0.5 * width_, ty = (1.0 - s.y() / s.w()) * 0.5 * height_;
  const double half = 0.5 * std::max(blur * width_, 1.0);
  const int n = std::max(samples, 1);
  int lit = 0, total = 0;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      // A regular grid over the window (deterministic: the same pixels every render).
      const double x = tx - half + (i + 0.5) * (2.0 * half / n), y = ty - half + (j + 0.5) * (2.0 * half / n);
      ++total;
      // Outside the map (compared before the conversion to int, which a far point would overflow).
      if (!(x >= 0.0 && y >= 0.0 && x < width_ && y < height_)) {
        ++lit;
        continue;
      }
      const int ix = static_cast<int>(x), iy = static_cast<int>(y);
      lit += z - bias <= depth_[static_cast<std::size_t>(iy) * static_cast<std::size_t>(width_) + static_cast<std::size_t>(ix)];
    }
  return static_cast<double>(lit) / total;
}

}  // namespace patchscan::raster
