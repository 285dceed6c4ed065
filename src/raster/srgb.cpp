#include "raster/srgb.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace patchscan::raster {

double SrgbFromLinear(double v) {
  v = std::clamp(v, 0.0, 1.0);
  return v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1.0 / 2.4) - 0.055;
}

double LinearFromSrgb(double e) {
  e = std::clamp(e, 0.0, 1.0);
  return e <= 0.04045 ? e / 12.92 : std::pow((e + 0.055) / 1.055, 2.4);
}

namespace {

constexpr int kTableSteps = 65535;
using Codes = std::array<std::uint8_t, kTableSteps + 1>;  // per linear step, its 8-bit code

// Code of table step i: round(255 SrgbFromLinear(i / kTableSteps)), the definition.
int CodeOfStep(int i) {
  return static_cast<int>(std::lround(255.0 * SrgbFromLinear(static_cast<double>(i) / kTableSteps)));
}

// The table holds 256 runs of equal codes: each run's first step is found near where the
// inverse puts it (LinearFromSrgb of the code's lower rounding bound) and confirmed by the
// definition on either side, about a thousand powers instead of one per step (65536, half
// the instructions of a small render).
const Codes& Table() {
  static const auto table = [] {
    Codes t{};
    int first = 0;  // first step of the current code's run
    for (int code = 1; code <= 255; ++code) {
      int i = static_cast<int>(std::ceil(LinearFromSrgb((code - 0.5) / 255.0) * kTableSteps));
      i = std::clamp(i, first, kTableSteps + 1);
      while (i > first && CodeOfStep(i - 1) >= code) --i;
      while (i <= kTableSteps && CodeOfStep(i) < code) ++i;
      std::fill(t.begin() + first, t.begin() + i, static_cast<std::uint8_t>(code - 1));
      first = i;
    }
    std::fill(t.begin() + first, t.end(), std::uint8_t{255});
    return t;
  }();
  return table;
}

std::uint8_t CodeIn(const Codes& table, float v) {
  const float c = std::clamp(v, 0.0f, 1.0f);  // NaN: clamp keeps it, the cast below maps it to 0
  const int i = std::isnan(c) ? 0 : static_cast<int>(c * static_cast<float>(kTableSteps) + 0.5f);
  return table[static_cast<std::size_t>(i)];
}

void StraightSrgba8(const Codes& table, const float* c, float a, std::uint8_t out[4]) {
  const float alpha = std::isnan(a) ? 0.0f : std::clamp(a, 0.0f, 1.0f);
  out[3] = static_cast<std::uint8_t>(alpha * 255.0f + 0.5f);
  if (out[3] == 0) {
    out[0] = out[1] = out[2] = 0;
  } else if (alpha == 1.0f) {  // most pixels: x / 1 is x
    for (int k = 0; k < 3; ++k) out[k] = CodeIn(table, c[k]);
  } else {
    for (int k = 0; k < 3; ++k) out[k] = CodeIn(table, c[k] / alpha);
  }
}

}  // namespace

std::uint8_t SrgbCode(float v) { return CodeIn(Table(), v); }

void StraightSrgba8(const float* c, float a, std::uint8_t out[4]) { StraightSrgba8(Table(), c, a, out); }

void StraightSrgba8Row(const float* pixels, int n, std::ptrdiff_t stride, std::uint8_t* out) {
  const Codes& table = Table();
  for (int x = 0; x < n; ++x, pixels += stride, out += 4) StraightSrgba8(table, pixels, pixels[3], out);
}

}  // namespace patchscan::raster
