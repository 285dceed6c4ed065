// patchscan-imageio.so: every call patchscan makes into OpenImageIO (raster/image_io.h says
// why it is a module of its own). Built against nothing of patchscan but that header.
// Imath before OpenImageIO: its texture.h declares a placeholder Imath::V3f otherwise.
#include <Imath/ImathVec.h>

#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/imageio.h>
#include <OpenImageIO/texture.h>

#include <algorithm>
#include <cstring>

#include "raster/image_io.h"

namespace patchscan::raster::imageio {
namespace {

OIIO::TypeDesc Oiio(PixelType type) {
  switch (type) {
    case PixelType::kUint8: return OIIO::TypeDesc::UINT8;
    case PixelType::kUint16: return OIIO::TypeDesc::UINT16;
    case PixelType::kHalf: return OIIO::TypeDesc::HALF;
    case PixelType::kFloat: break;
  }
  return OIIO::TypeDesc::FLOAT;
}

FileSpec FromOiio(const OIIO::ImageSpec& s) {
  FileSpec f;
  f.width = s.width;
  f.height = s.height;
  f.depth = s.depth;
  f.channels = s.nchannels;
  f.x = s.x;
  f.y = s.y;
  f.fullWidth = s.full_width;
  f.fullHeight = s.full_height;
  f.channelNames = s.channelnames;
  f.alphaChannel = s.alpha_channel;
  f.zChannel = s.z_channel;
  f.colorSpace = s.get_string_attribute("oiio:ColorSpace");
  f.unassociatedAlpha = s.get_int_attribute("oiio:UnassociatedAlpha", 0) != 0;
  f.compression = s.get_string_attribute("compression");
  for (const OIIO::ParamValue& p : s.extra_attribs)
    if (p.type() == OIIO::TypeMatrix) {
      std::array<float, 16> m;
      std::memcpy(m.data(), p.data(), sizeof m);
      f.matrices.emplace_back(p.name().string(), m);
    }
  return f;
}

OIIO::ImageSpec ToOiio(const FileSpec& f, PixelType type) {
  OIIO::ImageSpec s(f.width, f.height, f.channels, Oiio(type));
  s.alpha_channel = f.alphaChannel;
  s.z_channel = f.zChannel;
  if (!f.channelNames.empty()) s.channelnames = f.channelNames;
  if (f.fullWidth > 0) {
    s.x = f.x;
    s.y = f.y;
    s.full_x = s.full_y = 0;
    s.full_width = f.fullWidth;
    s.full_height = f.fullHeight;
  }
  if (!f.colorSpace.empty()) s.attribute("oiio:ColorSpace", f.colorSpace);
  if (!f.compression.empty()) s.attribute("compression", f.compression);
  for (const auto& [name, m] : f.matrices) s.attribute(name, OIIO::TypeMatrix, m.data());
  return s;
}

class OiioOutput final : public Output {
 public:
  explicit OiioOutput(std::unique_ptr<OIIO::ImageOutput> out) : out_(std::move(out)) {}
  ~OiioOutput() override {
    if (!closed_) out_->close();
  }
  bool WriteRow(int y, PixelType type, const void* row, std::size_t pixelBytes) override {
    return out_->write_scanline(y, 0, Oiio(type), row, static_cast<OIIO::stride_t>(pixelBytes));
  }
  bool Close() override {
    closed_ = true;
    return out_->close();
  }
  std::string Error() override { return out_->geterror(); }

 private:
  std::unique_ptr<OIIO::ImageOutput> out_;
  bool closed_ = false;
};

class OiioTexture final : public Texture {
 public:
  explicit OiioTexture(const std::string& path) : system_(OIIO::TextureSystem::create(/*shared=*/false)), name_(path) {
    options_.swrap = options_.twrap = OIIO::TextureOpt::WrapPeriodic;
  }
  ~OiioTexture() override { OIIO::TextureSystem::destroy(system_); }
  OiioTexture(const OiioTexture&) = delete;
  OiioTexture& operator=(const OiioTexture&) = delete;

