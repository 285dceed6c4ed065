#include "raster/batched_rows.h"

#include <oneapi/tbb/parallel_for.h>
#include <oneapi/tbb/task_arena.h>
#include <oneapi/tbb/task_group.h>

#include <algorithm>
#include <atomic>
#include <memory>
#include <chrono>

#include "raster/pixel_shading.h"
#include "raster/work_arena.h"

namespace patchscan::raster::detail {

template <class Geometry>
std::optional<Counters> RenderBatches(Geometry& geo, const RenderSettings& s, const Lattice& lat, int layers,
                                      Counters& stats, RowSink& sink, BackEndTimes* times) {
  using Clock = std::chrono::steady_clock;
  auto since = [](Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); };
  const std::shared_ptr<tbb::task_arena> shared = WorkArena(s.threads, /*callerWorks=*/true);
  tbb::task_arena& arena = *shared;
  BackEndTimes timed;
  timed.shading.assign(static_cast<std::size_t>(arena.max_concurrency()), 0.0);

  // Pixel row p's sample rows: FirstOfPixel(p) + r for r in [0, aa) (aa 1: the one), the
  // last shared with the row below (aa > 1). A shared row is resolved with the row above,
  // and copied into the row below as its first.
  const int lastR = s.aa > 1 ? s.aa - 1 : 0;
  const auto lastRow = [&](int p) { return lat.FirstOfPixel(p) + lastR; };
  // The batches: pixel rows up to one whose last sample row ends a batch.
  std::vector<int> ends;  // each batch's end (one past its last pixel row)
  for (int p = 0; p < s.height; ++p)
    if (p == s.height - 1 || geo.EndsBatch(lastRow(p))) ends.push_back(p + 1);
  int longest = 0;
  for (std::size_t b = 0, p0 = 0; b < ends.size(); p0 = static_cast<std::size_t>(ends[b++]))
    longest = std::max(longest, ends[b] - static_cast<int>(p0));
  // One batch, and the row above it (its shared edge row): a batch's rows are resolved
  // once the rows they replace are shaded, every thread shading meanwhile, so one batch's
  // last row shades while the next is scanned.
  std::vector<PixelRow<Geometry>> ring(static_cast<std::size_t>(longest + 1));
  for (auto& pr : ring) {
    pr.samples.assign(static_cast<size_t>(s.aa), std::vector<Sample>(static_cast<size_t>(lat.nx) * layers));
    pr.refs = geo.MakeRows();
    pr.pixels.resize(static_cast<size_t>(s.width) * kChannels);
  }
  std::vector<tbb::task_group> shading(ring.size());
  // Per pixel row of a batch, its sample rows (and shared edge row) not yet resolved.
  const auto pending = std::make_unique<std::atomic<int>[]>(static_cast<std::size_t>(longest));
  std::vector<Counters> rowStats;  // each sample row's resolve counts, in a batch
  Counters shaded;
  std::size_t made = 0, handed = 0;  // pixel rows resolved, and handed over
  bool stopped = false;
  const auto slot = [&](std::size_t k) -> PixelRow<Geometry>& { return ring[k % ring.size()]; };

  // Hands the oldest row over once shaded (running other tasks meanwhile).
  const auto finishOldest = [&] {
    PixelRow<Geometry>& pr = slot(handed);
    arena.execute([&] { shading[handed % ring.size()].wait(); });
    const auto t0 = Clock::now();
    shaded.Merge(pr.stats);
    if (stopped || geo.Failed() || !sink.WriteRow(pr.py, pr.pixels.data())) stopped = true;
    ++handed;
    timed.handOver += since(t0);
  };
  const auto shade = [&](PixelRow<Geometry>& pr) {
    const auto t0 = Clock::now();
    for (int px = 0; px < s.width; ++px) ShadePixel(geo, s, lat, layers, pr, px);
    const int k = tbb::this_task_arena::current_thread_index();
    if (k >= 0 && static_cast<std::size_t>(k) < timed.shading.size()) timed.shading[static_cast<std::size_t>(k)] += since(t0);
  };

