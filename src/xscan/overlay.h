// `--overlay trackers`: the exact scan's trace drawn over the image as it streams out.
// Tracker positions are one-pixel dots (their paths, row after row), coloured by kind;
// events are rings. Rows are held back a few rows so that a ring drawn late still
// reaches the rows above its centre; memory is a few rows of the image width.
#pragma once

#include <array>
#include <deque>
#include <vector>

#include "raster/scanline_renderer.h"
#include "xscan/trace.h"

namespace patchscan {

// The colour of each mark kind (linear RGB), for the legend in --help.
struct TraceStyle {
  float r, g, b;
  bool ring;  // an event ring; otherwise a one-pixel dot
};
TraceStyle StyleOf(TraceKind kind);

// Radius of an event ring in pixels.
constexpr double kTraceRingPx = 3.0;

class TrackerOverlay final : public raster::RowSink, public TraceSink {
 public:
  TrackerOverlay(raster::RowSink& next, int width, int height);

  void Mark(TraceKind kind, double x, double y) override;
  bool WriteRow(int y, const float* pixels) override;
  // Passes on the rows still held back; call after the last row.
  bool Finish();

 private:
  struct Pending {
    TraceKind kind;
    double x, y;
  };
  void Draw(int row, std::vector<float>& pixels) const;
  bool Flush(int upTo);

  raster::RowSink& next_;
  int width_, height_;
  int delay_;
  std::deque<std::pair<int, std::vector<float>>> held_;  // rows not yet passed on
  std::vector<Pending> marks_;
  int flushed_ = 0;  // rows passed on
};

}  // namespace patchscan
