#include "raster/texture.h"

#include <OpenImageIO/texture.h>

namespace patchscan::raster {

struct ImageTexture::Impl {
  OIIO::TextureSystem* system = nullptr;
  OIIO::TextureSystem::TextureHandle* handle = nullptr;
  OIIO::TextureSystem::Perthread* thread = nullptr;
  OIIO::TextureOpt options;
  int channels = 3;
  ~Impl() {
    if (system) {
      if (thread) system->destroy_thread_info(thread);
      OIIO::TextureSystem::destroy(system);
    }
  }
};

ImageTexture::ImageTexture(std::string path) : path_(std::move(path)) {}
ImageTexture::~ImageTexture() = default;

std::optional<Eigen::Vector3d> ImageTexture::Lookup(const Vec2& uv, const Vec2& duvdx,
                                                    const Vec2& duvdy) {
  if (!error_.empty()) return std::nullopt;
  if (!impl_) {
    // First use: a private texture system, its handle to the file, and the file's channels.
    auto impl = std::make_unique<Impl>();
    impl->system = OIIO::TextureSystem::create(/*shared=*/false);
    impl->thread = impl->system->create_thread_info();
    const OIIO::ustring name(path_);
    impl->handle = impl->system->get_texture_handle(name, impl->thread);
    int channels = 0;
    if (!impl->handle || !impl->system->get_texture_info(name, 0, OIIO::ustring("channels"),
                                                         OIIO::TypeDesc::INT, &channels)) {
      error_ = path_ + ": cannot read texture: " + impl->system->geterror();
      return std::nullopt;
    }
    impl->channels = std::min(channels, 3);
    impl->options.swrap = impl->options.twrap = OIIO::TextureOpt::WrapPeriodic;
    impl_ = std::move(impl);
  }
  ++nLookups_;
  float rgb[3] = {0, 0, 0};
  if (!impl_->system->texture(impl_->handle, impl_->thread, impl_->options, static_cast<float>(uv.x()),
                              static_cast<float>(uv.y()), static_cast<float>(duvdx.x()),
                              static_cast<float>(duvdx.y()), static_cast<float>(duvdy.x()),
                              static_cast<float>(duvdy.y()), impl_->channels, rgb)) {
    error_ = path_ + ": texture lookup failed: " + impl_->system->geterror();
    return std::nullopt;
  }
  if (impl_->channels == 1) rgb[1] = rgb[2] = rgb[0];
  return Eigen::Vector3d(rgb[0], rgb[1], rgb[2]);
}

}  // namespace patchscan::raster
