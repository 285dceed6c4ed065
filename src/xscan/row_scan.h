// The exact scan on every thread of one process, split by rows (sort-first, Molnar et al.
// 1994): the frame's sample rows in batches, each batch's Y scan (every surface's trackers
// advanced through its rows: cheap) and then its rows' X scans on every thread at once,
// each row with all its surfaces in scan order. So a row's surfaces hide each other's
// samples as in one scan (occlusion culling: a hidden sample costs no Newton solve), and
// nothing is scanned twice. The back end drives the batches and resolves each row as it is
// scanned (FragmentSource::ScansInBatches); a source wrapped by another (PolygonFeed) runs
// them on a thread of its own ahead of the back end instead (RowRing).
//
// The image is the same for any number of threads: a row's X scan depends on its trackers
// alone, and the one thing the X scan gives back to the Y scan, a silhouette found without
// a tracker, is taken up on the last row of a batch (ExactScanOptions::adoptRows), whoever
// scans. Memory: the trackers of one batch (and the ring's rows, when it runs ahead).
#pragma once

#include <memory>
#include <span>

#include "xscan/exact_scan.h"
#include "xscan/partitioned_scan.h"

namespace patchscan {

class RowRing;

class RowScan final : public DirectScanSource {
 public:
  // Whether a scan with `options` can be split by rows (the exact X scan; the θ scans'
  // chains carry from row to row per surface: PartitionedScan).
  static bool Splits(const ExactScanOptions& options) { return options.thetaSteps == 0; }
  // On `threads` threads (capped at the cores); `surfaces` must outlive it.
  RowScan(std::span<const Surface> surfaces, const Camera& camera, ExactScanOptions options, int threads);
  ~RowScan() override;

  void BeginRows(const raster::SampleColumns& columns, double y0, double dy, int nRows,
                 const raster::KeptDepths& kept) override;
  // Rows asked one by one (a wrapping source's): from the ring, scanned ahead.
  bool ScanRow(double y, const raster::SampleColumns& columns, raster::FragmentRow& out) override;

  bool ScansInBatches() const override { return true; }
  bool EndsBatch(int row) const override { return scan_.AdoptsOn(firstRow_ + row); }
  void PrepareRows(int first, int count) override;
  bool ScanPreparedRow(int k, raster::FragmentRow& out) override;
  void FinishRows() override;

  Counters Stats() const override;
  // workerSeconds: each thread's seconds in X scans (a slot of the arena each, as many as
  // the threads); compositeSeconds: the batches' Y scans and take-ups (the scan's serial
  // part).
  Timing Times() const override;
  // No trace: a trace is drawn by one scan on one thread (PartitionedScan).
  void SetTrace(TraceSink*) override {}

 private:
  // Runs the batches on the ring's thread, for a back end that asks row by row.
  void StartRing(int nRows, const raster::KeptDepths& kept);

  ExactScan scan_;
  int threads_;
  raster::SampleColumns columns_;
  double y0_ = 0.0, dy_ = 1.0;
  long firstRow_ = 0;  // the lattice's index of row 0 (y0)
  int nRows_ = 0;
  raster::KeptDepths kept_;
  bool begun_ = false;
  struct Scratch;
  std::unique_ptr<Scratch> scratch_;
  double serialSeconds_ = 0.0;
  std::unique_ptr<RowRing> ring_;
};

}  // namespace patchscan
