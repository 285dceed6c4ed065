#include "raster/image_writer.h"

#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <limits>
#include <system_error>

#include "core/ascii.h"
#include "core/check.h"
#include "raster/image_io.h"
#include "raster/png_encoder.h"
#include "raster/srgb.h"

namespace patchscan::raster {

struct ImageWriter::Impl {
  std::unique_ptr<imageio::Output> out;  // every format but PNG (OpenImageIO's module)
  std::FILE* file = nullptr;               // PNG: our own encoder, deflating on threads
  std::unique_ptr<PngEncoder> png;
  std::filesystem::path target, temp;
  int width = 0, channels = 4;
  int y0 = 0;  // the first row's y in the frame (OpenImageIO takes rows by it)
  bool srgb8 = false;              // JPEG: the row converted to sRGB bytes first
  std::vector<std::uint8_t> bytes;  // that row
  std::vector<float> depth;         // a depth map's row (OpenDepthMap)
  bool committed = false;
  int nextRow = 0;  // rows come top to bottom, each once (RowSink's contract)
  // Until committed, the temporary file goes, also when Open fails after creating it.
  ~Impl() {
    if (committed) return;
    out.reset();  // closes it
    png.reset();
    if (file) std::fclose(file);
    std::error_code ec;
    if (!temp.empty()) std::filesystem::remove(temp, ec);
  }
};

ImageWriter::ImageWriter(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

ImageWriter::~ImageWriter() = default;

namespace {

std::string LowerExtension(const std::filesystem::path& path) { return AsciiLower(path.extension().string()); }

// Each format's default compression (image_writer.h).
std::string DefaultCompression(const std::string& ext) {
  if (ext == ".png") return "rle";
  if (ext == ".jpg" || ext == ".jpeg") return "jpeg:98";
  return "zip";
}

// A compression as CheckFormat takes it, split: the method and its level (-1: none given).
struct Compression {
  std::string method;
  int level = -1;
};

// `text` parsed for the format of extension `ext`; the message when it is not one of the
// format's (image_writer.h lists them). "": the format's default.
std::variant<Compression, std::string> ParseCompression(const std::string& ext, const std::string& text) {
  Compression c;
  const std::size_t colon = text.find(':');
  c.method = text.substr(0, colon);
  if (colon != std::string::npos) {
    const std::string digits = text.substr(colon + 1);
    if (digits.empty() || digits.size() > 3 || digits.find_first_not_of("0123456789") != std::string::npos)
      return "compression '" + text + "': the level after ':' must be a whole number";
    c.level = std::stoi(digits);
  }
  auto oneOf = [&](std::initializer_list<const char*> methods) {
    for (const char* m : methods)
      if (c.method == m) return true;
    return false;
  };
  auto levelIn = [&](int lo, int hi) { return c.level < 0 || (c.level >= lo && c.level <= hi); };
  if (ext == ".png") {
    if (c.method == "none" && c.level < 0) return Compression{"zip", 0};
    if (c.method == "zip" && levelIn(0, 9)) return Compression{"zip", c.level < 0 ? 6 : c.level};
    if (c.method == "rle" && c.level < 0) return Compression{"rle", 6};  // any level but 0 (stored)
    return "compression '" + text + "' is not one of PNG's: rle, zip:L (L 0-9; zip = zip:6), none";
  }
  if (ext == ".tif" || ext == ".tiff") {
    if ((c.method == "zip" && levelIn(1, 9)) || (oneOf({"lzw", "packbits", "none"}) && c.level < 0)) return c;
    return "compression '" + text + "' is not one of TIFF's: zip, zip:L (L 1-9), lzw, packbits, none";
  }
  if (ext == ".exr") {
    if ((oneOf({"dwaa", "dwab"}) && levelIn(1, 999)) ||
        (oneOf({"zip", "zips", "piz", "rle", "pxr24", "b44", "b44a", "none"}) && c.level < 0))
      return c;
    return "compression '" + text +
           "' is not one of OpenEXR's: zip, zips, piz, rle, pxr24, b44, b44a, dwaa[:L], dwab[:L], none";
  }
  if (c.method == "jpeg" && c.level >= 1 && c.level <= 100) return c;
  return "compression '" + text + "' is not one of JPEG's: jpeg:Q (Q the quality 1-100)";
}

}  // namespace

std::optional<std::string> ImageWriter::CheckFormat(const std::string& path, bool aovs, const std::string& compression) {
  const std::string ext = LowerExtension(path);
  if (ext.empty())
    return path + ": no extension: the image's format follows it (.png .tif .tiff .jpg .jpeg .exr)";
  if (ext != ".png" && ext != ".jpg" && ext != ".jpeg" && ext != ".tif" && ext != ".tiff" && ext != ".exr")
    return path + ": unknown image format '" + ext + "' (known: .png .tif .tiff .jpg .jpeg .exr)";
  if (aovs && ext != ".exr") return path + ": AOV channels need an .exr output";
  if (compression.empty()) return std::nullopt;
  const auto parsed = ParseCompression(ext, compression);
  if (const auto* why = std::get_if<std::string>(&parsed)) return path + ": " + *why;
  return std::nullopt;
}

std::variant<std::unique_ptr<ImageWriter>, std::string> ImageWriter::Open(const std::string& path,
                                                                          int width, int height,
                                                                          bool aovs, int threads,
                                                                          Window window,
                                                                          const std::string& compression) {
  auto impl = std::make_unique<Impl>();
  impl->target = path;
  if (auto why = CheckFormat(path, aovs, compression)) return *why;
  const std::string ext = LowerExtension(impl->target);
  const auto parsed = ParseCompression(ext, compression.empty() ? DefaultCompression(ext) : compression);
  const Compression& chosen = std::get<Compression>(parsed);
  imageio::PixelType type = imageio::PixelType::kHalf;  // .exr
  if (ext == ".png" || ext == ".jpg" || ext == ".jpeg") type = imageio::PixelType::kUint8;
  else if (ext == ".tif" || ext == ".tiff") type = imageio::PixelType::kUint16;
  impl->channels = (ext == ".jpg" || ext == ".jpeg") ? 3 : aovs ? kChannels : 4;  // JPEG: no alpha
  if (aovs) type = imageio::PixelType::kFloat;  // depth and ids need more than half precision
  impl->width = width;
  std::string tempName = ".";
  tempName += impl->target.stem().string();
  tempName += ".partial-" + std::to_string(::getpid()) + ext;
  impl->temp = impl->target.parent_path() / tempName;
  // The temporary file is created here for every format, so that a directory that cannot
  // be written is reported by the user's name for the file, not the temporary one.
  impl->file = std::fopen(impl->temp.c_str(), "wb");
  if (!impl->file) return path + ": cannot write: " + std::strerror(errno);
  if (ext == ".png") {
    impl->png = std::make_unique<PngEncoder>(impl->file, width, height, PngEncoder::Options{chosen.level, threads, chosen.method == "rle"});
    return std::unique_ptr<ImageWriter>(new ImageWriter(std::move(impl)));
  }
  std::fclose(impl->file);  // OpenImageIO opens it again by name
  impl->file = nullptr;
  const auto library = imageio::Get();
  if (const auto* why = std::get_if<std::string>(&library)) return path + ": " + *why;
  imageio::FileSpec spec;
  spec.width = width;
  spec.height = height;
  spec.channels = impl->channels;
  if (impl->channels >= 4) spec.alphaChannel = 3;
  if (window.frameWidth > 0) {
    spec.x = window.x;
    spec.y = window.y;
    spec.fullWidth = window.frameWidth;
    spec.fullHeight = window.frameHeight;
    impl->y0 = window.y;
  }
  // 8-bit files hold sRGB-encoded colour; EXR and 16-bit TIFF linear (raster/srgb.h).
  impl->srgb8 = type == imageio::PixelType::kUint8;
  spec.colorSpace = impl->srgb8 ? "sRGB" : "Linear";
  if (impl->srgb8) impl->bytes.resize(static_cast<std::size_t>(width) * impl->channels);
  spec.compression = chosen.level >= 0 ? chosen.method + ":" + std::to_string(chosen.level) : chosen.method;
  if (aovs) {
    spec.channelNames = {"R", "G", "B", "A", "Z", "N.x", "N.y", "N.z", "u", "v", "id"};
    spec.zChannel = kChannelZ;
  }
  auto out = std::get<const imageio::Library*>(library)->Create(ext.substr(1), impl->temp.string(), spec, type);
  if (const auto* why = std::get_if<std::string>(&out)) return path + ": cannot write: " + *why;
  impl->out = std::move(std::get<std::unique_ptr<imageio::Output>>(out));
  return std::unique_ptr<ImageWriter>(new ImageWriter(std::move(impl)));
}

std::variant<std::unique_ptr<ImageWriter>, std::string> ImageWriter::OpenDepthMap(const std::string& path, int width,
                                                                                  int height, const ShadowCamera& camera) {
  auto impl = std::make_unique<Impl>();
  impl->target = path;
  impl->width = width;
  impl->channels = 1;
  impl->depth.resize(static_cast<std::size_t>(width));
  impl->temp = impl->target.parent_path() / ("." + impl->target.filename().string() + ".partial-" + std::to_string(::getpid()));
  impl->file = std::fopen(impl->temp.c_str(), "wb");
  if (!impl->file) return path + ": cannot write: " + std::strerror(errno);
  std::fclose(impl->file);
  impl->file = nullptr;
  const auto library = imageio::Get();
  if (const auto* why = std::get_if<std::string>(&library)) return path + ": " + *why;
  imageio::FileSpec spec;
  spec.width = width;
  spec.height = height;
  spec.channels = 1;
  spec.channelNames = {"Z"};
  spec.zChannel = 0;
  // As RenderMan keeps them, for row vectors: the transposes.
  for (const auto& [name, m] : {std::pair{"worldtocamera", &camera.worldToCamera}, std::pair{"worldtoscreen", &camera.worldToScreen}}) {
    std::array<float, 16> rows;
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 4; ++j) rows[static_cast<std::size_t>(4 * i + j)] = static_cast<float>((*m)(j, i));
    spec.matrices.emplace_back(name, rows);
  }
  auto out = std::get<const imageio::Library*>(library)->Create("tiff", impl->temp.string(), spec, imageio::PixelType::kFloat);
  if (const auto* why = std::get_if<std::string>(&out)) return path + ": cannot write: " + *why;
  impl->out = std::move(std::get<std::unique_ptr<imageio::Output>>(out));
  return std::unique_ptr<ImageWriter>(new ImageWriter(std::move(impl)));
}

bool ImageWriter::EncodesInParallel() const { return impl_->png != nullptr; }

bool ImageWriter::WriteRow(int y, const float* pixels) {
  PATCHSCAN_DCHECK(y == impl_->nextRow, "an image's rows written top to bottom, each once");
  ++impl_->nextRow;
  if (impl_->png) return impl_->png->WriteRow(pixels, kChannels);
  if (!impl_->depth.empty()) {  // a depth map: Z alone, no surface as the largest float
    for (int x = 0; x < impl_->width; ++x)
      impl_->depth[static_cast<std::size_t>(x)] =
          std::min(pixels[static_cast<std::size_t>(x) * kChannels + kChannelZ], std::numeric_limits<float>::max());
    return impl_->out->WriteRow(y, imageio::PixelType::kFloat, impl_->depth.data(), sizeof(float));
  }
  if (impl_->srgb8) {  // JPEG: no alpha, the colour over black as it is (premultiplied)
    for (int x = 0; x < impl_->width; ++x)
      for (int c = 0; c < impl_->channels; ++c)
        impl_->bytes[static_cast<std::size_t>(x * impl_->channels + c)] =
            SrgbCode(pixels[static_cast<std::size_t>(x) * kChannels + c]);
    return impl_->out->WriteRow(y + impl_->y0, imageio::PixelType::kUint8, impl_->bytes.data(), impl_->channels);
  }
  return impl_->out->WriteRow(y + impl_->y0, imageio::PixelType::kFloat, pixels, kChannels * sizeof(float));
}

std::variant<std::monostate, std::string> ImageWriter::Commit() {
  if (impl_->png) {
    const bool encoded = impl_->png->Finish();
    impl_->png.reset();
    const bool closed = std::fclose(impl_->file) == 0;
    impl_->file = nullptr;
    if (!encoded || !closed) return impl_->target.string() + ": writing the image failed";
  } else if (!impl_->out->Close()) {
    return impl_->target.string() + ": " + impl_->out->Error();
  }
  std::error_code ec;
  std::filesystem::rename(impl_->temp, impl_->target, ec);
  if (ec) return impl_->target.string() + ": cannot rename the finished image into place: " + ec.message();
  impl_->committed = true;
  return std::monostate{};
}

}  // namespace patchscan::raster
