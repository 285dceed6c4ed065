#include "raster/texture.h"

#include <OpenImageIO/texture.h>

namespace patchscan::raster {

struct ImageTexture::Impl {
  OIIO::TextureSystem* system = nullptr;
  OIIO::TextureSystem::TextureHandle* handle = nullptr;
  OIIO::TextureOpt options;
  int channels = 3;
  ~Impl() {
    if (system) OIIO::TextureSystem::destroy(system);
  }
};

ImageTexture::ImageTexture(std::string path) : path_(std::move(path)) {}
ImageTexture::~ImageTexture() = default;

bool ImageTexture::Open() {
  std::call_once(opened_, [&] {
    // First use: a private texture system, its handle to the file, and the file's channels.
    auto impl = std::make_unique<Impl>();
    impl->system = OIIO::TextureSystem::create(/*shared=*/false);
    const OIIO::ustring name(path_);
    impl->handle = impl->system->get_texture_handle(name, impl->system->get_perthread_info());
    int channels = 0;
    if (!impl->handle || !impl->system->get_texture_info(name, 0, OIIO::ustring("channels"),
                                                         OIIO::TypeDesc::INT, &channels)) {
      std::lock_guard lock(errorMutex_);
      error_ = path_ + ": cannot read texture: " + impl->system->geterror();
      failed_ = true;
      return;
    }
    impl->channels = std::min(channels, 3);
    impl->options.swrap = impl->options.twrap = OIIO::TextureOpt::WrapPeriodic;
    impl_ = std::move(impl);
  });
  return !failed_;
}

std::optional<Eigen::Vector3d> ImageTexture::Lookup(const Vec2& uv, const Vec2& duvdx,
                                                    const Vec2& duvdy) {
  if (failed_ || !Open()) return std::nullopt;
  ++nLookups_;
  float rgb[3] = {0, 0, 0};
  // Each thread its own per-thread record of the texture system (OpenImageIO keeps one per
  // thread).
  if (!impl_->system->texture(impl_->handle, impl_->system->get_perthread_info(), impl_->options,
                              static_cast<float>(uv.x()), static_cast<float>(uv.y()), static_cast<float>(duvdx.x()),
                              static_cast<float>(duvdx.y()), static_cast<float>(duvdy.x()),
                              static_cast<float>(duvdy.y()), impl_->channels, rgb)) {
    std::lock_guard lock(errorMutex_);
    if (!failed_) error_ = path_ + ": texture lookup failed: " + impl_->system->geterror();
    failed_ = true;
    return std::nullopt;
  }
  if (impl_->channels == 1) rgb[1] = rgb[2] = rgb[0];
  return Eigen::Vector3d(rgb[0], rgb[1], rgb[2]);
}

}  // namespace patchscan::raster
