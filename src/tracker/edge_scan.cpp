#include "tracker/edge_scan.h"

#include "core/hermite.h"
#include "tracker/monotone_curve.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <type_traits>

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
// images the same bit for bit. `yttAt()` gives y_tt at the last solution: asked only by
// the expansion, so that equal steps cost no second-order evaluation.
template <class YttAt>
double PredictedStart(const EdgeTracker& tr, double yNext, double tolerancePx, YttAt&& yttAt) {
  if (tr.nSolved < 1 || !(std::abs(tr.yt) > 0.0))
    return ExtrapolatedStart(tr.t, tr.tPrev, tr.tPrev2, tr.nSolved, tolerancePx <= kQuadraticExtrapolationTolPx);
  const double h = tr.y - tr.yPrev;
  // The next line's place in steps of the last: 2 when the steps are equal (the solutions'
  // y are within the tolerance of their lines, hence the slack).
  constexpr double kEqualStepSlack = 1e-3;
  const double s = std::abs(h) > 0.0 ? (yNext - tr.yPrev) / h : 0.0;
  if (tr.nSolved >= 2 && std::abs(tr.ytPrev) > 0.0 && s > 1.0 && s <= 2.0 + kEqualStepSlack) {
    const HermiteBlend w = HermiteWeights(s);
    return w.w0 * tr.tPrev + w.w1 * h / tr.ytPrev + w.w2 * tr.t + w.w3 * h / tr.yt;
  }
  const double dy = yNext - tr.y, inv = 1.0 / tr.yt;
  const double first = dy * inv, second = -0.5 * yttAt() * dy * dy * inv * inv * inv;
  return tr.t + first + (std::abs(second) <= 0.5 * std::abs(first) ? second : 0.0);
}

// Edge e cut where the shape's evaluation changes polynomial: span k is [breaks[k],
// breaks[k + 1]], and cubic[k] says the shape evaluates one polynomial of degree <= 3 in t
// there. A bicubic patch's edge (any basis) or a bilinear one's is one cubic span; a
// subdivision face's has one span per fitted piece along it (a bicubic, or a Gregory patch
// at an extraordinary corner, whose boundary curves are cubics) and one per quarter that
// Bfr evaluates; any other shape's edge is one span, not cubic.
struct EdgeSpans {
  int n = 1;
  std::array<double, 5> breaks{0.0, 1.0};
  std::array<bool, 4> cubic{};
};

template <class ShapeT>
EdgeSpans SpansOf(const ShapeT& shape, PatchEdge e) {
  EdgeSpans spans;
  if constexpr (std::is_same_v<ShapeT, BicubicPatch> || std::is_same_v<ShapeT, BilinearPatch>) {
    spans.cubic[0] = true;
  } else if constexpr (std::is_same_v<ShapeT, SubdivFace>) {
    spans.n = 0;
    for (int q = 0, last = -1; q < 4; ++q) {  // the pieces are fitted per quarter of the domain
      const Vec2 uv = EdgePoint(e, (q + 0.5) / 4.0);
      const int k = shape.PieceAt(uv.x(), uv.y());
      if (k < 0 || k != last) {
        spans.breaks[static_cast<std::size_t>(spans.n)] = q / 4.0;
        spans.cubic[static_cast<std::size_t>(spans.n++)] = k >= 0;
      }
      last = k;
    }
    spans.breaks[static_cast<std::size_t>(spans.n)] = 1.0;
  }
  return spans;
}

// The sign of y_t on [a, b], a span of edge e where the object point p(t) is a polynomial
// of degree <= 3, if it is proven not to change; else 0. The homogeneous screen point
// (X, Y, D, W) = M (p, 1) is such a polynomial too, and y_t = (Y_t W - Y W_t) / W^2 whose
// numerator N has degree <= 4 (the t^5 terms cancel). N is found from five evaluations
// inside the span and written in the Bernstein basis there: coefficients all of one sign,
// each beyond kMonotoneMargin of the magnitudes of the terms N is summed from (rounding),
// bound N away from 0 on the span (the convex-hull property), so y has no critical point
// there.
constexpr double kMonotoneMargin = 1e-9;

