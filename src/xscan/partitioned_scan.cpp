#include "xscan/partitioned_scan.h"

#include <oneapi/tbb/parallel_for.h>
#include <oneapi/tbb/global_control.h>
#include <oneapi/tbb/info.h>
#include <oneapi/tbb/task_arena.h>


#include <algorithm>
#include <chrono>
#include <cmath>
#include <numeric>
#include <utility>

#include "raster/scanline_renderer.h"
#include "raster/triangle_store.h"
#include "raster/work_arena.h"
#include "xscan/row_ring.h"

namespace patchscan {

std::vector<std::vector<ScanEntry>> PartitionSurfaces(const std::vector<ScanEntry>& order, const Camera& camera,
                                                      int workers) {
  const auto n = static_cast<std::size_t>(std::max(workers, 1));
  // A surface's work: the pixels its screen box covers within the image (what its walks
  // and samples cost), plus its set-up (the maxima pre-pass and edge pieces, about as much
  // as a few hundred pixels of scanning).
  constexpr double kSetUpPixels = 256.0;
  const double imageArea = static_cast<double>(camera.width) * camera.height;
  std::vector<double> work(order.size());
  for (std::size_t k = 0; k < order.size(); ++k) work[k] = std::min(order[k].area, imageArea) + kSetUpPixels;
  std::vector<std::size_t> byWork(order.size());
  std::iota(byWork.begin(), byWork.end(), 0);
  std::stable_sort(byWork.begin(), byWork.end(), [&](std::size_t a, std::size_t b) { return work[a] > work[b]; });
  std::vector<double> load(n, 0.0);
  std::vector<std::vector<std::size_t>> picks(n);
  for (std::size_t k : byWork) {
    const auto w = static_cast<std::size_t>(std::min_element(load.begin(), load.end()) - load.begin());
    load[w] += work[k];
    picks[w].push_back(k);
  }
  std::vector<std::vector<ScanEntry>> shares(n);
  for (std::size_t w = 0; w < n; ++w) {
    std::sort(picks[w].begin(), picks[w].end());  // back into scan order
    for (std::size_t k : picks[w]) shares[w].push_back(order[k]);
  }
  return shares;
}

namespace {

double Now() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }

// One worker's share of a row, as its scan handed it over: fragments and triangles, each
// with the rank of its surface in the scan order (non-decreasing: a scan hands over its
// surfaces one after another, in that order).
class RowBuffer final : public raster::FragmentRow {
 public:
  struct BufferedFragment {
    std::uint32_t rank;
    int column;
    raster::Fragment f;
  };
  struct BufferedTriangle {
    std::uint32_t rank;
    raster::RasterVertex a, b, c;
    std::uint32_t surfaceId;
  };
  struct BufferedChord {
    std::uint32_t rank;
    raster::Chord chord;
  };
  explicit RowBuffer(const std::vector<std::uint32_t>& rank) : rank_(rank) {}
  void Clear() {
    fragments.clear();
    triangles.clear();
    chords.clear();
    depth.ClearRow();
  }
  // A chord is kept whole, its samples tested and made by the back end: testing its
  // columns here too would cost as much as the back end's own test, to save copying a few
  // hidden chords (of θ mode, which hands over nothing else to hide).
  void AddChord(const raster::Chord& c, const raster::SampleColumns&) override {
    chords.push_back({rank_[c.a().surfaceId], c});
  }
  void Add(int column, const raster::Fragment& f) override {
    if (depth.Hidden(column, f.w)) return;
    depth.Keep(column, f.w);
    fragments.push_back({rank_[f.surfaceId], column, f});
  }
  bool Hidden(int column, double w) const override { return depth.Hidden(column, w); }
  void AddTriangle(const raster::RasterVertex& a, const raster::RasterVertex& b, const raster::RasterVertex& c,
                   std::uint32_t surfaceId) override {
    triangles.push_back({rank_[surfaceId], a, b, c, surfaceId});
  }
  std::vector<BufferedFragment> fragments;
  std::vector<BufferedTriangle> triangles;
  std::vector<BufferedChord> chords;
  DepthFilter depth;
  bool scanned = true;  // the worker's ScanRow's answer for the row

