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

template <class Call>
bool ImageTexture::Looked(Call&& call) {
  if (failed_ || !Open()) return false;
  ++nLookups_;
  if (call(*impl_->texture)) return true;
  Failed();
  return false;
}

namespace {

// The RGB of a lookup's first channels: a one-channel texture is grey.
Eigen::Vector3d Colour(const float* rgb, int channels) {
  return channels == 1 ? Eigen::Vector3d::Constant(rgb[0]) : Eigen::Vector3d(rgb[0], rgb[1], rgb[2]);
}

}  // namespace

std::optional<Eigen::Vector3d> ImageTexture::Lookup(const Vec2& uv, const Vec2& duvdx, const Vec2& duvdy) {
  float rgb[3] = {0, 0, 0};
  const auto f = [](double v) { return static_cast<float>(v); };
  if (!Looked([&](imageio::Texture& t) {
        return t.Lookup(f(uv.x()), f(uv.y()), f(duvdx.x()), f(duvdx.y()), f(duvdy.x()), f(duvdy.y()), rgb);
      }))
    return std::nullopt;
  return Colour(rgb, impl_->texture->Channels());
}

std::optional<ImageTexture::Height> ImageTexture::LookupHeight(const Vec2& uv, const Vec2& duvdx,
                                                               const Vec2& duvdy) {
  float value = 0, dds = 0, ddt = 0;
  const auto f = [](double v) { return static_cast<float>(v); };
  if (!Looked([&](imageio::Texture& t) {
        return t.LookupGradient(f(uv.x()), f(uv.y()), f(duvdx.x()), f(duvdx.y()), f(duvdy.x()), f(duvdy.y()), &value,
                                &dds, &ddt);
      }))
    return std::nullopt;
  return Height{value, Vec2(dds, ddt)};
}

std::optional<Eigen::Vector3d> ImageTexture::LookupEnvironment(const Vec3& r, const Vec3& drdx, const Vec3& drdy) {
  float rgb[3] = {0, 0, 0};
  const Eigen::Vector3f fr = r.cast<float>(), fx = drdx.cast<float>(), fy = drdy.cast<float>();
  if (!Looked([&](imageio::Texture& t) { return t.Environment(fr.data(), fx.data(), fy.data(), rgb); }))
    return std::nullopt;
  return Colour(rgb, impl_->texture->Channels());
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
