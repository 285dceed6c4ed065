// OpenImageIO, loaded on first use. Debian's OpenImageIO links some 260 shared libraries
// (video codecs, GDAL, OpenCV, DICOM...): loading them costs 0.2 s and 130 MB resident before
// any work, which a run that prints its version, writes a PNG (raster/png_encoder.h) or
// reads a scene without textures never needs. So every call into OpenImageIO lives in a
// module, patchscan-imageio.so (image_io_module.cpp), that Library() loads the first time a
// run writes another format, reads an image or a shadow map, makes a shadow texture or
// looks up a texture. The interface holds plain types only, and the module and its loader
// are built from this header alone: a module built from another version of it is refused.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <variant>
#include <vector>

namespace patchscan::raster::imageio {

enum class PixelType { kUint8, kUint16, kHalf, kFloat };

// An image file's description: the parts of OpenImageIO's ImageSpec that patchscan reads
// and writes.
struct FileSpec {
  int width = 0, height = 0, channels = 0;
  int depth = 1;                       // > 1: a volume (read only)
  int x = 0, y = 0;                    // the data window's corner in the display window
  int fullWidth = 0, fullHeight = 0;   // the display window at (0, 0); 0: the data window
  std::vector<std::string> channelNames;  // empty: OpenImageIO's defaults (R G B A)
  int alphaChannel = -1, zChannel = -1;
  std::string colorSpace;                // "oiio:ColorSpace": "sRGB", "Linear"
  bool unassociatedAlpha = false;        // "oiio:UnassociatedAlpha": colour not premultiplied
  std::string compression;               // "compression" ("zip", "zip:9", "piz"...); "": the format's default
  // 4x4 float matrices by name, as the file stores them (OpenImageIO's and RenderMan's
  // convention: for row vectors).
  std::vector<std::pair<std::string, std::array<float, 16>>> matrices;
};

// A file being written, row by row in order (rows of the data window, in frame coordinates).
class Output {
 public:
  virtual ~Output() = default;
  // One row of `spec.channels` values per pixel, given as `type` (kUint8 or kFloat), the
  // pixels `pixelBytes` apart (the rest of a pixel's values not written).
  virtual bool WriteRow(int y, PixelType type, const void* row, std::size_t pixelBytes) = 0;
  virtual bool Close() = 0;
  virtual std::string Error() = 0;  // why the last call failed
};

// A mipmapped, filtered texture (OpenImageIO's TextureSystem, one private system each).
class Texture {
 public:
  virtual ~Texture() = default;
  // The first min(channels, 3) channels at (s, t), t down the image, wrapping periodically,
  // filtered over the footprint d(s, t)/dx, d(s, t)/dy. Safe from several threads at once.
  virtual bool Lookup(float s, float t, float dsdx, float dtdx, float dsdy, float dtdy, float* rgb) = 0;
  // The first channel at (s, t), filtered over the same footprint, and its derivatives in
  // s and t (OpenImageIO's dresultds, dresultdt: of the filtered value).
  virtual bool LookupGradient(float s, float t, float dsdx, float dtdx, float dsdy, float dtdy, float* value,
                              float* dds, float* ddt) = 0;
  // An environment map's first min(channels, 3) channels in world direction r, filtered over
  // the directions' change per pixel drdx, drdy (OpenImageIO's environment(): a lat-long map
  // with +y up and longitude 0 along +z, as OpenEXR lays them out).
  virtual bool Environment(const float* r, const float* drdx, const float* drdy, float* rgb) = 0;
  virtual int Channels() const = 0;  // 1 to 3
  virtual std::string Error() = 0;
};

struct Image {
  FileSpec spec;
  std::vector<float> pixels;  // the channels read, per pixel, rows top first
};

class Library {
 public:
  virtual ~Library() = default;
  // A writer of `file` in the format `format` names (an extension or a format name), with
  // `spec`'s size, channels, windows and attributes, stored as `type`. OpenImageIO's
  // message when it fails.
  virtual std::variant<std::unique_ptr<Output>, std::string> Create(const std::string& format, const std::string& file,
                                                                    const FileSpec& spec, PixelType type) const = 0;
  // The description of `path`'s first image and its first `channels` channels as floats
  // (kAllChannels: every one; 0: the description alone). `unassociatedAlpha`: colour as
  // stored, not premultiplied by alpha.
  static constexpr int kAllChannels = -1;
  virtual std::variant<Image, std::string> Read(const std::string& path, int channels, bool unassociatedAlpha) const = 0;
  // MakeShadow (maketx's shadow mode): a tiled, mipmapped float TIFF of the depth map `input`.
  virtual std::optional<std::string> MakeShadowTexture(const std::string& input, const std::string& output) const = 0;
  // MakeLatLongEnvironment (maketx's --envlatl): a tiled, mipmapped TIFF of the lat-long
  // image `input` that environment lookups filter across its seam and poles.
  virtual std::optional<std::string> MakeLatLongTexture(const std::string& input, const std::string& output) const = 0;
  virtual std::variant<std::unique_ptr<Texture>, std::string> OpenTexture(const std::string& path) const = 0;
};

// The library, loaded on the first call (from any thread; once): the module beside an
// installed patchscan (bin/../lib/patchscan), then in the installation's library directory,
// then in the build tree. The message naming the places tried when none loads.
std::variant<const Library*, std::string> Get();

// Whether the module has been loaded in this process (a run that needed no image reading or
// non-PNG writing never loads it).
bool Loaded();

}  // namespace patchscan::raster::imageio

// The module's one entry point: the library when `interface` is the hash of this header the
// module was built with, else null.
extern "C" const patchscan::raster::imageio::Library* patchscan_imageio_library(const char* interface);
