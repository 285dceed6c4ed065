// What the tests that render through the library need: the back end's settings as every
// render starts from them, and a sink that keeps the rows.
#pragma once

#include <vector>

#include "raster/scanline_renderer.h"
#include "render/load.h"

namespace patchscan::test {

// The settings every render through the library starts from (render/load.h).
using render::SettingsFor;

// Keeps every channel of every row a render writes.
class KeepRows final : public raster::RowSink {
 public:
  explicit KeepRows(int width) : width_(width) {}
  bool WriteRow(int, const float* pixels) override {
    rows.insert(rows.end(), pixels, pixels + static_cast<std::size_t>(width_) * raster::kChannels);
    return true;
  }
  // Channel c of pixel (x, y).
  float At(int x, int y, int c) const {
    return rows[(static_cast<std::size_t>(y) * width_ + x) * raster::kChannels + c];
  }
  std::vector<float> rows;

 private:
  int width_;
};

}  // namespace patchscan::test
