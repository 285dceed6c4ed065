#include "xscan/overlay.h"

#include <algorithm>
#include <cmath>

namespace patchscan {

TraceStyle StyleOf(TraceKind kind) {
  switch (kind) {
    case TraceKind::EdgeTracker: return {0.05f, 0.35f, 1.0f, false};        // blue
    case TraceKind::SilhouetteTracker: return {1.0f, 0.1f, 0.05f, false};   // red
    case TraceKind::Maximum: return {1.0f, 0.85f, 0.0f, true};              // yellow
    case TraceKind::Saddle: return {0.9f, 0.1f, 0.9f, true};                // magenta
    case TraceKind::Fold: return {0.0f, 0.75f, 0.15f, true};                // green
    case TraceKind::Birth: return {1.0f, 0.55f, 0.55f, true};               // pink
    case TraceKind::Death: return {0.0f, 0.0f, 0.0f, true};                 // black
    case TraceKind::Repair: return {1.0f, 0.5f, 0.0f, true};                // orange
    case TraceKind::Failure: return {0.0f, 0.9f, 0.9f, true};               // cyan
  }
  return {1, 1, 1, false};
}

TrackerOverlay::TrackerOverlay(raster::RowSink& next, int width, int height)
    : next_(next), width_(width), height_(height), delay_(static_cast<int>(std::ceil(kTraceRingPx)) + 1) {}

void TrackerOverlay::Mark(TraceKind kind, double x, double y) {
  if (!std::isfinite(x) || !std::isfinite(y)) return;
  if (x < -kTraceRingPx - 1 || y < -kTraceRingPx - 1 || x > width_ + kTraceRingPx + 1 ||
      y > height_ + kTraceRingPx + 1)
    return;
  marks_.push_back({kind, x, y});
}

void TrackerOverlay::Draw(int row, std::vector<float>& pixels) const {
  auto put = [&](int px, const TraceStyle& st) {
    if (px < 0 || px >= width_) return;
    float* p = &pixels[static_cast<size_t>(px) * raster::kChannels];
    p[0] = st.r, p[1] = st.g, p[2] = st.b, p[3] = 1.0f;
  };
  // Dots first, then rings over them.
  for (int pass = 0; pass < 2; ++pass)
    for (const Pending& m : marks_) {
      const TraceStyle st = StyleOf(m.kind);
      if (st.ring != (pass == 1)) continue;
      if (!st.ring) {
        if (static_cast<int>(std::floor(m.y)) == row) put(static_cast<int>(std::floor(m.x)), st);
        continue;
      }
      // A ring: pixel centres between kTraceRingPx - 1 and kTraceRingPx from the mark.
      const double dy = row + 0.5 - m.y;
      if (std::abs(dy) > kTraceRingPx) continue;
      for (int px = static_cast<int>(std::floor(m.x - kTraceRingPx)); px <= m.x + kTraceRingPx; ++px) {
        const double d = std::hypot(px + 0.5 - m.x, dy);
        if (d <= kTraceRingPx && d >= kTraceRingPx - 1.0) put(px, st);
      }
    }
}

bool TrackerOverlay::Flush(int upTo) {
  while (!held_.empty() && held_.front().first < upTo) {
    auto& [row, pixels] = held_.front();
    Draw(row, pixels);
    if (!next_.WriteRow(row, pixels.data())) return false;
    flushed_ = row + 1;
    held_.pop_front();
    // Marks wholly above the next row to pass on are done.
    std::erase_if(marks_, [&](const Pending& m) { return m.y + kTraceRingPx + 1 < flushed_; });
  }
  return true;
}

bool TrackerOverlay::WriteRow(int y, const float* pixels) {
  held_.emplace_back(y, std::vector<float>(pixels, pixels + static_cast<size_t>(width_) * raster::kChannels));
  // Rows more than the delay above this one can no longer receive marks.
  return Flush(y - delay_ + 1);
}

bool TrackerOverlay::Finish() { return Flush(height_); }

}  // namespace patchscan
