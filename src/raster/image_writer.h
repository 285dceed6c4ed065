// Streams finished rows to an image file through OpenImageIO, all or nothing: rows go to a
// temporary file beside the target, which is renamed onto the target only by Commit().
// Destroying an uncommitted writer removes the temporary file.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <variant>

#include "raster/scanline_renderer.h"
#include "raster/shadow_map.h"

namespace patchscan::raster {

// Where an image lies in a larger frame (ImageWriter::Open).
struct ImageWindow {
  int x = 0, y = 0;                     // the image's top-left pixel in the frame
  int frameWidth = 0, frameHeight = 0;  // 0: the image is the frame
};

class ImageWriter final : public RowSink {
 public:
  // Opens the temporary file for `path`, with the format its extension names (.png, .tif,
  // .tiff, .jpg, .jpeg, .exr): RGBA (RGB for JPEG); with `aovs`, which only EXR takes, also
  // the channels Z (eye distance), N.x N.y N.z, u v and id. A message when that fails.
  // PNG is encoded by PngEncoder, deflating on `threads` threads (the same bytes for any).
  // An image that is a window of a larger frame (a crop) says where it lies in `window`:
  // EXR and TIFF record it (OpenEXR's data window in the display window); PNG and JPEG
  // hold the window alone.
  // `compression` as CheckFormat takes it ("": the format's default).
  using Window = ImageWindow;
  static std::variant<std::unique_ptr<ImageWriter>, std::string> Open(const std::string& path,
                                                                     int width, int height,
                                                                     bool aovs = false,
                                                                     int threads = 1,
                                                                     Window window = ImageWindow(),
                                                                     const std::string& compression = {});
  // A depth map (RenderMan's "zfile" and "shadow" displays): one float channel Z, the eye
  // distance along the view axis of the nearest surface (the largest float where none),
  // written as TIFF whatever `path`'s extension.
  // The light camera's matrices go with it (raster/shadow_map.h), so that it is a shadow map.
  static std::variant<std::unique_ptr<ImageWriter>, std::string> OpenDepthMap(const std::string& path, int width,
                                                                               int height, const ShadowCamera& camera);
  ~ImageWriter() override;
  // Whether `path` names a format Open takes (with `aovs`, an .exr), and `compression` is one
  // of that format's: the message if not. A refusal here is the user's choice; a failure of
  // Open after it is the file system's. Compression, by format (default first; kCompressionHelp):
  //   .png         rle (zlib's runs of a byte, the default: half zip:6's time, some 15 % more
  //                bytes), zip:L with L the zlib level 0 (stored) to 9 (zip = zip:6), none = zip:0
  //   .tif .tiff   zip (zip:L, L 1-9), lzw, packbits, none
  //   .exr         zip (16 rows a block), zips (one), piz, rle, pxr24, b44, b44a, dwaa, dwab
  //                (lossy, dwaa:L and dwab:L with L the quality), none
  //   .jpg .jpeg   jpeg:Q, Q the quality 1-100; default jpeg:98
  static std::optional<std::string> CheckFormat(const std::string& path, bool aovs = false,
                                                const std::string& compression = {});
  static constexpr const char* kCompressionHelp =
      "compression of the image file, by format (the first is the default): .png rle (zlib's runs), zip:L (zlib "
      "level L 0-9; zip = zip:6; none = zip:0); .tif/.tiff zip[:L], lzw, packbits, none; .exr zip (16 rows a block), zips (one row), piz, "
      "rle, pxr24, b44, b44a, dwaa[:L], dwab[:L] (lossy), none; .jpg/.jpeg jpeg:Q (quality 1-100; default 98, as OpenImageIO)";

  bool WriteRow(int y, const float* pixels) override;
  // Whether the format encodes on threads of its own (PNG): then a row costs the caller a
  // conversion to 8 bits only, and a writer thread in front of it would only add copies.
  bool EncodesInParallel() const;
  // Closes the file and renames it onto the target; the message on failure.
  std::variant<std::monostate, std::string> Commit();

 private:
  struct Impl;
  explicit ImageWriter(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace patchscan::raster