  bool Open() {
    handle_ = system_->get_texture_handle(name_, system_->get_perthread_info());
    int channels = 0;
    if (!handle_ || !system_->get_texture_info(name_, 0, OIIO::ustring("channels"), OIIO::TypeDesc::INT, &channels))
      return false;
    channels_ = std::clamp(channels, 1, 3);
    return true;
  }
  bool Lookup(float s, float t, float dsdx, float dtdx, float dsdy, float dtdy, float* rgb) override {
    // Each thread its own per-thread record of the texture system (OpenImageIO keeps one per thread).
    return system_->texture(handle_, system_->get_perthread_info(), options_, s, t, dsdx, dtdx, dsdy, dtdy, channels_,
                            rgb);
  }
  bool LookupGradient(float s, float t, float dsdx, float dtdx, float dsdy, float dtdy, float* value, float* dds,
                      float* ddt) override {
    return system_->texture(handle_, system_->get_perthread_info(), options_, s, t, dsdx, dtdx, dsdy, dtdy, 1, value,
                            dds, ddt);
  }
  bool Environment(const float* r, const float* drdx, const float* drdy, float* rgb) override {
    return system_->environment(handle_, system_->get_perthread_info(), options_, Imath::V3f(r[0], r[1], r[2]),
                                Imath::V3f(drdx[0], drdx[1], drdx[2]), Imath::V3f(drdy[0], drdy[1], drdy[2]), channels_,
                                rgb);
  }
  int Channels() const override { return channels_; }
  std::string Error() override { return system_->geterror(); }

 private:
  OIIO::TextureSystem* system_;
  OIIO::ustring name_;
  OIIO::TextureSystem::TextureHandle* handle_ = nullptr;
  OIIO::TextureOpt options_;
  int channels_ = 3;
};

class OiioLibrary final : public Library {
  // maketx's work in `mode`: a tiled, MIP-mapped TIFF of `input` (read as floats) at `output`.
  static std::optional<std::string> MakeTexture(OIIO::ImageBufAlgo::MakeTextureMode mode, const std::string& input,
                                                const std::string& output) {
    OIIO::ImageBuf in(input);
    if (!in.read(0, 0, true, OIIO::TypeDesc::FLOAT)) return in.geterror();
    OIIO::ImageSpec config;
    config.attribute("maketx:fileformatname", "tiff");
    if (!OIIO::ImageBufAlgo::make_texture(mode, in, output, config)) return OIIO::geterror();
    return std::nullopt;
  }

 public:
  std::variant<std::unique_ptr<Output>, std::string> Create(const std::string& format, const std::string& file,
                                                            const FileSpec& spec, PixelType type) const override {
    auto out = OIIO::ImageOutput::create(format);
    if (!out) return OIIO::geterror();
    if (!out->open(file, ToOiio(spec, type))) return out->geterror();
    return std::unique_ptr<Output>(std::make_unique<OiioOutput>(std::move(out)));
  }

  std::variant<Image, std::string> Read(const std::string& path, int channels, bool unassociatedAlpha) const override {
    OIIO::ImageSpec config;
    if (unassociatedAlpha) config.attribute("oiio:UnassociatedAlpha", 1);
    auto in = OIIO::ImageInput::open(path, &config);
    if (!in) return OIIO::geterror();
    Image image;
    image.spec = FromOiio(in->spec());
    const int n = channels == kAllChannels ? image.spec.channels : std::min(channels, image.spec.channels);
    if (n <= 0 || image.spec.width <= 0 || image.spec.height <= 0 || image.spec.depth != 1) return image;
    image.pixels.resize(static_cast<std::size_t>(image.spec.width) * static_cast<std::size_t>(image.spec.height) *
                        static_cast<std::size_t>(n));
    if (!in->read_image(0, 0, 0, n, OIIO::TypeDesc::FLOAT, image.pixels.data())) return in->geterror();
    return image;
  }

  std::optional<std::string> MakeShadowTexture(const std::string& input, const std::string& output) const override {
    return MakeTexture(OIIO::ImageBufAlgo::MakeTxShadow, input, output);
  }
  std::optional<std::string> MakeLatLongTexture(const std::string& input, const std::string& output) const override {
    return MakeTexture(OIIO::ImageBufAlgo::MakeTxEnvLatl, input, output);
  }

  std::variant<std::unique_ptr<Texture>, std::string> OpenTexture(const std::string& path) const override {
    auto texture = std::make_unique<OiioTexture>(path);
    if (!texture->Open()) return texture->Error();
    return std::unique_ptr<Texture>(std::move(texture));
  }
};

}  // namespace
}  // namespace patchscan::raster::imageio

extern "C" __attribute__((visibility("default"))) const patchscan::raster::imageio::Library* patchscan_imageio_library(
    const char* interface) {
  static const patchscan::raster::imageio::OiioLibrary library;
  return std::strcmp(interface, PATCHSCAN_IMAGEIO_INTERFACE) == 0 ? &library : nullptr;
}
