#include "raster/scanline_renderer.h"
#include "raster/work_arena.h"

#include <algorithm>
#include <limits>
#include <array>
#include <chrono>
#include <cmath>
#include <memory>

#include <oneapi/tbb/info.h>
#include <oneapi/tbb/task_arena.h>
#include <oneapi/tbb/task_group.h>

#include "raster/batched_rows.h"
#include "raster/pixel_shading.h"
#include "raster/row_geometry.h"
#include "raster/triangle_store.h"

namespace patchscan::raster {
namespace {

using detail::FragmentGeometry;
using detail::PixelRow;
using detail::ShadePixel;
using detail::TriangleGeometry;

// The pixel rows, for either geometry, in three stages: each row's sample rows resolved
// (in order: the scan and the active triangles move down the image), its pixels shaded
// (any row, on any thread), and the row handed to the sink (in order). Resolving and
// handing over stay on the calling thread (a source or sink may be bound to it, as MPI's
// are); with threads, each row is shaded as a task while the next rows are resolved, a few
// rows in flight, so memory stays O(width x threads).
template <class Geometry>
std::optional<Counters> RenderRows(Geometry& geo, const RenderSettings& s, const Lattice& lat,
                                      int layers, Counters& stats, RowSink& sink, BackEndTimes* times) {
  const int threads = s.threads > 1 ? std::min(s.threads, tbb::info::default_concurrency()) : 1;
  // Each thread's shading seconds in a slot of its own (its index in the arena, sized
  // below), so no two threads write one; the serial parts' on the calling thread.
  BackEndTimes timed;
  timed.shading.assign(1, 0.0);
  using Clock = std::chrono::steady_clock;
  auto since = [](Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); };
  // Rows in flight a thread: with two, the threads ran out of rows to shade while the
  // calling thread resolved and handed over (4096x3072 θ teapot at two threads 3 % slower).
  constexpr int kRowsInFlightPerThread = 4;
  const int inFlight = threads > 1 ? kRowsInFlightPerThread * threads : 1;
  // One row more than may be in flight: the row being resolved reads the one above it.
  std::vector<PixelRow<Geometry>> ring(static_cast<size_t>(inFlight + 1));
  for (auto& pr : ring) {
    pr.samples.assign(static_cast<size_t>(s.aa), std::vector<Sample>(static_cast<size_t>(lat.nx) * layers));
    pr.refs = geo.MakeRows();
    pr.pixels.resize(static_cast<size_t>(s.width) * kChannels);
  }
  Counters shaded;           // the rows' shading counts, added up in row order
  int written = 0;           // rows handed to the sink: every row above is done with
  bool stopped = false;      // the sink or the geometry failed
  int next = 0;              // the next pixel row to resolve
  std::size_t resolved = 0;  // rows resolved: the next one goes to ring[resolved % size]
  const PixelRow<Geometry>* above = nullptr;  // the row resolved last, if it was the one above

  // Resolves the next pixel row this render owns; null when none is left or it stopped.
  auto resolve = [&]() -> PixelRow<Geometry>* {
    while (next < s.height && s.ownsRow && !s.ownsRow(next)) ++next, above = nullptr;
    if (next >= s.height || stopped) return nullptr;
    PixelRow<Geometry>& pr = ring[resolved++ % ring.size()];
    pr.py = next++;
    pr.j0 = lat.FirstOfPixel(pr.py);
    pr.refs.j0 = pr.j0;
    pr.stats = Counters();
    geo.BeginPixelRow(pr.j0, lat.FirstOfPixel(written));
    for (int r = 0; r < s.aa; ++r) {
      if (r == 0 && above && s.aa > 1) {
        // The shared edge row, resolved with the row above (which may still be shading).
        pr.samples[0] = above->samples[static_cast<size_t>(s.aa - 1)];
        geo.CopySampleRow(above->refs, s.aa - 1, pr.refs, 0);
        continue;
      }
      std::fill(pr.samples[r].begin(), pr.samples[r].end(), kNoSample);
      geo.ScanRow(pr.j0 + r, r, lat.At(pr.j0 + r), pr.samples[r].data(), pr.refs);
    }
    above = &pr;
    return &pr;
  };
  auto timedResolve = [&] {
    const auto t0 = Clock::now();
    PixelRow<Geometry>* pr = resolve();
    timed.resolve += since(t0);
    return pr;
  };
  auto shade = [&](PixelRow<Geometry>& pr) {
    const auto t0 = Clock::now();
    for (int px = 0; px < s.width; ++px) ShadePixel(geo, s, lat, layers, pr, px);
    const int slot = threads > 1 ? tbb::this_task_arena::current_thread_index() : 0;
    if (slot >= 0 && static_cast<std::size_t>(slot) < timed.shading.size())
      timed.shading[static_cast<std::size_t>(slot)] += since(t0);
  };
  auto emit = [&](PixelRow<Geometry>& pr) {
    const auto t0 = Clock::now();
    shaded.Merge(pr.stats);
    // Rows still in flight when the render stopped are dropped.
    if (stopped || geo.Failed() || !sink.WriteRow(pr.py, pr.pixels.data())) stopped = true;
    written = pr.py + 1;
    timed.handOver += since(t0);
  };

