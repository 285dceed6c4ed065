#include "raster/texture.h"

#include <filesystem>

#include "raster/image_io.h"

namespace patchscan::raster {

struct ImageTexture::Impl {
  std::unique_ptr<imageio::Texture> texture;  // OpenImageIO's TextureSystem, in its module
};

ImageTexture::ImageTexture(std::string path) : path_(std::move(path)) {}
ImageTexture::~ImageTexture() = default;

bool ImageTexture::Open() {
  std::call_once(opened_, [&] {
    // First use: OpenImageIO's module, a private texture system and its handle to the file.
    auto fail = [&](const std::string& why) {
      std::lock_guard lock(errorMutex_);
      error_ = path_ + ": cannot read texture: " + why;
      failed_ = true;
    };
    const auto library = imageio::Get();
    if (const auto* why = std::get_if<std::string>(&library)) return fail(*why);
    auto texture = std::get<const imageio::Library*>(library)->OpenTexture(path_);
    if (const auto* why = std::get_if<std::string>(&texture)) return fail(*why);
    auto impl = std::make_unique<Impl>();
    impl->texture = std::move(std::get<std::unique_ptr<imageio::Texture>>(texture));
    impl_ = std::move(impl);
  });
  return !failed_;
}

void ImageTexture::Failed() {
  std::lock_guard lock(errorMutex_);
  if (!failed_) error_ = path_ + ": texture lookup failed: " + impl_->texture->Error();
  failed_ = true;
}

std::optional<Eigen::Vector3d> ImageTexture::Lookup(const Vec2& uv, const Vec2& duvdx, const Vec2& duvdy) {
  if (failed_ || !Open()) return std::nullopt;
  ++nLookups_;
  float rgb[3] = {0, 0, 0};
  if (!impl_->texture->Lookup(static_cast<float>(uv.x()), static_cast<float>(uv.y()), static_cast<float>(duvdx.x()),
                              static_cast<float>(duvdx.y()), static_cast<float>(duvdy.x()),
                              static_cast<float>(duvdy.y()), rgb)) {
    Failed();
    return std::nullopt;
  }
  if (impl_->texture->Channels() == 1) rgb[1] = rgb[2] = rgb[0];
  return Eigen::Vector3d(rgb[0], rgb[1], rgb[2]);
}

std::optional<ImageTexture::Height> ImageTexture::LookupHeight(const Vec2& uv, const Vec2& duvdx,
                                                               const Vec2& duvdy) {
  if (failed_ || !Open()) return std::nullopt;
  ++nLookups_;
  float value = 0, dds = 0, ddt = 0;
  if (!impl_->texture->LookupGradient(static_cast<float>(uv.x()), static_cast<float>(uv.y()),
                                      static_cast<float>(duvdx.x()), static_cast<float>(duvdx.y()),
                                      static_cast<float>(duvdy.x()), static_cast<float>(duvdy.y()), &value, &dds,
                                      &ddt)) {
    Failed();
    return std::nullopt;
  }
  return Height{value, Vec2(dds, ddt)};
}

std::optional<Eigen::Vector3d> ImageTexture::LookupEnvironment(const Vec3& r, const Vec3& drdx, const Vec3& drdy) {
  if (failed_ || !Open()) return std::nullopt;
  ++nLookups_;
  const auto f = [](const Vec3& v) { return Eigen::Vector3f(v.cast<float>()); };
  const Eigen::Vector3f fr = f(r), fx = f(drdx), fy = f(drdy);
  float rgb[3] = {0, 0, 0};
  if (!impl_->texture->Environment(fr.data(), fx.data(), fy.data(), rgb)) {
    Failed();
    return std::nullopt;
  }
  if (impl_->texture->Channels() == 1) rgb[1] = rgb[2] = rgb[0];
  return Eigen::Vector3d(rgb[0], rgb[1], rgb[2]);
}

std::optional<std::string> MakeLatLongEnvironment(const std::string& input, const std::string& output) {
  std::error_code ec;
  if (!std::filesystem::exists(input, ec)) return input + ": no such file";
  const auto library = imageio::Get();
  if (const auto* why = std::get_if<std::string>(&library)) return input + ": " + *why;
  if (auto why = std::get<const imageio::Library*>(library)->MakeLatLongTexture(input, output))
    return output + ": cannot make the environment texture: " + *why;
  return std::nullopt;
}

}  // namespace patchscan::raster
