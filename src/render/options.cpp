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
  // The exact mode's batches of rows (xscan/row_scan.h) are whole pixel rows, the last
  // sample row of each batch's last taking up what its X scans found (the same for any
  // number of threads or processes, so the image is). About kBatchSampleRows sample rows: a
  // batch is scanned between one fork and join of the threads, and a silhouette found
  // without a tracker is taken up at most that many rows later (it is found again on each
  // row meanwhile). 8 is under three pixel rows at aa 3, where a fork and join costs a few
  // microseconds against a row's scan of a tenth of a millisecond or more.
  // θ's surfaces that take the exact X scan take up on the next row (θ is split by
  // surfaces, never by rows).
  constexpr int kBatchSampleRows = 8;
  const int perPixel = aa == 1 ? 1 : aa - 1;  // new sample rows a pixel row (raster::Lattice)
  const int pixels = (kBatchSampleRows + perPixel - 1) / perPixel;
  if (o.mode == RenderMode::Exact) {
    xo.adoptRows = pixels * perPixel;
    // The last sample row of the first batch's last pixel row p = pixels - 1: aa 1, its
    // only one (p); else its bottom edge, (p + 1)(aa - 1).
    xo.adoptPhase = aa == 1 ? pixels - 1 : xo.adoptRows;
  }
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

int Cores() { return std::max(1, static_cast<int>(std::thread::hardware_concurrency())); }

int ThreadsFor(int threads) {
  return threads > 0 ? threads : Cores();
}

}  // namespace patchscan::render
