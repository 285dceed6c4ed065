// Silhouette trackers of the Y scan (Blinn 1978 §3.2.1–3.2.3): the points where the scan
// line crosses the silhouette J = 0 inside the domain, advanced scan line by scan line by
// bivariate Newton on (y - yScan, J) = 0 from a start extrapolated from the last two
// positions (§3.5).
//
// Trackers are created when the scan line passes a strict maximum (two seeds on the
// ellipse that approximates the level curve there, §3.2.2.2), when a boundary-edge
// tracker's J changes sign (a fold, §3.2.2.3) and when it passes a saddle (seeds on the
// hyperbola there, §3.2.2.4); they are deleted when Newton fails (a minimum, §3.2.3) or
// leaves [0,1]^2.
#pragma once

#include <vector>

#include "tracker/edge_scan.h"
#include "tracker/maxima.h"

namespace patchscan {

struct SilhouetteTracker {
  Vec2 uv, uvPrev;
  bool hasPrev = false;
  Vec2 uvPrev2 = Vec2::Zero();  // the scan line before the previous one (when nSolved >= 3)
  int nSolved = 1;                // scan lines on which this tracker has been solved
  double y = NAN, yPrev = NAN, yPrev2 = NAN;  // the scan lines of uv, uvPrev and uvPrev2
};

// Both equations are solved in pixels: y - yScan, and J / max(|s_u|, |s_v|), to the edge
// trackers' tolerance kEdgeTolPx.
// Two trackers closer than this in (u,v) are the same crossing.
constexpr double kSameTrackerUv = 1e-7;

// F = (y - yScan, J / max(|s_u|, |s_v|)) and its Jacobian at uv; `derivs`, when given,
// receives the screen derivatives they were made from.
template <class ShapeT>
inline void SilhouetteSystem(const ShapeT& shape, const ScreenMap& map, double yScan, const Vec2& uv,
                             Vec2* f, Mat2* jac, ScreenDerivs* derivs = nullptr) {
  ScreenDerivs local;
  ScreenDerivs& d = derivs ? *derivs : local;
  EvaluateScreen(shape, map, uv.x(), uv.y(), DerivOrder::Second, &d);
  const Vec2 su = d.dpdu.head<2>(), sv = d.dpdv.head<2>();
  // J / max(|s_u|, |s_v|) is in pixels, like y - yScan, so one tolerance and the
  // damping's residual compare like with like.
  const double norm = std::max(std::max(su.norm(), sv.norm()), 1e-300);
  const double j = su.x() * sv.y() - sv.x() * su.y();
  // dJ/du = x_uu y_v + x_u y_uv - x_uv y_u - x_v y_uu; dJ/dv likewise. The normalization
  // is treated as constant in the Jacobian: it changes only the step length, not the root.
  const double ju = d.d2pdu2.x() * sv.y() + su.x() * d.d2pduv.y() - d.d2pduv.x() * su.y() -
                    sv.x() * d.d2pdu2.y();
  const double jv = d.d2pduv.x() * sv.y() + su.x() * d.d2pdv2.y() - d.d2pdv2.x() * su.y() -
                    sv.x() * d.d2pduv.y();
  *f = Vec2(d.p.y() - yScan, j / norm);
  *jac << su.y(), sv.y(), ju / norm, jv / norm;
}

class SilhouetteScan {
 public:
  // `stationary`: the surface's maxima and saddles (FindStationaryPoints). Counts into
  // `counters`, which must outlive the scan.
  SilhouetteScan(const Surface& s, const ScreenMap& map, std::vector<Stationary> stationary, Counters& counters,
                 bool extrapolate = true);

  // Moves to scan line yScan (non-decreasing); `edges` must already be at yScan (its
  // folds create trackers here).
  void Advance(double yScan, const EdgeScan& edges);

