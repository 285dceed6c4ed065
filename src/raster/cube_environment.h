// RenderMan's MakeCubeFaceEnvironment: six images of the surroundings, each seen from the
// cube's centre along one axis, made into an environment texture. OpenImageIO 2.4's
// environment() looks up lat-long maps only, so the faces are resampled into a lat-long
// image (OpenEXR's layout, as every environment lookup here reads it) and that is made into
// the texture as MakeLatLongEnvironment makes one.
//
// The faces' orientation is RenderMan's, which OpenGL's cube maps took over (the OpenGL 4.6
// specification, section 8.13, "Cube Map Texture Selection", table 8.19): for a direction d
// whose largest component is the major axis m, face +x has s = -d.z / |m|, t = -d.y / |m|;
// -x: s = d.z, t = -d.y; +y: s = d.x, t = d.z; -y: s = d.x, t = -d.z; +z: s = d.x, t = -d.y;
// -z: s = -d.x, t = -d.y, each from -1 (left, top) to 1 (right, bottom) across a face of
// 90 degrees. These are the views of a camera at the centre (RenderMan's left-handed camera
// space) looking along each axis with +y up, and along +y with -z up, along -y with +z up. A
// field of view wider than 90 degrees lets the faces overlap: the image then spans
// tan(fov / 2) in s and t.
#pragma once

#include <array>
#include <optional>
#include <string>
#include <vector>

#include "raster/image_io.h"

namespace patchscan::raster {

// The faces in RenderMan's order: px, nx, py, ny, pz, nz.
using CubeFaceImages = std::array<imageio::Image, 6>;

// The lat-long image (width x height texels, rows top first, +y up, longitude pi at the left
// edge and 0 along +z) of `faces` whose field of view is `fovDeg` (90 or more), with
// `channels` (1 to 3) channels: each texel the mean of 2 x 2 bilinear samples of the face its
// directions fall in (a face of fewer channels gives its first one to every channel).
std::vector<float> LatLongOfCubeFaces(const CubeFaceImages& faces, double fovDeg, int width, int height,
                                      int channels);

// MakeCubeFaceEnvironment: the environment texture (a tiled, MIP-mapped lat-long TIFF, four
// times as wide as the widest face and half as high) of the six face images `inputs`
// (px, nx, py, ny, pz, nz) rendered with a `fovDeg` field of view, written to `output`; the
// message when that fails.
std::optional<std::string> MakeCubeFaceEnvironment(const std::array<std::string, 6>& inputs, double fovDeg,
                                                   const std::string& output);

}  // namespace patchscan::raster
