// The back end's settings for rendering what `camera` sees at `aa`, as `patchscan render`
// sets them (default material and lights), for the tests that render through the library.
#pragma once

#include <vector>

#include "patch/camera.h"
#include "raster/scanline_renderer.h"

namespace patchscan::test {

inline raster::RenderSettings SettingsFor(const Camera& camera, int aa) {
  raster::RenderSettings s;
  s.width = camera.width;
  s.height = camera.height;
  s.aa = aa;
  s.hither = camera.hither;
  s.eye = EyePoint(camera);
  s.forward = ViewForward(camera);
  s.orthographic = camera.orthographic;
  return s;
}

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
