// Depth shadow maps (RenderMan Interface 3.2: the "zfile"/"shadow" displays, MakeShadow,
// and the shadow() lookup of the shadowspot and shadowdistant lights). A map is the depth
// of the nearest surface seen from the light, with the light camera's matrices stored as
// OpenImageIO's (and RenderMan's) "worldtocamera" and "worldtoscreen" attributes, so that
// a world point is found in it and compared: a point farther than the map's depth (less a
// bias) is in shadow. Lookups filter by percentage closer filtering (Reeves, Salesin and
// Cook 1987): the fraction of samples over a window around the point that it is in front
// of. Loaded whole: a map is one frame's depth.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "core/vec.h"

namespace patchscan::raster {

// RenderMan's matrices of a camera seen as a light's: world to camera space (z the
// distance along the view axis) and world to screen space (x, y in [-1, 1] over the
// image, y up; homogeneous), both acting on column vectors here.
struct ShadowCamera {
  Mat4 worldToCamera = Mat4::Identity();
  Mat4 worldToScreen = Mat4::Identity();
};

// MakeShadow: the shadow texture (a tiled, MIP-mapped float TIFF that keeps the matrices)
// of the depth map `input`, written to `output`; the message when that fails.
std::optional<std::string> MakeShadowTexture(const std::string& input, const std::string& output);

class ShadowMap {
 public:
  // Reads a depth map written by a "zfile"/"shadow" display, or the texture MakeShadow
  // made of one (its finest level): one float channel and both matrices. The message when
  // the file cannot be read or is not a shadow map.
  static std::variant<std::unique_ptr<ShadowMap>, std::string> Load(const std::string& path);
  ShadowMap(int width, int height, std::vector<float> depth, const ShadowCamera& camera);

  // The fraction of light that reaches world point p: the share of samples x samples
  // points spread over a window `blur` wide (a fraction of the map's width; at least a
  // texel) around p's place in the map whose depth is beyond p's less `bias` (world units).
  // Points outside the map, or behind the light, are lit. Allocation-free.
  double Visibility(const Vec3& p, double bias, double blur, int samples) const;

  // Whether p lies in the map's view: in front of the light, within its screen.
  bool Holds(const Vec3& p) const;

  int Width() const { return width_; }
  int Height() const { return height_; }

 private:
  int width_, height_;
  std::vector<float> depth_;
  ShadowCamera camera_;
};

}  // namespace patchscan::raster
