// A crop window (RenderMan's CropWindow): the part of the frame an image holds.
#pragma once

#include <optional>
#include <string>

#include "core/vec.h"
#include "raster/scanline_renderer.h"

namespace patchscan::render {

// The pixels [x0, x1) x [y0, y1) of a frame.
struct PixelWindow {
  int x0, y0, x1, y1;
};

// The pixels of a width x height frame that a crop window in NDC (xmin, xmax, ymin, ymax;
// y down) covers: RenderMan's rule, the pixels from ceil(W xmin) to ceil(W xmax) - 1, so
// windows that share a side share no pixel and tile the frame.
PixelWindow CropPixels(const Vec4& ndc, int width, int height);

// "xmin,xmax,ymin,ymax" with 0 <= xmin < xmax <= 1 and the same for y; nullopt otherwise.
std::optional<Vec4> ParseCrop(const std::string& text);

// Passes on the window's part of each row, renumbered from the window's top.
class CropSink final : public raster::RowSink {
 public:
  CropSink(raster::RowSink& next, const PixelWindow& w) : next_(next), w_(w) {}
  bool WriteRow(int y, const float* pixels) override {
    if (y < w_.y0 || y >= w_.y1) return true;
    return next_.WriteRow(y - w_.y0, pixels + static_cast<std::size_t>(w_.x0) * raster::kChannels);
  }

 private:
  raster::RowSink& next_;
  PixelWindow w_;
};

}  // namespace patchscan::render