  try {
    for (std::size_t b = 0, p0 = 0; b < ends.size() && !stopped && !geo.Failed(); p0 = static_cast<std::size_t>(ends[b++])) {
      const auto p1 = static_cast<std::size_t>(ends[b]), n = p1 - p0;
      while (made - handed + n > ring.size()) finishOldest();
      const auto t0 = Clock::now();
      for (std::size_t p = p0; p < p1; ++p) {
        PixelRow<Geometry>& pr = slot(made + p - p0);
        pr.py = static_cast<int>(p);
        pr.j0 = lat.FirstOfPixel(pr.py);
        pr.refs.j0 = pr.j0;
        pr.stats = Counters();
      }
      // What ended above the batch leaves the scan; what the rows still shading use stays.
      geo.BeginPixelRow(lat.FirstOfPixel(static_cast<int>(p0)), lat.FirstOfPixel(static_cast<int>(handed)));
      // The batch's sample rows: the first pixel row's first is the batch before's last.
      const int first = p0 > 0 && s.aa > 1 ? lat.FirstOfPixel(static_cast<int>(p0)) + 1 : lat.FirstOfPixel(static_cast<int>(p0));
      const int count = lastRow(static_cast<int>(p1) - 1) - first + 1;
      arena.execute([&] { geo.PrepareRows(first, count); });  // its parallel parts on these threads
      timed.resolve += since(t0);
      rowStats.assign(static_cast<std::size_t>(count), Counters());
      // A pixel row is shaded once its sample rows are resolved, as a task of the thread that
      // resolved the last of them (oneTBB runs a thread's newest task first: the row is
      // shaded while in that core's cache). The first pixel row's shared edge row, resolved
      // with the batch before, is copied now; the others' when the row above resolves it.
      const auto shadeRow = [&](std::size_t p) {
        PixelRow<Geometry>* pr = &slot(made + p - p0);
        shading[(made + p - p0) % ring.size()].run([&shade, pr] { shade(*pr); });
      };
      const auto copyEdge = [&](std::size_t p) {
        const PixelRow<Geometry>& above = slot(made + p - p0 - 1);
        PixelRow<Geometry>& pr = slot(made + p - p0);
        pr.samples[0] = above.samples[static_cast<size_t>(s.aa - 1)];
        geo.CopySampleRow(above.refs, s.aa - 1, pr.refs, 0);
      };
      const bool shared = s.aa > 1;
      for (std::size_t p = p0; p < p1; ++p)
        pending[p - p0] = shared ? s.aa : 1;  // aa 1: its one row; else aa - 1 and the edge row
      if (shared && p0 > 0) {
        copyEdge(p0);
        --pending[0];
      }
      const auto arrive = [&](std::size_t p) {
        if (pending[p - p0].fetch_sub(1, std::memory_order_acq_rel) == 1) shadeRow(p);
      };
      // Each sample row resolved into the pixel row it is the last of (or the first's first).
      const auto resolve = [&](int k) {
        const int j = first + k;
        const int p = s.aa == 1 ? j : std::max(0, (j - 1) / (s.aa - 1));
        PixelRow<Geometry>& pr = slot(made + static_cast<std::size_t>(p) - p0);
        const int r = j - pr.j0;
        std::fill(pr.samples[r].begin(), pr.samples[r].end(), kNoSample);
        geo.ScanPreparedRow(k, r, pr.samples[r].data(), pr.refs, rowStats[static_cast<std::size_t>(k)]);
        const auto pu = static_cast<std::size_t>(p);
        if (shared && r == s.aa - 1 && pu + 1 < p1) {
          copyEdge(pu + 1);  // before this row may be shaded: shading reads it too
          arrive(pu + 1);
        }
        arrive(pu);
      };
      arena.execute([&] { tbb::parallel_for(0, count, resolve); });
      const auto t1 = Clock::now();
      geo.FinishRows();
      for (const Counters& c : rowStats) stats.Merge(c);
      timed.resolve += since(t1);
      made += n;
    }
    while (handed < made) finishOldest();
  } catch (...) {
    CancelAndWait(arena, shading);  // no task may outlive the rows it shades
    throw;
  }
  if (times) *times = std::move(timed);
  if (stopped || geo.Failed() || made < static_cast<std::size_t>(s.height)) return std::nullopt;
  stats.Merge(shaded);
  return stats;
}

template std::optional<Counters> RenderBatches(FragmentGeometry&, const RenderSettings&, const Lattice&, int,
                                               Counters&, RowSink&, BackEndTimes*);
template std::optional<Counters> RenderBatches(TriangleGeometry&, const RenderSettings&, const Lattice&, int,
                                               Counters&, RowSink&, BackEndTimes*);

}  // namespace patchscan::raster::detail
