// The rows' way to the image, watched: a progress line on the log while rendering, the time
// the image writer takes, and the stop of an interrupted render (render/interrupt.h).
#pragma once

#include <iosfwd>

#include "raster/scanline_renderer.h"

namespace patchscan::render {

// Passes rows on (none once interrupted), timing how long the next sink (the image writer)
// takes; with `show`, a line on `log` a few times a second: the share of rows finished
// (scanned, composited and shaded), the seconds since the start and an estimate of those left.
class ProgressSink final : public raster::RowSink {
 public:
  ProgressSink(raster::RowSink& next, int height, std::ostream& log, bool show);
  // Clears the line, if an interrupted render left one.
  ~ProgressSink() override;
  bool WriteRow(int y, const float* pixels) override;
  // After the last row: the line at 100 % with the total time, ended, so what follows
  // starts on a line of its own.
  void Finish();
  double OutputSeconds() const { return outputSeconds_; }

 private:
  raster::RowSink& next_;
  int height_, rows_ = 0;
  std::ostream& err_;
  bool show_, shown_ = false;
  double outputSeconds_ = 0.0;
  double lastShown_ = -1.0;  // seconds since start when the percentage was last shown
  double start_;
};

}  // namespace patchscan::render
