// Trim-curve trackers of the Y scan: the points where the scan line
// crosses the trim curves of a trimmed NURBS piece (patch/trim.h), tracked as the
// boundary edges are (tracker/edge_scan.h, Blinn 1978 §3.2.1): each curve, clipped to the
// piece's domain, is cut where screen y turns; a tracker is born where the scan line
// passes the top of a piece and dies at its bottom, and in between follows its crossing by
// univariate Newton along the curve from an extrapolated start (§3.5), repaired inside
// the piece, which brackets it. The X scans toggle between kept and cut at these points.
#pragma once

#include <vector>

#include "core/counters.h"
#include "patch/screen.h"
#include "patch/surface.h"
#include "patch/trim.h"
#include "tracker/edge_crossings.h"
#include "tracker/edge_scan.h"

namespace patchscan {

// A piece [t0, t1] of trim curve `curve` (an index into PieceTrim::segments) inside the
// domain on which screen y is monotone.
struct TrimPiece {
  int curve;
  double t0, t1;
  double yTop, yBottom;
};

// Samples per trim segment when looking for where it enters and leaves the domain and
// where screen y turns along it: two such points within 1/64 of a segment are missed.
constexpr int kTrimCriticalSamples = 64;

class TrimScan {
 public:
  // The trackers of the trim of `surface` (any shape; `trim` its PieceTrim) seen
  // through `map`. All references must outlive the scan.
  TrimScan(const Surface& surface, const PieceTrim& trim, const ScreenMap& map, Counters& counters, bool extrapolate,
           double tolerancePx = kEdgeTolPx);

  // Moves every tracker to line yScan (non-decreasing from call to call), creating and
  // deleting trackers at the pieces' ends. Allocation-free once the lists have their size.
  void Advance(double yScan);

  // The crossings of the latest line, in the piece's (u,v), and the curve of each (an index
  // into PieceTrim::segments).
  const std::vector<Vec2>& Points() const { return points_; }
  const std::vector<int>& Curves() const { return curves_; }
  // Where line ys crosses the B-rep edge curve `curve` runs along, nearest the screen x of
  // the curve's own crossing (EdgeCrossings::Nearest); NaN where the curve is no edge's.
  double EdgeX(int curve, double ys, double x) const {
    const int e = edgeOfCurve_[static_cast<std::size_t>(curve)];
    return e < 0 ? NAN : edges_[static_cast<std::size_t>(e)].Nearest(ys, x);
  }
  const std::vector<TrimPiece>& Pieces() const { return pieces_; }
  // Trackers born and died so far.
  long Events() const { return events_; }

 private:
  struct Tracker {
    int piece;
    double t, tPrev, tPrev2;
    int nSolved;
  };

 public:
  // What Advance changes (as EdgeScan::State).
  struct State {
    std::vector<Tracker> trackers;
    std::vector<Vec2> points;
    std::vector<int> curves;
    std::size_t nextPiece = 0;
    long events = 0;
  };
  void Save(State* s) const {
    s->trackers = trackers_, s->points = points_, s->curves = curves_, s->nextPiece = nextPiece_, s->events = events_;
  }
  void Restore(const State& s) {
    trackers_ = s.trackers, points_ = s.points, curves_ = s.curves, nextPiece_ = s.nextPiece, events_ = s.events;
  }

 private:
  const Surface& surface_;
  const PieceTrim& trim_;
  const ScreenMap& map_;
  Counters& counters_;
  bool extrapolate_;
  double tolerancePx_;
  std::vector<TrimPiece> pieces_;  // sorted by yTop
  std::vector<Tracker> trackers_;
  std::vector<Vec2> points_;
  std::vector<int> curves_;
  std::vector<EdgeCrossings> edges_;   // the distinct edges the curves run along
  std::vector<int> edgeOfCurve_;       // per curve: an index into edges_, or -1
  std::size_t nextPiece_ = 0;
  long events_ = 0;
};

}  // namespace patchscan
