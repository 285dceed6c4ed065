#include "render/progress.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <ostream>
#include <string>

#include "render/interrupt.h"

namespace patchscan::render {
namespace {

double SecondsSinceEpoch() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

}  // namespace

ProgressSink::ProgressSink(raster::RowSink& next, int height, std::ostream& err, bool show)
    : next_(next), height_(height), err_(err), show_(show), start_(SecondsSinceEpoch()) {}

ProgressSink::~ProgressSink() {
  if (shown_) err_ << "\r" << std::string(72, ' ') << "\r" << std::flush;
}

void ProgressSink::Finish() {
  if (!show_) return;
  char line[96];
  std::snprintf(line, sizeof line, "\rrender: 100%% (%d/%d rows, %.1f s)%20s\n", rows_, height_,
                SecondsSinceEpoch() - start_, "");
  err_ << line << std::flush;
  shown_ = false;
}

bool ProgressSink::WriteRow(int y, const float* pixels) {
  if (gInterrupted) return false;
  // A few times a second: often enough to see it move, rarely enough to cost nothing.
  constexpr double kShowEverySec = 0.25;
  const double now = SecondsSinceEpoch();
  ++rows_;
  if (show_ && now - std::max(lastShown_, start_) > kShowEverySec) {
    lastShown_ = now;
    shown_ = true;
    // Time left: the rows left at the rate so far.
    const double elapsed = now - start_, left = elapsed * (height_ - rows_) / rows_;
    char line[96];
    std::snprintf(line, sizeof line, "\rrender: %3d%% (%d/%d rows, %.1f s, about %.1f s left)   ",
                  (100 * rows_) / height_, rows_, height_, elapsed, left);
    err_ << line << std::flush;
  }
  const double t0 = now;
  const bool ok = next_.WriteRow(y, pixels);
  outputSeconds_ += SecondsSinceEpoch() - t0;
  return ok;
}

}  // namespace patchscan::render
