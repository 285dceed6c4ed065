// Boundary-edge trackers of the Y scan (Blinn 1978 §3.2.1): the points where the scan line
// crosses the four boundary edges of a surface, advanced from one scan line to the next
// by univariate Newton on y(edge(t)) = yScan from a start extrapolated from the last two
// positions (§3.5).
//
// Each edge is first cut into pieces on which y is monotone (its critical points are the
// edge and corner maxima and minima of §3.2.2): a tracker is created when the scan line
// passes the top of a piece and deleted when it passes the bottom, and inside a piece
// there is exactly one crossing, so a failed Newton step is repaired inside the piece
// (Newton kept in the bracket, CrossingOnPiece), never by guessing.
#pragma once

#include <array>
#include <cmath>
#include <utility>
#include <vector>

#include "core/counters.h"
#include "patch/screen.h"
#include "tracker/newton.h"

namespace patchscan {

// The boundary edge e as a curve in the domain: U0 = (0, t), U1 = (1, t), V0 = (t, 0),
// V1 = (t, 1), t in [0, 1].
inline Vec2 EdgePoint(PatchEdge e, double t) {
  switch (e) {
    case PatchEdge::U0: return {0.0, t};
    case PatchEdge::U1: return {1.0, t};
    case PatchEdge::V0: return {t, 0.0};
    case PatchEdge::V1: return {t, 1.0};
  }
  return {t, 0.0};
}

// A piece [t0, t1] of an edge on which screen y is monotone.
struct EdgePiece {
  PatchEdge edge;
  double t0, t1;
  double yTop, yBottom;  // smallest and largest y on the piece
};

// Samples per edge when looking for the critical points of y along it: y along a cubic
// edge in perspective has at most a few; two within 1/64 of the edge would be missed.
constexpr int kEdgeCriticalSamples = 64;
// Convergence of edge trackers in screen y: far below the 1e-3 px the exact mode allows.
constexpr double kEdgeTolPx = 1e-7;

// How an edge's critical points of y are found: spans where the surface is a cubic
// polynomial proven monotone without sampling, the rest sampled (what the scans do); or
// the whole edge sampled (to test the one against the other).
enum class EdgeSampling { ProveCubicSpans, SampleAll };

// The monotone pieces of one edge of `s` (none for a collapsed edge; then *collapsedY,
// when given, is set to the screen y of the point the edge collapses to, else NaN).
std::vector<EdgePiece> MonotoneEdgePieces(const Surface& s, const ScreenMap& map, PatchEdge e,
                                          double* collapsedY = nullptr,
                                          EdgeSampling sampling = EdgeSampling::ProveCubicSpans);
// Whether y is proven monotone along all of edge e (no sample taken): every span of it is
// cubic and of one sign of y_t (edge_scan.cpp, MonotoneSign).
bool EdgeProvenMonotone(const Surface& s, const ScreenMap& map, PatchEdge e);

// A piece whose y range is this small lies along its scan line: a straight boundary edge
// level on the screen (a full quadric's seam seen edge-on, a cylinder's ruling), whose
// "pieces" are the rounding noise of y_t = 0. Rounding of y is ~1e-13 px.
constexpr double kFlatPiecePx = 1e-9;
// A line within this of a flat piece or a collapsed edge's point meets a degenerate level
// set (a whole edge, or the pole every level curve through it passes): SurfaceScan::LineFor.
constexpr double kDegenerateNearPx = 1e-6;

struct EdgeTracker {
  int piece;            // index into EdgeScan::Pieces()
  double t, tPrev;      // on this and the previous scan line
  bool hasPrev = false;
  double j = 0.0;       // Blinn's Zn (the silhouette function J) here; a sign change is a fold
  bool folded = false;  // J changed sign since the previous scan line, or since the
                        // piece's top for a new tracker (§3.2.2.3)
  double tPrev2 = 0.0;  // on the scan line before the previous one (when nSolved >= 3)
  int nSolved = 0;      // scan lines on which this tracker has been solved
  // Screen y and its derivative along the edge at the latest solution t, and at tPrev:
  // the predictor's data (PredictedStart in edge_scan.cpp, which finds y_tt when it needs it).
  double y = 0.0, yt = 0.0, yPrev = 0.0, ytPrev = 0.0;
};

// All boundary-edge trackers of one surface, advanced scan line by scan line.
class EdgeScan {
 public:
  // `tolerancePx`: convergence in screen y (Blinn stopped at a tenth of a raster). Counts
  // into `counters` (the y scan's, core/counters.h), which must outlive the scan.
  EdgeScan(const Surface& s, const ScreenMap& map, Counters& counters, bool extrapolate = true,
           double tolerancePx = kEdgeTolPx);

  // Moves every tracker to the scan line yScan (non-decreasing from call to call),
  // creating and deleting trackers at the pieces' ends. Allocation-free after the first
  // calls have sized the tracker list.
  void Advance(double yScan);

  const std::vector<EdgeTracker>& Trackers() const { return trackers_; }
  const std::vector<EdgePiece>& Pieces() const { return pieces_; }
  // The top of the topmost piece (+inf: the edges have none), and whether the scan has
  // passed them all: no tracker alive and no piece left to begin.
  double FirstTop() const { return pieces_.empty() ? INFINITY : pieces_.front().yTop; }
  bool Done() const { return trackers_.empty() && nextPiece_ == pieces_.size(); }
  // Ranges of y, sorted and disjoint, on which a scan line meets a degenerate level set:
  // within kDegenerateNearPx of a flat piece or of a collapsed edge's point.
  const std::vector<std::pair<double, double>>& DegenerateRanges() const { return degenerate_; }
  // Events so far: trackers born and died, folds, bisection repairs. Two calls that
  // return the same number bracket scan lines on which the boundary crossings kept their
  // topology (a θ slab needs that, xscan/exact_scan.cpp).
  long Events() const { return events_; }
  // Where a silhouette crossed a boundary edge since the previous scan line (§3.2.2.3):
  // a tracker whose J changed sign (its position), or a tracker deleted at the bottom of
  // its piece after J changed sign on the way there (that end). Refilled by Advance.
  const std::vector<Vec2>& Folds() const { return folds_; }
  // Where trackers died (their last position) at the latest Advance.
  const std::vector<Vec2>& Deaths() const { return deaths_; }
  Vec2 Uv(const EdgeTracker& t) const { return EdgePoint(pieces_[t.piece].edge, t.t); }

  // What Advance changes: Save and Restore return the scan to a line it has passed
  // (SurfaceScan::State). Allocation-free once the state's lists have their size.
  struct State {
    std::vector<EdgeTracker> trackers;
    std::vector<Vec2> folds, deaths;
    size_t nextPiece = 0;
    long events = 0;
  };
  void Save(State* s) const {
    s->trackers = trackers_, s->folds = folds_, s->deaths = deaths_;
    s->nextPiece = nextPiece_, s->events = events_;
  }
  void Restore(const State& s) {
    trackers_ = s.trackers, folds_ = s.folds, deaths_ = s.deaths;
    nextPiece_ = s.nextPiece, events_ = s.events;
  }

 private:
  const Surface& surface_;
  const ScreenMap& map_;
  bool extrapolate_;
  double tolerancePx_;
  std::vector<EdgePiece> pieces_;   // sorted by yTop
  std::vector<std::pair<double, double>> degenerate_;
  std::vector<EdgeTracker> trackers_;
  std::vector<Vec2> folds_, deaths_;
  size_t nextPiece_ = 0;
  Counters& counters_;
  long events_ = 0;
};

}  // namespace patchscan
