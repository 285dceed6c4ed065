#include "render/crop.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace patchscan::render {

PixelWindow CropPixels(const Vec4& ndc, int width, int height) {
  auto at = [](double f, int n) { return std::clamp(static_cast<int>(std::ceil(f * n)), 0, n); };
  return {at(ndc[0], width), at(ndc[2], height), at(ndc[1], width), at(ndc[3], height)};
}

std::optional<Vec4> ParseCrop(const std::string& text) {
  Vec4 w;
  char tail = 0;
  if (std::sscanf(text.c_str(), "%lf,%lf,%lf,%lf%c", &w[0], &w[1], &w[2], &w[3], &tail) != 4) return std::nullopt;
  if (!(0.0 <= w[0] && w[0] < w[1] && w[1] <= 1.0 && 0.0 <= w[2] && w[2] < w[3] && w[3] <= 1.0)) return std::nullopt;
  return w;
}

}  // namespace patchscan::render
