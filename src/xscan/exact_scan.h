// The exact render's front end (Blinn 1978 §3): per surface the maxima pre-pass, then
// scan line by scan line the boundary-edge and silhouette trackers of the Y scan and the
// exact X scan between them, handing the back end one fragment per sample of every
// surface layer (depth, exact normal, uv, surface id). A surface is set up when the scan
// reaches the top of its screen box and dropped below its bottom: memory follows the
// active set, not the scene.
#pragma once

#include <cmath>
#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <utility>
#include <vector>

#include "patch/camera.h"
#include "patch/surface.h"
#include "raster/fragment.h"
#include "tracker/surface_scan.h"
#include "xscan/level_walk.h"
#include "xscan/theta_slab.h"
#include "xscan/theta_walk.h"
#include "xscan/trace.h"

namespace patchscan {

// The fragment of the surface point a walk found: world position, unit world normal (its
// limit from inside at a collapsed edge), eye distance, uv and uv per pixel.
raster::Fragment FragmentAt(const LevelPoint& p, const Surface& surface,
                            const Mat3& normalFromObject, std::uint32_t surfaceId);

struct ExactScanOptions {
  bool extrapolate = true;  // start tracker Newton from the last two positions (§3.5)
  // 0: the exact X scan. N > 0: the θ-sampled X scan (§4) with N angles per turn.
  int thetaSteps = 0;
  // θ scan only. 0: a chain on every sample row, its samples interpolated along its
  // chords. R > 0: chains on scan lines R sample rows apart, half a row above sample rows
  // (so no sample lies on one), and the surface between two lines handed to the back end
  // as triangles (theta_slab.h); where the lines' chains do not pair up, or the Y scan
  // has an event between them, every sample row between them takes its own chains.
  int slabRows = 0;
  // θ rows: a surface whose chains hold more Newton-solved vertices per sample than
  // samples of the exact X scan cost (exact_scan.cpp: kThetaVerticesPerSampleMax) takes
  // the exact X scan from then on. Off: every surface keeps its chains (tests of the θ
  // scan's own error).
  bool exactWhereCheaper = true;
  // A silhouette the exact X scan finds without a tracker is taken up by the Y scan
  // (SurfaceScan::Adopt) only on the sample rows j >= adoptPhase with j - adoptPhase a
  // multiple of adoptRows (ExactScan::AdoptsOn; j = 0 at the columns' x0, the lattice's
  // first row).
  // 1: on every row. More: the exact X scans of a batch of rows that ends on such a row
  // depend on the Y scan alone, and run on any threads (xscan/row_scan.h).
  int adoptRows = 1, adoptPhase = 0;
  bool AdoptsOn(long row) const { return adoptRows <= 1 || (row >= adoptPhase && (row - adoptPhase) % adoptRows == 0); }
};

// A surface as the scan meets it: its index, and the y extent and area (pixels) of its
// conservative screen box; a surface reaching behind the eye has an unbounded box.
struct ScanEntry {
  std::size_t index;
  double yMin, yMax;
  double area;
  bool operator==(const ScanEntry&) const = default;
};
// The surfaces of `surfaces` the scan will meet, in the order it meets them: by the top of
// the screen box, then by index. Surfaces wholly nearer than the hither plane (or behind
// the eye) are left out: never set up. Set-up only (allocates).
std::vector<ScanEntry> ScanOrder(std::span<const Surface> surfaces, const Camera& camera);

class ExactScan final : public raster::FragmentSource {
 public:
  // `surfaces` must outlive the scan; fragment surface ids are indices into it. The scan
  // covers `share` (entries of ScanOrder, in its order), or every surface when omitted.
  ExactScan(std::span<const Surface> surfaces, const Camera& camera, ExactScanOptions options = {});
  ExactScan(std::span<const Surface> surfaces, const Camera& camera, ExactScanOptions options,
            std::vector<ScanEntry> share);
  ~ExactScan() override;

  bool ScanRow(double y, const raster::SampleColumns& columns, raster::FragmentRow& out) override;