template <class ShapeT>
int MonotoneSign(const ShapeT& shape, const ScreenMap& map, PatchEdge e, double a, double b) {
  // Nodes s_i = (2 i + 1) / 10 inside the span, and the inverse of the quartic Bernstein
  // basis at them: coefficients = kToBernstein * (N at the nodes).
  static const Eigen::Matrix<double, 5, 5> kToBernstein = [] {
    Eigen::Matrix<double, 5, 5> basis;
    constexpr double kBinomial[5] = {1, 4, 6, 4, 1};
    for (int i = 0; i < 5; ++i) {
      const double s = (2 * i + 1) / 10.0;
      for (int j = 0; j < 5; ++j) basis(i, j) = kBinomial[j] * std::pow(s, j) * std::pow(1.0 - s, 4 - j);
    }
    return Eigen::Matrix<double, 5, 5>(basis.inverse());
  }();
  const Mat4& m = map.ScreenFromObject();
  const Vec4 rowAbs = m.block<4, 3>(0, 0).cwiseAbs().rowwise().sum();
  const bool alongV = e == PatchEdge::U0 || e == PatchEdge::U1;
  Eigen::Matrix<double, 5, 1> n;
  double scale = 0.0;
  for (int i = 0; i < 5; ++i) {
    const Vec2 uv = EdgePoint(e, a + (b - a) * (2 * i + 1) / 10.0);
    SurfaceDerivs d;
    shape.Evaluate(uv.x(), uv.y(), DerivOrder::First, &d);
    const Vec3& pt = alongV ? d.dpdv : d.dpdu;
    const Vec4 h = m.block<4, 3>(0, 0) * d.p + m.col(3);
    const Vec4 ht = m.block<4, 3>(0, 0) * pt;
    n[i] = ht.y() * h.w() - h.y() * ht.w();
    // What rounding scales with: the magnitudes of the terms, the point's and tangent's
    // largest coordinate standing for each of their coordinates (an edge level on the
    // screen has a tangent whose y is the evaluation's rounding, and N of rounding alone).
    const Vec4 hAbs = rowAbs * d.p.cwiseAbs().maxCoeff() + m.col(3).cwiseAbs();
    const Vec4 htAbs = rowAbs * pt.cwiseAbs().maxCoeff();
    scale = std::max(scale, htAbs.y() * hAbs.w() + hAbs.y() * htAbs.w());
  }
  const Eigen::Matrix<double, 5, 1> c = kToBernstein * n;
  const double margin = kMonotoneMargin * scale;
  return (c.array() > margin).all() ? 1 : (c.array() < -margin).all() ? -1 : 0;
}

// The signs MonotoneSign proves on the edge's spans (0: not proven); two proven
// neighbours of opposite signs would meet at a critical point, so neither counts.
template <class ShapeT>
std::array<int, 4> SpanSigns(const ShapeT& shape, const ScreenMap& map, PatchEdge e, const EdgeSpans& spans) {
  std::array<int, 4> sign{};
  for (std::size_t k = 0; k < static_cast<std::size_t>(spans.n); ++k)
    if (spans.cubic[k]) sign[k] = MonotoneSign(shape, map, e, spans.breaks[k], spans.breaks[k + 1]);
  for (std::size_t k = 0; k + 1 < static_cast<std::size_t>(spans.n); ++k)
    if (sign[k] * sign[k + 1] < 0) sign[k] = sign[k + 1] = 0;
  return sign;
}

// The critical points of y along edge e, appended to *cuts in increasing order: none on
// the spans MonotoneSign proves, and on each run of the others the sign changes of y_t
// between samples kEdgeCriticalSamples to the edge apart, refined by Newton on y_t = 0
// inside the bracket (bisection when Newton leaves it); the samples need y_t alone, Newton
// y_tt too. The samples are those of the whole edge's sampling, and a proven span has no
// sign change among them (its ends' y_t are beyond the margin, and the neighbouring
// piece's y_t agrees there to rounding: both pieces are the limit surface), so the cuts
// are the ones sampling the whole edge finds, for a fraction of the evaluations where
// the edge is cubic.
template <class ShapeT>
void CriticalPoints(const ShapeT& shape, const ScreenMap& map, PatchEdge e, EdgeSampling sampling,
                    std::vector<double>* cuts) {
  const EdgeSpans spans = sampling == EdgeSampling::SampleAll ? EdgeSpans{} : SpansOf(shape, e);
  const std::array<int, 4> sign = SpanSigns(shape, map, e, spans);
  for (int k = 0; k < spans.n;) {
    if (sign[static_cast<std::size_t>(k)] != 0) {
      ++k;
      continue;
    }
    const double t0 = spans.breaks[static_cast<std::size_t>(k)];
    while (k < spans.n && sign[static_cast<std::size_t>(k)] == 0) ++k;
    const double t1 = spans.breaks[static_cast<std::size_t>(k)];
    const int samples = static_cast<int>(std::lround(kEdgeCriticalSamples * (t1 - t0)));
    SignChanges([&](double t) { return SampleEdge(shape, map, e, t, DerivOrder::First).yt; },
                [&](double t) {
                  const EdgeSample s = SampleEdge(shape, map, e, t);
                  return std::pair(s.yt, s.ytt);
                },
                t0, t1, samples, cuts);
  }
}