  // Takes up a crossing of the current scan line found by other means (the X scan's walk
  // along the level curve passed a silhouette no tracker held): a repair, tracked from
  // the next scan line on. Ignored if a tracker is already there.
  void Adopt(const Vec2& uv);

  const std::vector<SilhouetteTracker>& Trackers() const { return trackers_; }
  // Whether no tracker is alive and no maximum or saddle is left below the scan line: then
  // none can be born but at a fold, where an edge tracker crosses a silhouette.
  bool Done() const { return trackers_.empty() && nextStationary_ == stationary_.size(); }
  // Events so far: trackers born, died, left, merged and adopted, searches (as
  // EdgeScan::Events).
  long Events() const { return events_; }
  // Where trackers were born and where they died (their last position) at the latest
  // Advance.
  const std::vector<Vec2>& Births() const { return births_; }
  const std::vector<Vec2>& Deaths() const { return deaths_; }

  // What Advance and Adopt change (as EdgeScan::State).
  struct State {
    std::vector<SilhouetteTracker> trackers;
    std::vector<Vec2> births, deaths;
    size_t nextStationary = 0;
    double yLast = NAN;
    long events = 0;
  };
  void Save(State* s) const {
    s->trackers = trackers_, s->births = births_, s->deaths = deaths_;
    s->nextStationary = nextStationary_, s->yLast = yLast_, s->events = events_;
  }
  void Restore(const State& s) {
    trackers_ = s.trackers, births_ = s.births, deaths_ = s.deaths;
    nextStationary_ = s.nextStationary, yLast_ = s.yLast, events_ = s.events;
  }

 private:
  template <class ShapeT>
  void AdvanceImpl(const ShapeT& shape, double yScan, const EdgeScan& edges);
  template <class ShapeT>
  bool Solve(const ShapeT& shape, double yScan, const Vec2& start, Vec2* uv, DomainRule domain);
  // Whether a tracker is already at uv (within kSameTrackerUv).
  bool Tracked(const Vec2& uv) const;
  // Tracks what the latest search found that no tracker holds.
  void AddFound();
  // A tracker at uv on the latest scan line.
  SilhouetteTracker NewTracker(const Vec2& uv) const {
    SilhouetteTracker t{uv, uv, false};
    t.y = yLast_;
    return t;
  }

  const Surface& surface_;
  const ScreenMap& map_;
  std::vector<Stationary> stationary_;  // maxima and saddles, by y
  size_t nextStationary_ = 0;
  bool extrapolate_;
  std::vector<SilhouetteTracker> trackers_;
  std::vector<Vec2> births_, deaths_, searchFound_;
  std::vector<unsigned> exits_;  // the latest Advance's trackers that left: their boundary edges
  // The latest Advance's trackers that died inside the domain: where they were, where their
  // iteration failed, and the one they met (index; -1: none).
  struct InsideDeath {
    Vec2 last, failed;
    int partner;
  };
  std::vector<InsideDeath> insideDeaths_;
  Counters& counters_;
  double yLast_ = NAN;  // the latest scan line
  long events_ = 0;
};

// The crossings of scan line yScan with the silhouette found by the trackers' repair
// search: the domain subdivided while a cell's conservative y range holds yScan, Newton
// from cells under two pixels on the screen. Collapsed edges are not silhouettes. With a
// square [u0, u0 + side] x [v0, v0 + side] of the domain, that square alone (as searched
// around two trackers that met).
std::vector<Vec2> SilhouetteCrossingsBySubdivision(const Surface& s, const ScreenMap& map, double yScan,
                                                   double u0 = 0.0, double v0 = 0.0, double side = 1.0);

// All solutions of y = yScan, J = 0 in [0,1]^2 found by Newton from a grid of starts and
// merged: slow and independent of any tracking, for tests and repairs.
std::vector<Vec2> SilhouetteCrossingsBruteForce(const Surface& s, const ScreenMap& map,
                                                 double yScan, int grid = 48);

}  // namespace patchscan