  // θ slabs: whether sample row y begins an interval of slabRows rows (ScanRow takes the
  // interval at its first row: every surface's trackers advanced through it, then each
  // surface alone made into slabs between the interval's lines, or, where its Y scan has
  // an event there or its lines' chains do not pair up, into each row's chains; a surface
  // taken row by row ends its rows' chains on a boundary where a slab across it would
  // (SnapEnds), so no decision needs another surface's, and a partition of the scene
  // changes nothing).
  bool BeginsInterval(double y, const raster::SampleColumns& columns) const;

  // Marks every tracker position and event on `trace` from the next row on (null: none).
  void SetTrace(TraceSink* trace) { trace_ = trace; }

  // Theta mode: shows every chain to `sink` as it is made (null: none).
  void SetThetaChainSink(ThetaChainSink* sink) { chainSink_ = sink; }

  // The counts so far (core/counters.h: set up, y scan, x scan, θ and slab groups).
  const Counters& Stats() const { return counters_; }

  // Whether sample row `row` takes up the silhouettes its exact X scans found untracked
  // (ExactScanOptions::adoptRows). The image is the same for any split of the rows between
  // such rows; until it is taken up, such a silhouette is found again on each row by the
  // walk that found it (a walk follows the level curve from a tracker, and finds every
  // silhouette on it).
  bool AdoptsOn(long row) const { return options_.AdoptsOn(row); }
  // What one thread's exact X scans use beside the scan's state, and what they count.
  struct RowScratch {
    WalkEvents events;
    std::vector<char> edgeUsed, silUsed;
    TrimScratch trim;
    Counters counters;
  };
  // Sort-first, exact X scan only (thetaSteps 0): the Y scan of rows y0 + j dy for j in
  // [first, first + count), every surface's trackers on each kept for its X scan, which
  // ScanPrepared then makes. `first` + count - 1 should be a row that AdoptsOn, or the
  // frame's last: the rows before it do not. The surfaces the rows reach are set up first,
  // through `parallel` if given (its calls f(i) for i in [0, n) may run at once; a surface
  // set up that way counts into its own counters, added to the scan's in order), each as
  // the Y scan would set it up on the row that reaches it.
  using ParallelFor = std::function<void(int n, const std::function<void(int)>& f)>;
  void PrepareBatch(double y0, double dy, int first, int count, const raster::SampleColumns& columns,
                   const ParallelFor& parallel = {});
  // The exact X scan of the k-th row prepared (k < count) into `out`, as ScanRow would make
  // it. Rows may be scanned at once on several threads, each with scratch of its own.
  bool ScanPrepared(int k, const raster::SampleColumns& columns, raster::FragmentRow& out, RowScratch& scratch);
  // After every prepared row is scanned: the silhouettes the last row's X scans found
  // untracked are taken up, if that row AdoptsOn.
  void FinishBatch();

