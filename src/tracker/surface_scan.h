// One surface's Y scan (Blinn 1978 §3.2): the maxima pre-pass when the scan reaches the
// surface, then line by line its boundary-edge and silhouette trackers advanced by Newton,
// with the events of the scan (births at maxima, folds and saddles, deaths, repairs). The
// exact and θ X scans both start from its trackers; a worker owns the scans of its share
// of the surfaces.
#pragma once

#include <algorithm>
#include <cmath>
#include <memory>
#include <vector>

#include "core/counters.h"
#include "patch/camera.h"
#include "patch/screen.h"
#include "patch/surface.h"
#include "tracker/edge_scan.h"
#include "tracker/maxima.h"
#include "tracker/silhouette_scan.h"
#include "tracker/trim_scan.h"

namespace patchscan {

// A scan line's trackers of one surface: where the X scan's walks start.
struct RowTrackers {
  std::vector<Vec2> edgePoints;        // on the boundary, y = ys
  std::vector<PatchEdge> edgeOf;       // per edge point
  std::vector<Vec2> silhouettePoints;  // inside, y = ys and J = 0
  std::vector<Vec2> trimPoints;        // on a trim curve, y = ys (trimmed surfaces)
  std::vector<double> trimX;           // their screen x
  std::vector<double> trimEdgeX;       // the screen x of the B-rep edge each runs along
                                       // (TrimScan::EdgeX), NaN where none
  void Clear() {
    edgePoints.clear();
    edgeOf.clear();
    silhouettePoints.clear();
    trimPoints.clear();
    trimX.clear();
    trimEdgeX.clear();
  }
};

// A maximum or saddle of the pre-pass where the screen shows it.
struct ScreenStationary {
  bool saddle;
  Vec2 p;  // screen x, y
};

// The step by which SurfaceScan::LineFor moves a degenerate line: a few times the width
// of a degenerate range, so that one step leaves it.
constexpr double kDegenerateStepPx = 4.0 * kDegenerateNearPx;

class SurfaceScan {
 public:
  // Sets up the Y scan of `surface` seen by `camera`: the maxima pre-pass and the edges'
  // monotone pieces. `extrapolate`: start each tracker's Newton from its last lines (§3.5).
  // Counts into `counters`. `surface` and `counters` must outlive the scan.
  SurfaceScan(const Surface& surface, const Camera& camera, bool extrapolate, Counters& counters);
  SurfaceScan(const SurfaceScan&) = delete;
  SurfaceScan& operator=(const SurfaceScan&) = delete;

  // The topmost maximum's y (+inf if the pre-pass found none): where the scan begins.
  double Top() const { return yTop_; }
  // Where the surface can first meet a scan line: its topmost maximum or the top of its
  // topmost edge piece (the top of a compact surface is one of them). Above it the scan
  // has no tracker and none is born, so the X scan finds nothing there. -inf for a trimmed
  // surface (its trim curves' trackers are not looked at).
  double FirstY() const { return trims_ ? -INFINITY : std::min(yTop_, edges_.FirstTop()); }
  // Whether the scan has passed all of the surface: no tracker of its edges or silhouettes
  // alive and none left to be born (no edge piece left to begin, no maximum or saddle
  // below; a fold needs a live edge tracker, and a tracker adopted from the X scan a walk,
  // which needs a tracker). False for a trimmed surface.
  bool Done() const { return !trims_ && edges_.Done() && silhouettes_.Done(); }
  // For a scan that begins at line yStart below Top() (the surface's top is above the
  // image, or between two lines): advances the trackers from Top() towards yStart in steps
  // of max(spacing, 1) px, so that they are born where the seeds of §3.2.2 are good.
  void StartAt(double yStart, double spacing);

  // The line the scan takes for sample row y: y itself, unless y meets a degenerate level
  // set (EdgeScan::DegenerateRanges: a boundary edge lying along the line, a collapsed
  // edge's point on it, as a full sphere seen along its axis has both on its centre row);
  // then the nearest line below it by steps of kDegenerateStepPx that does not. Symbolic
  // perturbation: the level curves there are curves again, and the samples move by at most
  // a few steps times |dx/dy| of a silhouette, far below the 1e-3 px exact mode allows
  // (except at a silhouette's very top, where a tangency is ambiguous anyway). A function of
  // y and the surface alone, so every worker and every slab takes the same line.
  double LineFor(double y) const;

  // Advances every tracker to line y (non-decreasing from call to call) and lists them in
  // Trackers(). Allocation-free once the lists have their size.
  void AdvanceTo(double y);
  const RowTrackers& Trackers() const { return row_; }

  // Events so far (births, deaths, folds, merges, adoptions, repairs): two calls that
  // return the same number bracket lines whose level curves kept their topology.
  long Events() const { return edges_.Events() + silhouettes_.Events() + (trims_ ? trims_->Events() : 0); }
  // The trim of a trimmed NURBS piece (null: the surface is whole).
  const PieceTrim* Trim() const { return TrimOf(surface_); }

  // Takes up a silhouette crossing of the current line that the X scan found and no
  // tracker held: tracked from the next line on.
  void Adopt(const Vec2& uv) { silhouettes_.Adopt(uv); }

  const Surface& Shape() const { return surface_; }
  const ScreenMap& Map() const { return map_; }
  const Mat3& NormalFromObject() const { return normalFromObject_; }  // world normals from dp/du x dp/dv
  // The pre-pass's maxima and saddles on the screen, by y.
  const std::vector<ScreenStationary>& StationaryOnScreen() const { return stationary_; }
  // The y ranges of the degenerate level sets LineFor steps off (EdgeScan::DegenerateRanges).
  const std::vector<std::pair<double, double>>& DegenerateRanges() const { return edges_.DegenerateRanges(); }
  // The trackers themselves (their folds, births and deaths at the latest line).
  const EdgeScan& Edges() const { return edges_; }
  const SilhouetteScan& Silhouettes() const { return silhouettes_; }

  // Everything AdvanceTo (and Adopt) change: Save, advance, and Restore returns the scan to
  // the line it saved, as if it had not moved (its counters keep the work done). θ slabs
  // advance a surface straight to the next line and come back for its rows when it needs
  // them. Allocation-free once a state's lists have their size.
  struct State {
    EdgeScan::State edges;
    SilhouetteScan::State silhouettes;
    TrimScan::State trims;
    RowTrackers row;
  };
  void Save(State* s) const;
  void Restore(const State& s);

 private:
  // The maxima pre-pass: fills stationary_ and yTop_, returns the points for the trackers.
  std::vector<Stationary> PrePass();

  const Surface& surface_;
  SurfaceHold hold_;  // the surface prepared while it is scanned (before the members that evaluate it)
  ScreenMap map_;
  Mat3 normalFromObject_;
  Counters& counters_;
  std::vector<ScreenStationary> stationary_;
  double yTop_ = 0.0;  // the topmost stationary point's y
  EdgeScan edges_;
  SilhouetteScan silhouettes_;
  std::unique_ptr<TrimScan> trims_;  // trimmed surfaces only
  RowTrackers row_;
};

}  // namespace patchscan
