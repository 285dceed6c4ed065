// The sRGB transfer function (IEC 61966-2-1) for 8-bit outputs: renders are linear, and
// an 8-bit file holds sRGB-encoded colour, as every viewer assumes (PNG's sRGB chunk,
// JPEG's JFIF). EXR and 16-bit TIFF stay linear.
#pragma once

#include <cstddef>
#include <cstdint>

namespace patchscan::raster {

// sRGB-encoded value of linear v in [0, 1] (clamped), exact; and back.
double SrgbFromLinear(double v);
double LinearFromSrgb(double e);

// The 8-bit code of linear v: round(255 SrgbFromLinear(v)), by a table of 65536 linear
// steps (a step moves the code by at most 0.05 near black, where sRGB is steepest).
// Thread-safe; the table is built once.
std::uint8_t SrgbCode(float v);

// Premultiplied linear colour c (3) and alpha a as straight 8-bit RGBA: the colour divided
// by alpha, sRGB-encoded; alpha linear. A pixel of alpha 0 is 0 0 0 0.
void StraightSrgba8(const float* c, float a, std::uint8_t out[4]);
// The same for a row of n pixels, each 4 floats (colour, alpha) of `stride` floats apart,
// into 4 n bytes.
void StraightSrgba8Row(const float* pixels, int n, std::ptrdiff_t stride, std::uint8_t* out);

}  // namespace patchscan::raster