 private:
  struct Active;
  // Retires the surfaces the scan has passed (below yLo) and sets up those it has reached
  // (top at or above yHi, bottom at or below yLo), their trackers first advanced to yLo.
  void UpdateActive(double yLo, double yHi, double spacing);
  void Activate(const ScanEntry& entry, double y, double spacing);
  // A surface set up on row y, counting into `counters` (which must outlive it).
  std::unique_ptr<Active> SetUp(const ScanEntry& entry, double y, double spacing, Counters& counters) const;
  // Adds the counts of the surfaces set up apart (Active::own) to the scan's.
  void GatherCounts();
  // Advances a surface's trackers to y (and traces them).
  void AdvanceTo(Active& a, double y);
  // The X scan of a surface on line y from its trackers `t`: exact fragments, or (θ) each
  // chain to Take(std::span<const ThetaVertex>, bool closed).
  template <class Take>
  void WalkSurface(Active& a, double y, const RowTrackers& t, const raster::SampleColumns& columns,
                   raster::FragmentRow& out, Take&& take);
  bool SlabMode() const { return options_.thetaSteps > 0 && options_.slabRows > 0; }
  // θ slabs: the interval beginning at sample row y (below).
  void ScanInterval(double y, const raster::SampleColumns& columns, raster::FragmentRow& out);
  // θ slabs: the interval beginning at sample row y: surfaces set up, and every surface's
  // trackers advanced to its top line and its bottom one, with whether each step has no
  // event (Active::stepCalm): straight from line to line for a surface that was a slab
  // through the interval before, unless that step has an event; else through each row.
  void PrepareInterval(double y, const raster::SampleColumns& columns, raster::FragmentRow& out);
  // θ slabs: a surface's trackers advanced from the interval's top line to each of its
  // rows (Active::rowTrackers) and its bottom line, with whether each step is calm.
  void AdvanceRows(Active& a, const raster::SampleColumns& columns);
  // θ slabs: whether every step of a surface through the interval is calm.
  static bool AllCalm(const Active& a);
  // θ slabs: screen y of the interval's sample row r.
  double RowY(const raster::SampleColumns& columns, int r) const {
    return columns.x0 + static_cast<double>(intervalStart_ + r) * columns.dx;
  }
  // θ slabs: whether a surface is a slab through the interval: no event in it, its lines'
  // chains walked or advanced, and paired (else rows, and, with an event, no line walked).
  bool PairSurface(Active& a, const raster::SampleColumns& columns, raster::FragmentRow& out);
  // θ slabs: a paired surface's slabs, or the chains of each of a surface's rows.
  void SlabSurface(Active& a, const raster::SampleColumns& columns, raster::FragmentRow& out);
  void RowSurface(Active& a, const raster::SampleColumns& columns, raster::FragmentRow& out);
  // θ slabs: a boundary's point on one of the interval's lines, its screen x rounded as a
  // slab vertex's (SlabEndX).
  struct LineEnd {
    Vec2 uv;
    double x;
  };
  // The boundary points of a surface's trackers `t` on a line.
  void LineEnds(const Active& a, const RowTrackers& t, std::vector<LineEnd>* ends) const;
  // Moves each End vertex of a row's chains, t of the way from the interval's top line to
  // its bottom one, onto the straight line between its boundary's points on the two lines
  // (topEnds_, bottomEnds_): the edge a slab across the boundary has there. The boundary
  // lies within h^2 / (8 R) px of it (h the interval's height, R the boundary's radius of
  // curvature on screen); the end keeps its fragment. Where the boundary has no point on
  // a line near the end, the points do not bracket it, or the side has a crossing born or
  // gone in the interval (a fold, a corner: the surface across shares it, and is taken
  // row by row too), it stays. `row`: the row's trackers.
  void SnapEnds(double t, const RowTrackers& row, ChainSet* set) const;
  // The boundary's parameter may lie this far outside its points on the lines (rounding),
  // and an end moves at most this far (pixels; farther, the points are another crossing's).
  static constexpr double kSnapAlongSlack = 1e-12, kSnapMaxPx = 0.5;
  // θ slabs: the current interval's top and bottom lines.
  std::pair<double, double> IntervalLines(const raster::SampleColumns& columns) const;
  // θ slabs: a surface's chains on line y, from its trackers `t` there, into *set, and
  // whether the walk failed or repaired a tracker miss.
  void WalkLine(Active& a, double y, const RowTrackers& t, const raster::SampleColumns& columns,
                raster::FragmentRow& out, ChainSet* set, bool* broken);
  // θ rows and slabs: a surface's chains `from` on line yFrom advanced to line y, its
  // trackers `t` there, as θ trackers into *to; false if the line must be crawled afresh.
  bool AdvanceSurface(Active& a, const ChainSet& from, double yFrom, double y, const RowTrackers& t, ChainSet* to,
                      const raster::SampleColumns& columns);
  // θ rows: a surface's chains on row y, its trackers `t` there, into *set: advanced from
  // `before` on row yBefore where given (AdvanceSurface, counted as a row advanced or a
  // line repaired), else, or where that fails, crawled afresh. Whether they were advanced.
  bool AdvanceOrWalk(Active& a, const ChainSet* before, double yBefore, double y, const RowTrackers& t, ChainSet* set,
                     const raster::SampleColumns& columns, raster::FragmentRow& out);
  // Calls f(walker, make) with the θ walker of a surface on line y and its fragment maker.
  template <class F>
  void VisitTheta(Active& a, double y, const raster::SampleColumns& columns, F&& f);
  // After a surface's X scan: silhouettes found without a tracker are adopted (if `adopt`);
  // the trace.
  void FinishWalk(Active& a, bool adopt = true);
  // The exact X scan of a surface on line y from its trackers `t`, with `scratch`: what
  // WalkSurface does for a surface not θ-scanned, less FinishWalk.
  struct WalkScratch {
    WalkEvents* events;
    std::vector<char>*edgeUsed, *silUsed;
    TrimScratch* trim;
    Counters* counters;
  };
  void WalkExact(const Active& a, double y, const RowTrackers& t, const raster::SampleColumns& columns,
                 raster::FragmentRow& out, const WalkScratch& scratch) const;
  // Whether a surface's sections keep their shape from line yTop to line yBottom, its
  // trackers advanced there from a count of eventsBefore events: no event of the Y scan,
  // stationary point or degenerate level set between them, and no trim.
  bool Calm(const Active& a, long eventsBefore, double yTop, double yBottom) const;
  // Whether the last X scan of a surface gave up or repaired a tracker miss.
  bool WalkBroken() const { return !walkEvents_.failures.empty() || !walkEvents_.repairs.empty(); }
  // The sample row index of line y.
  static long RowIndex(double y, const raster::SampleColumns& columns) {
    return std::lround((y - columns.x0) / columns.dx);
  }
  bool ScanRowSlabs(double y, const raster::SampleColumns& columns, raster::FragmentRow& out);
  void TraceTrackers(Active& a, double y);
  void TraceWalk(Active& a);
  // Marks the surface point uv of `a` on the trace, if it is in front of the eye.
  void TraceMark(const Active& a, TraceKind kind, const Vec2& uv);

