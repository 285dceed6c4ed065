#include "render/options.h"

#include <algorithm>
#include <cmath>
#include <thread>

namespace patchscan::render {

const char* ModeName(RenderMode mode) {
  switch (mode) {
    case RenderMode::Exact: return "exact";
    case RenderMode::Theta: return "theta";
    case RenderMode::Tess: return "tess";
  }
  return "?";
}

ExactScanOptions ScanOptionsFor(const RenderOptions& o, int aa) {
  ExactScanOptions xo;
  xo.extrapolate = !o.noExtrapolate;
  if (o.mode == RenderMode::Theta) {
    xo.thetaSteps = o.thetaSteps;
    // Sample rows are 1 / (aa - 1) pixels apart (aa 1: one per pixel). A slab one sample
    // row high would cost two lines' trackers and a zip for the one row of samples its own
    // chains give exactly: such a step takes chains on every row instead.
    const double spacing = aa == 1 ? 1.0 : 1.0 / (aa - 1);
    const int rows = o.yStep > 0.0 ? static_cast<int>(std::lround(o.yStep / spacing)) : 0;
    xo.slabRows = rows >= 2 ? rows : 0;
  }
  return xo;
}

int ThreadsFor(int threads) {
  return threads > 0 ? threads : std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
}

}  // namespace patchscan::render
