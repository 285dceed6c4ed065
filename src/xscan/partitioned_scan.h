// Molnar's object partition and z-composition (1990) on threads: the scene's surfaces
// are dealt out to workers, each an ExactScan of its share that scans every sample row in
// order exactly as it would alone; the rows of all workers are composited for the back end,
// which keeps the nearest layers per sample.
//
// The image is the same for any number of workers: every surface is scanned as it would be
// alone, and the compositor hands the back end each row's fragments and triangles in the
// order one scan of all surfaces would (surfaces in the order the scan meets them, each
// surface's own in its own order), so even ties of depth resolve alike. No decision joins
// surfaces (each decides alone whether a θ slab interval is a slab for it), so the workers
// meet only to hand their rows over. Memory: each worker holds a batch of rows (a pixel
// row's sample rows, or 8 rows of θ chords; the back end's batches of θ, about 16).
#pragma once

#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <vector>

#include "core/counters.h"
#include "raster/scanline_renderer.h"
#include "raster/work_arena.h"
#include "xscan/exact_scan.h"

namespace patchscan {

class RowRing;

// How the surfaces are dealt out: each worker's share of `order` (ScanOrder), in scan
// order. Balanced by an estimate of each surface's work — its screen box's area within
// the image, plus a set-up's worth — largest first, each to the least loaded worker (ties:
// the lower index), so the partition depends only on the scene, camera and worker count.
std::vector<std::vector<ScanEntry>> PartitionSurfaces(const std::vector<ScanEntry>& order, const Camera& camera,
                                                      int workers);

// What a direct render's front end gives the program besides the rows: its counts, its
// times, and (with one process) the trackers drawn on an overlay. PartitionedScan is one;
// a scan shared between processes (src/mpi, through render/shared_rows.h) is another.
class DirectScanSource : public raster::FragmentSource {
 public:
  // Each scanning worker's wall seconds, and the compositor's merging their rows.
  struct Timing {
    std::vector<double> workerSeconds;
    double compositeSeconds = 0.0;
  };
  virtual Counters Stats() const = 0;
  virtual Timing Times() const = 0;
  virtual void SetTrace(TraceSink* trace) = 0;
};

class PartitionedScan final : public DirectScanSource {
 public:
  // `workers` scans (at least 1) run on up to `threads` threads (1: all in the caller's).
  // `surfaces` must outlive the scan.
  PartitionedScan(std::span<const Surface> surfaces, const Camera& camera, ExactScanOptions options, int workers,
                  int threads);
  // One process's part of a scan shared by several (patchscan-mpi): its workers scan
  // `share`, part of ScanOrder(surfaces, camera), and the ranks of the whole order are
  // kept (RankOf) so that the processes' rows merge in scan order.
  PartitionedScan(std::span<const Surface> surfaces, const Camera& camera, ExactScanOptions options, int workers,
                  int threads, std::vector<ScanEntry> share);
  ~PartitionedScan() override;

  // With more than one thread, unless the back end takes the rows in batches, rows are
  // scanned and composited ahead of the back end (up to two pixel rows, or two θ batches)
  // on a thread of their own, from the first ScanRow on, while the back end shades the
  // rows before.
  void BeginRows(const raster::SampleColumns& columns, double y0, double dy, int nRows,
                 const raster::KeptDepths& kept) override;
  bool ScanRow(double y, const raster::SampleColumns& columns, raster::FragmentRow& out) override;
  // θ on threads: the back end takes the rows in batches (raster/batched_rows.h). A batch's
  // rows are scanned by every worker at once (PrepareRows, on the back end's threads); the
  // triangles of θ slabs are merged row by row on the calling thread for the back end's
  // store (PreparedTriangles); then every thread merges and resolves rows' fragments and
  // chords, a row a task: no thread of the scan's own. A back end that takes the rows one by
  // one (ScanRow) gets the scan-ahead instead.
  bool ScansInBatches() const override { return arena_ && chords_ && !tracing_; }
  bool EndsBatch(int row) const override { return raster::EndsRowBlock(row, perPixel_, kReplayBatch); }
  void PrepareRows(int first, int count) override;
  void PreparedTriangles(int k, raster::FragmentRow& out) override;
  bool ScanPreparedRow(int k, raster::FragmentRow& out) override;
  void FinishRows() override;

  // A row for a scan shared between processes: scanned by every worker (a θ slab interval
  // beginning at it first), and handed to `out` in scan order.
  bool ScanRowNow(double y, const raster::SampleColumns& columns, raster::FragmentRow& out);
  // Rows handed over leave out fragments the back end would drop by depth (`kept`, on rows
  // of `columns` samples): what BeginRows does, for a scan whose rows go elsewhere.
  void KeepDepths(const raster::KeptDepths& kept, int columns);
  // The place of surface `id` in the scan order of all surfaces.
  std::uint32_t RankOf(std::uint32_t id) const { return rank_[id]; }
  const std::vector<std::uint32_t>& Ranks() const { return rank_; }