template <class ShapeT>
std::vector<EdgePiece> Pieces(const ShapeT& shape, const ScreenMap& map, PatchEdge e, double* collapsedY,
                              EdgeSampling sampling) {
  // Step 1: collapsed edges (kCollapsedRel everywhere along them) have no crossing to track.
  bool collapsed = true;
  for (int k = 0; k <= 4 && collapsed; ++k) {
    const EdgeSample s = SampleEdge(shape, map, e, k / 4.0, DerivOrder::First);
    collapsed = s.tangent <= kCollapsedRel * std::max(s.across, 1e-300);
  }
  if (collapsedY) *collapsedY = collapsed ? SampleEdge(shape, map, e, 0.5, DerivOrder::Position).y : NAN;
  if (collapsed) return {};
  // Step 2: the critical points of y(t).
  std::vector<double> cuts = {0.0};
  CriticalPoints(shape, map, e, sampling, &cuts);
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

std::vector<EdgePiece> MonotoneEdgePieces(const Surface& s, const ScreenMap& map, PatchEdge e, double* collapsedY,
                                          EdgeSampling sampling) {
  return VisitShape(s, [&](const auto& shape) { return Pieces(shape, map, e, collapsedY, sampling); });
}

bool EdgeProvenMonotone(const Surface& s, const ScreenMap& map, PatchEdge e) {
  return VisitShape(s, [&](const auto& shape) {
    const EdgeSpans spans = SpansOf(shape, e);
    const std::array<int, 4> sign = SpanSigns(shape, map, e, spans);
    return std::all_of(sign.begin(), sign.begin() + spans.n, [](int g) { return g != 0; });
  });
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
    // Step 3: Newton from the extrapolated start (§3.5), CrossingOnPiece if it fails.
    for (EdgeTracker& tr : trackers_) {
      const EdgePiece& p = pieces_[tr.piece];
      const auto yttAtLast = [&] { return SampleEdge(shape, map_, p.edge, tr.t, DerivOrder::Second).ytt; };
      const double start = extrapolate_ ? PredictedStart(tr, yScan, tolerancePx_, yttAtLast) : tr.t;
      EdgeSample last{NAN};  // the solve's latest evaluation, at lastT
      double lastT = NAN;
      auto f = [&](double t, double* v, double* d) {
        last = SampleEdge(shape, map_, p.edge, t, DerivOrder::First);
        lastT = t;
        *v = last.y - yScan;
        *d = last.yt;
      };
      // The piece is monotone and holds yScan, so it brackets the crossing: Newton kept
      // inside it (CrossingOnPiece) seeds a new tracker (whose start is a critical point,
      // where plain Newton divides by zero) and repairs a failed Newton step.
      if (tr.hasPrev) ++counters_[Counter::EdgeNewtonCalls];
      bool repaired = false;
      const double t = TrackOnPiece(f, p.t0, p.t1, start, tr.hasPrev, tolerancePx_,
                                    &counters_[Counter::EdgeNewtonIterations], &repaired);
      if (repaired) {
        ++counters_[Counter::EdgeRepairs];
        ++events_;
      }
      // y, y_t and J at the solution: Newton's last evaluation was there (a bracketed search
      // may end on a point it did not evaluate); y_tt only if the next prediction asks.
      const EdgeSample at = t == lastT ? last : SampleEdge(shape, map_, p.edge, t, DerivOrder::First);
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
      ++tr.nSolved;
      tr.t = t;
      tr.hasPrev = true;
    }
  });
}

}  // namespace patchscan