  std::span<const Surface> surfaces_;
  Camera camera_;
  Vec3 eye_, right_, forward_;  // EyePoint, ViewRight and ViewForward of camera_, for the θ frame
  std::vector<Vec2> angles_;   // (cos θ_i, sin θ_i): the θ trackers' table (§4.1)
  ExactScanOptions options_;
  std::vector<ScanEntry> pending_;  // in scan order
  ThetaTable thetaTable_;           // the walkers' view of the table
  std::size_t nextPending_ = 0;
  std::vector<std::unique_ptr<Active>> active_;
  // Sort-first: each prepared row's surfaces (in scan order) and their trackers; surfaces
  // left behind within a batch are kept until its rows are scanned.
  struct Prepared {
    Active* a = nullptr;
    RowTrackers t;
  };
  struct PreparedRow {
    double y = 0.0;
    int count = 0;
    std::vector<Prepared> entries;  // the first count; the rest keep their lists' capacity
  };
  std::vector<PreparedRow> prepared_;
  int preparedCount_ = 0;
  std::vector<std::unique_ptr<Active>> retired_;
  bool holdRetired_ = false;
  // Sort-first: surfaces set up ahead of the rows that reach them, by pending_ index.
  struct Ready {
    std::size_t index;  // in pending_
    double y;           // the row that reaches it
    std::unique_ptr<Active> a;
  };
  std::vector<Ready> ready_;
  std::size_t nextReady_ = 0;
  WalkEvents walkEvents_;
  std::vector<ThetaVertex> chain_;
  ThetaChainSink* chainSink_ = nullptr;
  TraceSink* trace_ = nullptr;
  std::vector<char> edgeUsed_, silUsed_;
  TrimScratch trimScratch_;                        // the walks of trimmed surfaces
  std::vector<ThetaVertex> trimPiece_, trimFirst_;  // θ chains cut by trims
  Counters counters_;
  // θ slabs: the interval of sample rows being scanned.
  long intervalStart_ = 0, intervalEnd_ = -1;
  std::vector<std::uint32_t> anchorsTop_, anchorsBottom_;
  std::vector<LineEnd> topEnds_, bottomEnds_;  // SnapEnds' boundary points
};

}  // namespace patchscan