  if (threads <= 1) {
    while (PixelRow<Geometry>* pr = timedResolve()) {
      shade(*pr);
      emit(*pr);
    }
  } else {
    const std::shared_ptr<tbb::task_arena> shared = WorkArena(threads);
    tbb::task_arena& arena = *shared;
    timed.shading.assign(static_cast<std::size_t>(arena.max_concurrency()), 0.0);
    std::vector<tbb::task_group> shading(ring.size());  // per ring slot, its row's task
    std::size_t oldest = 0;                             // rows handed over: the oldest in flight
    // Waits for the oldest row in flight (running other rows' tasks meanwhile) and hands it over.
    auto finishOldest = [&] {
      const std::size_t k = oldest++ % ring.size();
      arena.execute([&] { shading[k].wait(); });
      emit(ring[k]);
    };
    try {
      while (PixelRow<Geometry>* pr = timedResolve()) {
        const std::size_t k = (resolved - 1) % ring.size();
        arena.execute([&] { shading[k].run([&shade, pr] { shade(*pr); }); });
        while (resolved - oldest >= static_cast<std::size_t>(inFlight)) finishOldest();
      }
      while (oldest < resolved) finishOldest();
    } catch (...) {
      CancelAndWait(arena, shading);  // no task may outlive the rows it shades
      throw;
    }
  }
  if (times) *times = std::move(timed);
  if (stopped) return std::nullopt;
  stats.Merge(shaded);
  return stats;
}

}  // namespace

bool RenderSettings::AnyTransparency() const {
  if (opacity < 1.0 || material.opacity < 1.0) return true;
  for (const Material& m : materials)
    if (m.opacity < 1.0) return true;
  return false;
}

int RenderSettings::Layers() const {
  return AnyTransparency() ? kMaxLayers : depthFilter == DepthFilter::Midpoint ? 3 : 1;
}

std::optional<Counters> RenderMesh(const TriangleMesh& mesh, const RenderSettings& s,
                                      RowSink& sink, BackEndTimes* times) {
  Counters stats;
  const Lattice lat(s);
  const int layers = s.Layers();
  TriangleGeometry geo(mesh, s, lat, layers, stats);
  // On threads, every row ours: rows resolved on every thread, in batches.
  if (s.threads > 1 && !s.ownsRow) return detail::RenderBatches(geo, s, lat, layers, stats, sink, times);
  return RenderRows(geo, s, lat, layers, stats, sink, times);
}

std::optional<Counters> RenderFragments(FragmentSource& source, const RenderSettings& s,
                                           RowSink& sink, BackEndTimes* times) {
  Counters stats;
  const Lattice lat(s);
  const int layers = s.Layers();
  FragmentGeometry geo(source, s, lat, layers, stats);
  source.BeginRows(SampleColumns{lat.offset, lat.spacing, lat.nx}, lat.At(0), lat.spacing, lat.ny,
                   KeptDepths{s.hither, geo.DepthDecides() ? layers : 0});
  // A source scanning in batches, on threads, every row ours: rows resolved on every thread.
  if (source.ScansInBatches() && s.threads > 1 && !s.ownsRow)
    return detail::RenderBatches(geo, s, lat, layers, stats, sink, times);
  return RenderRows(geo, s, lat, layers, stats, sink, times);
}

}  // namespace patchscan::raster
