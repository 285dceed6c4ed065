// The rows a threaded direct scan produces ahead of the back end: each row's fragments,
// chords and triangles held in a ring of slots, those the back end would drop by depth
// left out (DepthFilter), and handed over in row order while the scan fills the next. A
// thread of its own produces the rows (PartitionedScan: the object partition's workers
// composited; RowScan: batches of rows scanned on every thread), the back end's calling
// thread replays them. Memory: the ring's rows, O(width x depth).
#pragma once

#include <condition_variable>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>
#include <utility>
#include <vector>

#include "raster/fragment.h"
#include "raster/triangle_store.h"

namespace patchscan {

// What the back end will keep of a row's samples by depth (raster::KeptDepths), followed
// as fragments arrive in the order the back end will take them: a fragment it would drop
// (behind the `layers` nearest of those before it, or nearer than the hither plane) is
// dropped here already. Dropping from the fragments of some surfaces only is safe: what
// hides a fragment among them hides it among all, and merging keeps their order.
class DepthFilter {
 public:
  void Reset(const raster::KeptDepths& kept, int columns) {
    kept_ = kept;
    columns_ = columns;
    keep_.clear();
    touched_ = false;
  }
  // The depths are made when the first is kept: a row that keeps none (a θ scan's, whose
  // chords are not tested here) costs nothing to hold or to clear.
  void ClearRow() {
    if (touched_) std::fill(keep_.begin(), keep_.end(), raster::kNoSample);
    touched_ = false;
  }
  bool Hidden(int column, double w) const {
    if (kept_.layers == 0) return false;
    return column < 0 || column >= columns_ || !(w >= kept_.hither) ||
           (touched_ && raster::Behind(Of(column), kept_.layers, 1.0 / w));
  }
  // Takes a fragment not Hidden: its depth joins the sample's nearest.
  void Keep(int column, double w) {
    if (kept_.layers == 0) return;
    if (keep_.empty()) keep_.assign(static_cast<std::size_t>(columns_) * kept_.layers, raster::kNoSample);
    raster::InsertNearest(Of(column), kept_.layers, 1.0 / w, 0);
    touched_ = true;
  }

 private:
  const raster::Sample* Of(int column) const { return keep_.data() + static_cast<std::ptrdiff_t>(column) * kept_.layers; }
  raster::Sample* Of(int column) { return keep_.data() + static_cast<std::ptrdiff_t>(column) * kept_.layers; }
  raster::KeptDepths kept_;
  int columns_ = 0;
  bool touched_ = false;  // some depth kept since the row was cleared
  std::vector<raster::Sample> keep_;  // per column its layers' depths, nearest first (as the back end's)
};

// A row kept for the back end: what the scan handed over, in its order, less what DepthFilter
// drops.
class StoredRow final : public raster::FragmentRow {
 public:
  void Clear() {
    fragments_.clear();
    triangles_.clear();
    chords_.clear();
    depth.ClearRow();
  }
  // Chords are kept as they are (the back end tests their samples).
  void AddChord(const raster::Chord& c, const raster::SampleColumns& columns) override {
    chords_.push_back(c);
    columns_ = columns;
  }
  void Add(int column, const raster::Fragment& f) override {
    if (depth.Hidden(column, f.w)) return;
    depth.Keep(column, f.w);
    fragments_.push_back({column, f});
  }
  bool Hidden(int column, double w) const override { return depth.Hidden(column, w); }
  void AddTriangle(const raster::RasterVertex& a, const raster::RasterVertex& b, const raster::RasterVertex& c,
                   std::uint32_t surfaceId) override {
    triangles_.push_back({a, b, c, surfaceId});
  }
  DepthFilter depth;
  // Hands everything over to `out` in the order it came.
  void Replay(raster::FragmentRow& out) const {
    for (const auto& [column, f] : fragments_) out.Add(column, f);
    for (const raster::Chord& c : chords_) out.AddChord(c, columns_);
    for (const Triangle& t : triangles_) out.AddTriangle(t.a, t.b, t.c, t.surfaceId);
  }

 private:
  struct Triangle {
    raster::RasterVertex a, b, c;
    std::uint32_t surfaceId;
  };
  std::vector<std::pair<int, raster::Fragment>> fragments_;
  std::vector<raster::Chord> chords_;
  raster::SampleColumns columns_;
  std::vector<Triangle> triangles_;
};

// The ring: a producer thread fills rows 0, 1, ... (Slot, Publish) while the back end
// replays them in order (Replay); the producer waits while the ring is full.
class RowRing {
 public:
  // `depth` slots of rows of `columns` samples, filtered as the back end keeps `kept`.
  RowRing(int depth, const raster::KeptDepths& kept, int columns);
  // Stop()s.
  ~RowRing();
  RowRing(const RowRing&) = delete;
  RowRing& operator=(const RowRing&) = delete;

  // Runs `produce` on a plain thread (not a task of an arena: the destructor joins it
  // without waiting inside the arena, where the wait could be run by the very worker the
  // producer runs on). An exception it throws is rethrown to the back end by Replay.
  void Start(std::function<void()> produce);

  // Cancels the producer and joins it (its owner calls it before what the producer uses goes).
  void Stop();

  int Depth() const { return static_cast<int>(slots_.size()); }
  // Producer: waits until the back end has replayed every row before `end` - Depth() (so
  // rows up to `end` - 1 have slots); false when cancelled.
  bool Reserve(int end);
  // Producer: row j's slot, cleared (j below the last Reserve's end).
  StoredRow& Slot(int j);
  // Producer: row j is made (`ok`: the scan's answer for it).
  void Publish(int j, bool ok);
  // Back end: waits for row j, hands it to `out` and frees its slot; the scan's answer.
  bool Replay(int j, raster::FragmentRow& out);

 private:
  std::vector<StoredRow> slots_;
  std::vector<char> okOf_;
  std::mutex m_;
  // The producer waits on `space_` for the back end to have replayed `producerNeeds_` rows
  // (half the ring past what it needs: a wait frees room for several rows), the back end on
  // `ready_` for `consumerNeeds_` rows made; each is woken only once what it waits for is there.
  std::condition_variable space_, ready_;
  int produced_ = 0, consumed_ = 0;
  int producerNeeds_ = -1, consumerNeeds_ = -1;  // -1: not waiting
  bool cancel_ = false;
  std::exception_ptr error_;
  std::thread producer_;
};

}  // namespace patchscan
