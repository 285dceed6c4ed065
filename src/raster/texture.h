// An image texture read through OpenImageIO's TextureSystem (mipmapped, filtered over the
// footprint given by the screen derivatives of uv). Nothing is created and no file is
// opened until a visible sample first asks for a colour (Woo and Chall 1990 §5: lazy texture
// loading), so a texture on a hidden surface costs nothing.
#pragma once

#include <atomic>
#include <memory>
#include <mutex>
#include <optional>
#include <string>

#include "raster/mesh.h"

namespace patchscan::raster {

class ImageTexture {
 public:
  explicit ImageTexture(std::string path);
  ~ImageTexture();
  ImageTexture(const ImageTexture&) = delete;
  ImageTexture& operator=(const ImageTexture&) = delete;

  // RGB at (s, t) = uv (t = 0 at the image's top, as in RenderMan), filtered with the
  // derivatives of uv per pixel in x and y. nullopt if the texture cannot be read
  // (Error() says why). Safe to call from several threads at once.
  std::optional<Eigen::Vector3d> Lookup(const Vec2& uv, const Vec2& duvdx, const Vec2& duvdy);
  // A height field's first channel at (s, t) = uv, filtered over the same footprint as a
  // colour, with its derivatives in s and t (a bump map's B_s, B_t: Blinn 1978).
  struct Height {
    double value = 0.0;
    Vec2 gradient = Vec2::Zero();  // (dh/ds, dh/dt)
  };
  std::optional<Height> LookupHeight(const Vec2& uv, const Vec2& duvdx, const Vec2& duvdy);
  // An environment map's RGB in world direction r (any length), filtered over r's change
  // per pixel drdx, drdy (Blinn and Newell 1976; the layout is image_io.h's Environment).
  std::optional<Eigen::Vector3d> LookupEnvironment(const Vec3& r, const Vec3& drdx, const Vec3& drdy);

  // After the render (not while lookups run):
  bool Opened() const { return impl_ != nullptr; }
  long Lookups() const { return nLookups_; }
  const std::string& Error() const { return error_; }

 private:
  struct Impl;
  // Opens the texture (once, whichever thread asks first); false if it cannot be read.
  bool Open();
  // After a lookup that failed: records why (the first failure only) and stops further ones.
  void Failed();
  // Opens the texture if need be and makes one lookup, `call(texture)`, counted; false, with
  // the texture failed, when it cannot be read or the lookup fails.
  template <class Call>
  bool Looked(Call&& call);
  std::string path_, error_;
  std::unique_ptr<Impl> impl_;
  std::once_flag opened_;
  std::mutex errorMutex_;  // error_ is written by whichever lookup fails
  std::atomic<bool> failed_ = false;
  std::atomic<long> nLookups_ = 0;
};

// MakeLatLongEnvironment: the environment texture (tiled, MIP-mapped TIFF) of the lat-long
// image `input`, written to `output`; the message when that fails.
std::optional<std::string> MakeLatLongEnvironment(const std::string& input, const std::string& output);

}  // namespace patchscan::raster
