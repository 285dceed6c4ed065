#include "xscan/row_scan.h"

#include <oneapi/tbb/enumerable_thread_specific.h>
#include <oneapi/tbb/info.h>
#include <oneapi/tbb/parallel_for.h>
#include <oneapi/tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>

#include "raster/work_arena.h"
#include "xscan/row_ring.h"

namespace patchscan {

namespace {

double Now() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }

}  // namespace

// Each thread's X scan scratch, and the seconds scanning of each slot of the arena the
// rows are scanned in (a slot holds one thread at a time: a worker may leave it for another,
// and the slots in use are at most the threads asked for).
struct RowScan::Scratch {
  explicit Scratch(int slots) : seconds(static_cast<std::size_t>(slots), 0.0) {}
  tbb::enumerable_thread_specific<ExactScan::RowScratch> threads;
  std::vector<double> seconds;
};

RowScan::RowScan(std::span<const Surface> surfaces, const Camera& camera, ExactScanOptions options, int threads)
    : scan_(surfaces, camera, options),
      threads_(threads),
      // raster::WorkArena's: its workers and the two threads from outside.
      scratch_(std::make_unique<Scratch>(threads + 2)) {}

RowScan::~RowScan() {
  if (ring_) ring_->Stop();  // before what it scans with goes
}

void RowScan::BeginRows(const raster::SampleColumns& columns, double y0, double dy, int nRows,
                        const raster::KeptDepths& kept) {
  columns_ = columns;
  y0_ = y0;
  dy_ = dy;
  firstRow_ = std::lround((y0 - columns.x0) / columns.dx);
  nRows_ = nRows;
  kept_ = kept;
  begun_ = true;
}

void RowScan::PrepareRows(int first, int count) {
  const double t0 = Now();
  // The surfaces the rows reach set up on every thread of the arena this runs in (a
  // surface's set-up, its maxima pre-pass, costs as much as hundreds of rows of its Y scan).
  scan_.PrepareBatch(y0_, dy_, first, count, columns_, [](int n, const std::function<void(int)>& f) {
    tbb::parallel_for(0, n, [&](int i) { f(i); });
  });
  serialSeconds_ += Now() - t0;
}

bool RowScan::ScanPreparedRow(int k, raster::FragmentRow& out) {
  const double t0 = Now();
  const bool ok = scan_.ScanPrepared(k, columns_, out, scratch_->threads.local());
  const int slot = tbb::this_task_arena::current_thread_index();
  if (slot >= 0 && static_cast<std::size_t>(slot) < scratch_->seconds.size())
    scratch_->seconds[static_cast<std::size_t>(slot)] += Now() - t0;
  return ok;
}

void RowScan::FinishRows() {
  const double t0 = Now();
  scan_.FinishBatch();
  serialSeconds_ += Now() - t0;
}

void RowScan::StartRing(int nRows, const raster::KeptDepths& kept) {
  // The longest batch, so that the ring holds two: the threads scan one while the back end
  // takes the rows of the other.
  int longest = 1;
  for (int j = 0, run = 0; j < nRows; ++j) {
    longest = std::max(longest, ++run);
    if (EndsBatch(j)) run = 0;
  }
  ring_ = std::make_unique<RowRing>(2 * longest, kept, columns_.n);
  std::shared_ptr<tbb::task_arena> arena = raster::WorkArena(std::clamp(threads_, 1, tbb::info::default_concurrency()));
  ring_->Start([this, nRows, arena, longest] {
    std::vector<char> ok;  // each row's scan succeeded
    ok.reserve(static_cast<std::size_t>(longest));
    for (int j = 0; j < nRows;) {
      int count = 1;
      while (j + count < nRows && !EndsBatch(j + count - 1)) ++count;
      if (!ring_->Reserve(j + count)) return;
      ok.assign(static_cast<std::size_t>(count), 1);
      arena->execute([&] {
        PrepareRows(j, count);
        tbb::parallel_for(0, count, [&](int k) {
          ok[static_cast<std::size_t>(k)] = ScanPreparedRow(k, ring_->Slot(j + k));
        });
      });
      FinishRows();
      for (int k = 0; k < count; ++k) ring_->Publish(j + k, ok[static_cast<std::size_t>(k)] != 0);
      j += count;
    }
  });
}

bool RowScan::ScanRow(double y, const raster::SampleColumns& columns, raster::FragmentRow& out) {
  if (!begun_) return scan_.ScanRow(y, columns, out);  // not begun: scanned here, the same rows
  if (!ring_) StartRing(nRows_, kept_);
  return ring_->Replay(static_cast<int>(std::lround((y - y0_) / dy_)), out);
}

Counters RowScan::Stats() const {
  Counters total = scan_.Stats();
  for (const ExactScan::RowScratch& t : scratch_->threads) total.Merge(t.counters);
  return total;
}

DirectScanSource::Timing RowScan::Times() const {
  // The slots that scanned, in order, as many as the threads (a thread that took no row
  // scanned for 0 s).
  Timing t;
  for (const double s : scratch_->seconds)
    if (s > 0.0) t.workerSeconds.push_back(s);
  if (t.workerSeconds.size() < static_cast<std::size_t>(threads_)) t.workerSeconds.resize(static_cast<std::size_t>(threads_), 0.0);
  t.compositeSeconds = serialSeconds_;
  return t;
}

}  // namespace patchscan