 private:
  const std::vector<std::uint32_t>& rank_;
};

// Hands the buffers' entries of one kind to `take` in rank order: a k-way merge of lists
// that are each in rank order already (a surface belongs to one worker, so no two lists
// hold the same rank). `next` is scratch.
template <class Entries, class Take>
void MergeByRank(std::size_t nLists, Entries&& entries, std::vector<std::size_t>* next, Take&& take) {
  next->assign(nLists, 0);
  for (;;) {
    std::size_t best = nLists;
    std::uint32_t bestRank = 0;
    for (std::size_t w = 0; w < nLists; ++w) {
      const auto& list = entries(w);
      if ((*next)[w] < list.size() && (best == nLists || list[(*next)[w]].rank < bestRank)) {
        best = w;
        bestRank = list[(*next)[w]].rank;
      }
    }
    if (best == nLists) return;
    // Everything of that worker up to the next surface of another worker goes at once.
    const auto& list = entries(best);
    std::uint32_t limit = UINT32_MAX;
    for (std::size_t w = 0; w < nLists; ++w)
      if (w != best && (*next)[w] < entries(w).size()) limit = std::min(limit, entries(w)[(*next)[w]].rank);
    std::size_t& i = (*next)[best];
    for (; i < list.size() && list[i].rank < limit; ++i) take(list[i]);
  }
}

// Sample rows the scan-ahead may be in front of the back end: two pixel rows' worth of the
// render's supersampling grid (RowsAhead), at most those of the largest grid. A row held
// is every fragment of every layer of it (144 bytes each): 16 rows of a 16384-wide teapot
// were 60 MB, so the ring is sized by the grid in use, and memory stays O(width). A θ
// scan's rows hold chords, a few dozen a row: its ring holds two batches (kThetaBatch).
// The workers scan a pixel row's sample rows between one fork and join (a θ scan's, a
// batch), so each worker holds that many rows too.
constexpr int kMaxRowsAhead = 2 * raster::kMaxAa;
int RowsAhead(double dy) {
  const double perPixel = dy > 0.0 ? std::round(1.0 / dy) : 1.0;
  return static_cast<int>(std::clamp(2.0 * perPixel, 2.0, static_cast<double>(kMaxRowsAhead)));
}

}  // namespace

struct PartitionedScan::Worker {
  Worker(std::span<const Surface> surfaces, const Camera& camera, ExactScanOptions options,
         std::vector<ScanEntry> share, const std::vector<std::uint32_t>& rank)
      : rank(rank), scan(surfaces, camera, options, std::move(share)) {
    Batch(1);
  }
  // Buffers for a batch of n rows.
  void Batch(int n) {
    while (rows.size() < static_cast<std::size_t>(n)) rows.emplace_back(rank);
  }
  const std::vector<std::uint32_t>& rank;  // of every surface, for the buffers
  ExactScan scan;
  std::vector<RowBuffer> rows;  // a batch of rows, scanned between one fork and join
  double seconds = 0.0;  // spent scanning
};

PartitionedScan::PartitionedScan(std::span<const Surface> surfaces, const Camera& camera, ExactScanOptions options,
                                 int workers, int threads)
    : PartitionedScan(surfaces, camera, options, workers, threads, ScanOrder(surfaces, camera), std::nullopt) {}

PartitionedScan::PartitionedScan(std::span<const Surface> surfaces, const Camera& camera, ExactScanOptions options,
                                 int workers, int threads, std::vector<ScanEntry> share)
    : PartitionedScan(surfaces, camera, options, workers, threads, ScanOrder(surfaces, camera), std::move(share)) {}

PartitionedScan::PartitionedScan(std::span<const Surface> surfaces, const Camera& camera, ExactScanOptions options,
                                 int workers, int threads, const std::vector<ScanEntry>& order,
                                 std::optional<std::vector<ScanEntry>> share)
    : chords_(options.thetaSteps > 0) {
  rank_.assign(surfaces.size(), 0);
  for (std::size_t k = 0; k < order.size(); ++k) rank_[order[k].index] = static_cast<std::uint32_t>(k);
  for (std::vector<ScanEntry>& part : PartitionSurfaces(share ? *share : order, camera, workers))
    workers_.push_back(std::make_unique<Worker>(surfaces, camera, options, std::move(part), rank_));
  // More threads than the machine has cores would only queue (and oneTBB warns): the
  // arena is capped there; the partition, and so the image, follows `workers` alone.
  threads = std::min(threads, tbb::info::default_concurrency());
  // The render's threads (raster::WorkArena), shared with the back end's shading and the
  // PNG encoder's deflating, so a thread that has scanned its share of a row takes up a
  // row's shading instead of waiting idle.
  if (threads > 1) arena_ = raster::WorkArena(threads);
}