  // With one worker: its tracker marks on `trace` (a trace is not shared between threads).
  void SetTrace(TraceSink* trace) override;

  // Every worker's counts added up (MaxActiveSurfaces: the most any one worker had).
  Counters Stats() const override;
  // Wall seconds each worker spent scanning its share, and the compositor merging the
  // workers' rows (with one worker: none).
  Timing Times() const override;
  int Workers() const { return static_cast<int>(workers_.size()); }

 private:
  struct Worker;
  // Runs f(worker) for every worker, in parallel when there are threads.
  // The scan order of all surfaces is `order`; the workers scan `share` (all: order).
  PartitionedScan(std::span<const Surface> surfaces, const Camera& camera, ExactScanOptions options, int workers,
                  int threads, const std::vector<ScanEntry>& order, std::optional<std::vector<ScanEntry>> share);
  template <class F>
  void ForEachWorker(F&& f);

  // One row of all workers, composited (into `out`, or into a slot of the scan-ahead).
  bool Composite(double y, const raster::SampleColumns& columns, raster::FragmentRow& out);
  // Every worker scans rows first, ..., first + count - 1 into its buffers, row j at
  // y0 + j dy (as the back end's lattice places it: y + k dy would round differently).
  void ScanRows(double y0, double dy, int first, int count, const raster::SampleColumns& columns);
  // The workers' k-th buffered rows, merged in scan order into `out` (`next`: scratch),
  // their triangles too if `triangles`: whether all scanned. Rows of a batch may be merged
  // on any threads at once.
  bool MergeRow(int k, const raster::SampleColumns& columns, raster::FragmentRow& out,
                std::vector<std::size_t>* next, bool triangles = true) const;
  // The workers' k-th rows' triangles, merged in scan order into `out`.
  void MergeTriangles(int k, raster::FragmentRow& out, std::vector<std::size_t>* next) const;
  // MergeRow on one thread at a time, its seconds counted.
  bool TimedMerge(int k, const raster::SampleColumns& columns, raster::FragmentRow& out);
  // Starts the scan-ahead on BeginRows' rows.
  void StartAhead();
  // With a scan-ahead, the workers scan batch_ rows between one fork and join: a fork and
  // join a sample row cost more than a θ
  // scan's row at two threads (4096x3072 θ teapot at two threads: 958 ms of CPU with,
  // 811 ms without, with the shared arena). A θ scan's rows hold chords, a few dozen
  // each: kThetaBatch of them; an exact scan's hold a fragment a covered sample: a pixel
  // row's sample rows (1024x768 exact aa 3 teapot at two threads 0.285 -> 0.265 s).
  static constexpr int kThetaBatch = 8;
  // Sample rows of the back end's batches (ScansInBatches), scanned and then resolved
  // between two forks and joins of the threads, against about 40 microseconds to scan a
  // sample row (the 2048x1536 θ teapot at aa 3: 3073 rows in 0.12 s on one thread,
  // --stats); each row's buffers hold a few dozen chords.
  static constexpr int kReplayBatch = kThetaBatch;
  bool chords_ = false;  // a θ scan
  int batch_ = 1;
  int perPixel_ = 1;      // new sample rows a pixel row (BeginRows' dy: 1 / perPixel)
  bool batched_ = false;  // the back end has taken a batch: the workers scan on its threads
  bool aheadAsked_ = false;  // BeginRows wants a scan-ahead, started by the first ScanRow
  int aheadRows_ = 0;
  raster::SampleColumns columns_;  // BeginRows' rows, and what the back end keeps of them
  raster::KeptDepths kept_;
  std::vector<std::vector<std::size_t>> batchNext_;  // merge scratch, a row of a batch each
  std::vector<double> batchSeconds_;                 // compositing seconds, a row of a batch each

  std::vector<std::unique_ptr<Worker>> workers_;
  std::unique_ptr<RowRing> ahead_;  // the scan-ahead, when BeginRows started one
  double aheadY0_ = 0.0, aheadDy_ = 1.0;  // its rows
  std::vector<std::uint32_t> rank_;  // per surface id: its place in the scan order
  std::shared_ptr<tbb::task_arena> arena_;
  std::vector<std::size_t> next_;  // merge scratch
  double compositeSeconds_ = 0.0;
  bool tracing_ = false;           // no scan-ahead: the trace is drawn row by row
};

}  // namespace patchscan
