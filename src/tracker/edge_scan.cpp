#include "tracker/edge_scan.h"

#include "tracker/monotone_curve.h"

#include <algorithm>
#include <cmath>

namespace patchscan {
namespace {

// y along the edge and its first two derivatives in t, and J, at t; of an evaluation of
// `order`, what it gives (NaN the rest): a Newton step needs y and y_t, a tracker's
// prediction y_tt too. A subdivision face's second derivatives cost two more evaluations.
struct EdgeSample {
  double y, yt = NAN, ytt = NAN, j = NAN;
  double tangent = NAN, across = NAN;  // |dp/dt| and |dp/d(other)| in screen space
};

template <class ShapeT>
EdgeSample SampleEdge(const ShapeT& shape, const ScreenMap& map, PatchEdge e, double t,
                      DerivOrder order = DerivOrder::Second) {
  const Vec2 uv = EdgePoint(e, t);
  ScreenDerivs d;
  EvaluateScreen(shape, map, uv.x(), uv.y(), order, &d);
  if (!Wants(order, DerivOrder::First)) return {d.p.y()};
  const bool alongV = e == PatchEdge::U0 || e == PatchEdge::U1;
  const Vec3& pt = alongV ? d.dpdv : d.dpdu;
  const Vec3& across = alongV ? d.dpdu : d.dpdv;
  const double ytt = Wants(order, DerivOrder::Second) ? (alongV ? d.d2pdv2 : d.d2pdu2).y() : NAN;
  return {d.p.y(), pt.y(), ytt, SilhouetteJ(d), pt.head<2>().norm(), across.head<2>().norm()};
}

// Where a tracker's Newton iteration starts on scan line yNext. Paper 001 §3.5 extrapolates
// the solutions of the last lines (ExtrapolatedStart, which assumes equal steps); here t is
// predicted as a function of screen y from what the evaluations at the last two solutions
// already gave (y, y_t, y_tt), so no evaluation is added:
//  - the next line one step on (the steps equal, as in the exact scan): the cubic Hermite
//    interpolant of t(y) through both solutions with slopes 1 / y_t, extended one step
//    (error O(h^4); quadratic extrapolation errs by O(h^3));
//  - else (the first step, or a θ scan's longer steps between sampled lines): the inverse's
//    second-order Taylor expansion t + dy / y_t - y_tt dy^2 / (2 y_t^3), its second term
//    dropped where it exceeds half the first (near a turn of y along the edge, where the
//    expansion no longer holds).
// Measured on the teapot at 1024x768 (--stats newton_iterations_per_tracker_row, edge and
// silhouette trackers together): exact aa 3 1.199 -> 0.813, θ aa 4 2.103 -> 0.847; the
// images the same bit for bit.
double PredictedStart(const EdgeTracker& tr, double yNext, double tolerancePx) {
  if (tr.nSolved < 1 || !(std::abs(tr.yt) > 0.0))
    return ExtrapolatedStart(tr.t, tr.tPrev, tr.tPrev2, tr.nSolved, tolerancePx <= kQuadraticExtrapolationTolPx);
  const double h = tr.y - tr.yPrev;
  // The next line's place in steps of the last: 2 when the steps are equal (the solutions'
  // y are within the tolerance of their lines, hence the slack).
  constexpr double kEqualStepSlack = 1e-3;
  const double s = std::abs(h) > 0.0 ? (yNext - tr.yPrev) / h : 0.0;
  if (tr.nSolved >= 2 && std::abs(tr.ytPrev) > 0.0 && s > 1.0 && s <= 2.0 + kEqualStepSlack) {
    const double s2 = s * s, s3 = s2 * s;
    return (2 * s3 - 3 * s2 + 1) * tr.tPrev + (s3 - 2 * s2 + s) * h / tr.ytPrev + (-2 * s3 + 3 * s2) * tr.t +
           (s3 - s2) * h / tr.yt;
  }
  const double dy = yNext - tr.y, inv = 1.0 / tr.yt;
  const double first = dy * inv, second = -0.5 * tr.ytt * dy * dy * inv * inv * inv;
  return tr.t + first + (std::abs(second) <= 0.5 * std::abs(first) ? second : 0.0);
}

template <class ShapeT>
std::vector<EdgePiece> Pieces(const ShapeT& shape, const ScreenMap& map, PatchEdge e, double* collapsedY) {
  // Step 1: collapsed edges (kCollapsedRel everywhere along them) have no crossing to track.
  bool collapsed = true;
  for (int k = 0; k <= 4 && collapsed; ++k) {
    const EdgeSample s = SampleEdge(shape, map, e, k / 4.0, DerivOrder::First);
    collapsed = s.tangent <= kCollapsedRel * std::max(s.across, 1e-300);
  }
  if (collapsedY) *collapsedY = collapsed ? SampleEdge(shape, map, e, 0.5, DerivOrder::Position).y : NAN;
  if (collapsed) return {};
  // Step 2: critical points of y(t): sign changes of y_t between samples, refined by
  // Newton on y_t = 0 inside the bracket (bisection when Newton leaves it): the samples
  // need y_t alone, Newton y_tt too.
  std::vector<double> cuts = {0.0};
  SignChanges([&](double t) { return SampleEdge(shape, map, e, t, DerivOrder::First).yt; },
              [&](double t) {
                const EdgeSample s = SampleEdge(shape, map, e, t);
                return std::pair(s.yt, s.ytt);
              },
              0.0, 1.0, kEdgeCriticalSamples, &cuts);
  cuts.push_back(1.0);
  std::vector<EdgePiece> pieces;
  for (size_t k = 0; k + 1 < cuts.size(); ++k) {
    const double ya = SampleEdge(shape, map, e, cuts[k], DerivOrder::Position).y,
                 yb = SampleEdge(shape, map, e, cuts[k + 1], DerivOrder::Position).y;
    if (cuts[k + 1] > cuts[k]) pieces.push_back({e, cuts[k], cuts[k + 1], std::min(ya, yb), std::max(ya, yb)});
  }
  return pieces;
}

}  // namespace

std::vector<EdgePiece> MonotoneEdgePieces(const Surface& s, const ScreenMap& map, PatchEdge e, double* collapsedY) {
  return VisitShape(s, [&](const auto& shape) { return Pieces(shape, map, e, collapsedY); });
}

EdgeScan::EdgeScan(const Surface& s, const ScreenMap& map, Counters& counters, bool extrapolate, double tolerancePx)
    : surface_(s), map_(map), extrapolate_(extrapolate), tolerancePx_(tolerancePx), counters_(counters) {
  for (PatchEdge e : {PatchEdge::U0, PatchEdge::U1, PatchEdge::V0, PatchEdge::V1}) {
    double collapsedY = NAN;
    const auto p = MonotoneEdgePieces(s, map, e, &collapsedY);
    pieces_.insert(pieces_.end(), p.begin(), p.end());
    if (std::isfinite(collapsedY)) degenerate_.emplace_back(collapsedY - kDegenerateNearPx, collapsedY + kDegenerateNearPx);
    for (const EdgePiece& q : p)
      if (q.yBottom - q.yTop <= kFlatPiecePx) degenerate_.emplace_back(q.yTop - kDegenerateNearPx, q.yBottom + kDegenerateNearPx);
  }
  // Merged into disjoint ranges (a flat edge's noise pieces are one range).
  std::sort(degenerate_.begin(), degenerate_.end());
  std::size_t n = 0;
  for (const auto& r : degenerate_) {
    if (n > 0 && r.first <= degenerate_[n - 1].second) degenerate_[n - 1].second = std::max(degenerate_[n - 1].second, r.second);
    else degenerate_[n++] = r;
  }
  degenerate_.resize(n);
  std::stable_sort(pieces_.begin(), pieces_.end(),
                   [](const EdgePiece& a, const EdgePiece& b) { return a.yTop < b.yTop; });
  trackers_.reserve(pieces_.size());
  folds_.reserve(2 * pieces_.size());
  deaths_.reserve(pieces_.size());
}

void EdgeScan::Advance(double yScan) {
  VisitShape(surface_, [&](const auto& shape) {
    // Step 1: delete trackers whose piece the scan line has left (a minimum, §3.2.3).
    folds_.clear();
    deaths_.clear();
    std::erase_if(trackers_, [&](const EdgeTracker& t) {
      const EdgePiece& p = pieces_[t.piece];
      if (p.yBottom >= yScan) return false;
      ++counters_[Counter::EdgeDied];
      ++events_;
      deaths_.push_back(EdgePoint(p.edge, t.t));
      const double bottom = SampleEdge(shape, map_, p.edge, p.t0, DerivOrder::Position).y >= p.yBottom ? p.t0 : p.t1;
      const double j = SampleEdge(shape, map_, p.edge, bottom, DerivOrder::First).j;
      if ((j > 0 && t.j < 0) || (j < 0 && t.j > 0)) {
        folds_.push_back(EdgePoint(p.edge, bottom));
        ++counters_[Counter::Folds];
        ++events_;
      }
      return true;
    });
    // Step 2: create trackers on pieces whose top the scan line has passed (§3.2.2).
    for (; nextPiece_ < pieces_.size() && pieces_[nextPiece_].yTop <= yScan; ++nextPiece_) {
      if (pieces_[nextPiece_].yBottom < yScan) continue;  // passed between two lines
      const EdgePiece& p = pieces_[nextPiece_];
      const double yAt0 = SampleEdge(shape, map_, p.edge, p.t0, DerivOrder::Position).y;
      const double top = yAt0 <= p.yTop ? p.t0 : p.t1;
      // J at the piece's top, where the tracker is born: a silhouette that crosses the
      // edge between the top and the first scan line is a fold too.
      trackers_.push_back({static_cast<int>(nextPiece_), top, top, false, SampleEdge(shape, map_, p.edge, top, DerivOrder::First).j});
      ++counters_[Counter::EdgeBorn];
      ++events_;
    }
    // Step 3: Newton from the extrapolated start (§3.5), bisection on the piece if it fails.
    for (EdgeTracker& tr : trackers_) {
      const EdgePiece& p = pieces_[tr.piece];
      const double start = extrapolate_ ? PredictedStart(tr, yScan, tolerancePx_) : tr.t;
      auto f = [&](double t, double* v, double* d) {
        const EdgeSample s = SampleEdge(shape, map_, p.edge, t, DerivOrder::First);
        *v = s.y - yScan;
        *d = s.yt;
      };
      // The piece is monotone and holds yScan, so it brackets the crossing: bisection
      // there seeds a new tracker (whose start is a critical point, where Newton divides
      // by zero) and repairs a failed Newton step.
      if (tr.hasPrev) ++counters_[Counter::EdgeNewtonCalls];
      bool repaired = false;
      const double t = TrackOnPiece(f, p.t0, p.t1, start, tr.hasPrev, tolerancePx_,
                                    &counters_[Counter::EdgeNewtonIterations], &repaired);
      if (repaired) {
        ++counters_[Counter::EdgeRepairs];
        ++events_;
      }
      const EdgeSample at = SampleEdge(shape, map_, p.edge, t);
      const double j = at.j;
      tr.folded = (j > 0 && tr.j < 0) || (j < 0 && tr.j > 0);
      counters_[Counter::Folds] += tr.folded;
      events_ += tr.folded;
      if (tr.folded) folds_.push_back(EdgePoint(p.edge, t));
      tr.j = j;
      tr.tPrev2 = tr.tPrev;
      tr.tPrev = tr.hasPrev ? tr.t : t;
      tr.yPrev = tr.y;
      tr.ytPrev = tr.yt;
      tr.y = at.y;
      tr.yt = at.yt;
      tr.ytt = at.ytt;
      ++tr.nSolved;
      tr.t = t;
      tr.hasPrev = true;
    }
  });
}

}  // namespace patchscan