PartitionedScan::~PartitionedScan() {
  if (ahead_) ahead_->Stop();  // before the workers it scans with go
}

void PartitionedScan::KeepDepths(const raster::KeptDepths& kept, int columns) {
  for (auto& w : workers_)
    for (RowBuffer& row : w->rows) row.depth.Reset(kept, columns);
}

void PartitionedScan::BeginRows(const raster::SampleColumns& columns, double y0, double dy, int nRows,
                                const raster::KeptDepths& kept) {
  perPixel_ = static_cast<int>(std::max(1.0, std::round(1.0 / dy)));
  if (arena_ && !tracing_ && !ahead_) {
    batch_ = chords_ ? kThetaBatch : RowsAhead(dy) / 2;
    const int most = kReplayBatch + perPixel_ - 1;  // the most rows of a batch (EndsRowBlock)
    if (ScansInBatches()) {
      batchNext_.assign(static_cast<std::size_t>(most), {});
      for (auto& next : batchNext_) next.reserve(workers_.size());
      batchSeconds_.assign(static_cast<std::size_t>(most), 0.0);
    }
    for (auto& w : workers_) w->Batch(ScansInBatches() ? most : batch_);
  }
  KeepDepths(kept, columns.n);
  if (!arena_ || tracing_ || ahead_) return;
  aheadY0_ = y0;
  aheadDy_ = dy;
  aheadRows_ = nRows;
  columns_ = columns;
  kept_ = kept;
  aheadAsked_ = true;
}

void PartitionedScan::StartAhead() {
  aheadAsked_ = false;
  ahead_ = std::make_unique<RowRing>(std::max(RowsAhead(aheadDy_), 2 * batch_), kept_, columns_.n);
  ahead_->Start([this, columns = columns_, y0 = aheadY0_, dy = aheadDy_, nRows = aheadRows_] {
    for (int j = 0; j < nRows;) {
      const double y = raster::RowY(y0, dy, j);
      if (workers_.size() == 1) {
        if (!ahead_->Reserve(j + 1)) return;
        ahead_->Publish(j, Composite(y, columns, ahead_->Slot(j)));
        ++j;
        continue;
      }
      // A batch of rows between one fork and join.
      const int count = std::min(batch_, nRows - j);
      ScanRows(y0, dy, j, count, columns);
      for (int k = 0; k < count; ++k, ++j) {
        if (!ahead_->Reserve(j + 1)) return;
        ahead_->Publish(j, TimedMerge(k, columns, ahead_->Slot(j)));
      }
    }
  });
}

void PartitionedScan::PrepareRows(int first, int count) {
  batched_ = true;  // called in the back end's arena: the workers scan there
  ScanRows(aheadY0_, aheadDy_, first, count, columns_);
}

void PartitionedScan::PreparedTriangles(int k, raster::FragmentRow& out) { MergeTriangles(k, out, &next_); }

void PartitionedScan::MergeTriangles(int k, raster::FragmentRow& out, std::vector<std::size_t>* next) const {
  MergeByRank(workers_.size(),
              [&](std::size_t w) -> const auto& { return workers_[w]->rows[static_cast<std::size_t>(k)].triangles; }, next,
              [&](const RowBuffer::BufferedTriangle& e) { out.AddTriangle(e.a, e.b, e.c, e.surfaceId); });
}

bool PartitionedScan::ScanPreparedRow(int k, raster::FragmentRow& out) {
  const double t0 = Now();
  const bool ok = MergeRow(k, columns_, out, &batchNext_[static_cast<std::size_t>(k)], /*triangles=*/false);
  batchSeconds_[static_cast<std::size_t>(k)] += Now() - t0;
  return ok;
}

void PartitionedScan::FinishRows() {
  for (double& t : batchSeconds_) compositeSeconds_ += std::exchange(t, 0.0);
}

template <class F>
void PartitionedScan::ForEachWorker(F&& f) {
  auto timed = [&](Worker& w) {
    const double t0 = Now();
    f(w);
    w.seconds += Now() - t0;
  };
  if (!arena_ || workers_.size() == 1) {
    for (auto& w : workers_) timed(*w);
    return;
  }
  if (batched_) {  // in the back end's arena already
    tbb::parallel_for(std::size_t{0}, workers_.size(), [&](std::size_t k) { timed(*workers_[k]); });
    return;
  }
  arena_->execute([&] {
    tbb::parallel_for(std::size_t{0}, workers_.size(), [&](std::size_t k) { timed(*workers_[k]); });
  });
}

void PartitionedScan::SetTrace(TraceSink* trace) {
  if (workers_.size() == 1) workers_.front()->scan.SetTrace(trace);
  tracing_ = trace != nullptr;
}

bool PartitionedScan::ScanRow(double y, const raster::SampleColumns& columns, raster::FragmentRow& out) {
  if (aheadAsked_) StartAhead();
  if (!ahead_) return Composite(y, columns, out);
  return ahead_->Replay(static_cast<int>(std::lround((y - aheadY0_) / aheadDy_)), out);
}

bool PartitionedScan::Composite(double y, const raster::SampleColumns& columns, raster::FragmentRow& out) {
  if (workers_.size() == 1) {  // alone: no compositing
    const double t0 = Now();
    const bool ok = workers_.front()->scan.ScanRow(y, columns, out);
    workers_.front()->seconds += Now() - t0;
    return ok;
  }
  return ScanRowNow(y, columns, out);
}

void PartitionedScan::ScanRows(double y0, double dy, int first, int count, const raster::SampleColumns& columns) {
  // Step 1: every worker's rows, each into its own buffers (a θ slab interval's surfaces
  // each decide alone whether they are slabs: no worker waits for another's within it).
  ForEachWorker([&](Worker& w) {
    for (int k = 0; k < count; ++k) {
      RowBuffer& row = w.rows[static_cast<std::size_t>(k)];
      row.Clear();
      row.scanned = w.scan.ScanRow(raster::RowY(y0, dy, first + k), columns, row);
    }
  });
}

bool PartitionedScan::MergeRow(int k, const raster::SampleColumns& columns, raster::FragmentRow& out,
                               std::vector<std::size_t>* next, bool triangles) const {
  // Step 2: composite, in scan order.
  const std::size_t n = workers_.size();
  const auto row = [&](std::size_t w) -> const RowBuffer& { return workers_[w]->rows[static_cast<std::size_t>(k)]; };
  // A scan hands over fragments (exact mode) or chords (θ mode), not both.
  MergeByRank(n, [&](std::size_t w) -> const auto& { return row(w).fragments; }, next,
              [&](const RowBuffer::BufferedFragment& e) { out.Add(e.column, e.f); });
  MergeByRank(n, [&](std::size_t w) -> const auto& { return row(w).chords; }, next,
              [&](const RowBuffer::BufferedChord& e) { out.AddChord(e.chord, columns); });
  if (triangles) MergeTriangles(k, out, next);
  bool ok = true;
  for (const auto& w : workers_) ok = ok && w->rows[static_cast<std::size_t>(k)].scanned;
  return ok;
}

bool PartitionedScan::TimedMerge(int k, const raster::SampleColumns& columns, raster::FragmentRow& out) {
  const double t0 = Now();
  const bool ok = MergeRow(k, columns, out, &next_);
  compositeSeconds_ += Now() - t0;
  return ok;
}

bool PartitionedScan::ScanRowNow(double y, const raster::SampleColumns& columns, raster::FragmentRow& out) {
  ScanRows(y, 0.0, 0, 1, columns);
  return TimedMerge(0, columns, out);
}

PartitionedScan::Timing PartitionedScan::Times() const {
  Timing t;
  for (const auto& w : workers_) t.workerSeconds.push_back(w->seconds);
  t.compositeSeconds = compositeSeconds_;
  return t;
}

Counters PartitionedScan::Stats() const {
  Counters total;
  for (const auto& w : workers_) total.Merge(w->scan.Stats());
  return total;
}

}  // namespace patchscan
