#include "tracker/silhouette_scan.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>

#include "core/check.h"

namespace patchscan {
namespace {

bool OnBoundary(const Vec2& uv) {
  return uv.x() <= 0.0 || uv.x() >= 1.0 || uv.y() <= 0.0 || uv.y() >= 1.0;
}

// The boundary edges a point lies on, one bit each (u = 0, u = 1, v = 0, v = 1).
unsigned BoundarySides(const Vec2& uv) {
  return (uv.x() <= 0.0 ? 1u : 0u) | (uv.x() >= 1.0 ? 2u : 0u) | (uv.y() <= 0.0 ? 4u : 0u) |
         (uv.y() >= 1.0 ? 8u : 0u);
}

// The repair search: cells of the domain are split while the scan line can cross them
// (the cell's y range, from its corners grown by the second-order deviation of y from
// their interpolation, h^2/8 max|y''| doubled for safety, holds yScan) and so can the
// silhouette (the range of J / max(|s_u|, |s_v|) over its corners and centre, grown by
// its first-order change h/2 (|J_u| + |J_v|) to the farthest point of the cell, doubled
// for safety, holds 0); a cell under kSearchLeafPx on the screen is solved by Newton
// from its centre, and a solution inside it (grown by half its side) is a crossing.
// Every answer is a verified root.
constexpr double kSearchLeafPx = 2.0;
constexpr int kSearchMaxDepth = 12;

// What the search needs of the surface at one point of a cell.
struct SearchPoint {
  bool front;    // w > 0: in front of the eye (else no screen y)
  double y;      // screen y
  double bend;   // |y_uu| + 2 |y_uv| + |y_vv|
  double slope;  // max(|dp/du|, |dp/dv|) on the screen, pixels per unit of u or v
  double j;      // J / max(|s_u|, |s_v|), pixels (the silhouette function SilhouetteSystem solves)
  double jSlope;  // (|J_u| + |J_v|) / max(|s_u|, |s_v|), pixels per unit of u or v
};

template <class ShapeT>
SearchPoint EvalSearchPoint(const ShapeT& shape, const ScreenMap& map, double u, double v) {
  Vec2 f;
  Mat2 jac;
  ScreenDerivs d;
  SilhouetteSystem(shape, map, 0.0, Vec2(u, v), &f, &jac, &d);
  return {d.w > 0.0,
          d.p.y(),
          std::abs(d.d2pdu2.y()) + 2.0 * std::abs(d.d2pduv.y()) + std::abs(d.d2pdv2.y()),
          std::max(d.dpdu.head<2>().norm(), d.dpdv.head<2>().norm()),
          f.y(),
          std::abs(jac(1, 0)) + std::abs(jac(1, 1))};
}

// One cell [u0, u0 + h] x [v0, v0 + h], its corners (0,0), (1,0), (0,1), (1,1) already
// evaluated. Its four children share their corners with it and with each other (the
// cell's corners, centre and edge midpoints), so each split evaluates the four midpoints
// and each cell its centre. Cell coordinates are multiples of 2^-13 (kSearchMaxDepth),
// exact in double, so a shared point is the very point each child would evaluate.
template <class ShapeT>
void FindCrossingsInCell(const ShapeT& shape, const ScreenMap& map, double yScan, double u0, double v0, double h,
                         int depth, const std::array<SearchPoint, 4>& corner, std::vector<Vec2>* found) {
  const SearchPoint centre = EvalSearchPoint(shape, map, u0 + 0.5 * h, v0 + 0.5 * h);
  double lo = INFINITY, hi = -INFINITY, second = 0.0, slope = 0.0;
  double jLo = INFINITY, jHi = -INFINITY, jSlope = 0.0;
  for (int k = 0; k < 5; ++k) {
    const SearchPoint& c = k < 4 ? corner[static_cast<std::size_t>(k)] : centre;
    if (!c.front) return;  // behind the eye: no screen y
    if (k < 4) lo = std::min(lo, c.y), hi = std::max(hi, c.y);
    second = std::max(second, c.bend);
    slope = std::max(slope, c.slope);
    jLo = std::min(jLo, c.j), jHi = std::max(jHi, c.j);
    jSlope = std::max(jSlope, c.jSlope);
  }
  const double size = h * slope;
  const double margin = 2.0 * h * h / 8.0 * second;
  if (!std::isfinite(lo) || yScan < lo - margin || yScan > hi + margin) return;
  const double jMargin = 2.0 * 0.5 * h * jSlope;
  if (std::isfinite(jLo) && std::isfinite(jHi) && (jLo > jMargin || jHi < -jMargin)) return;
  if (size > kSearchLeafPx && depth < kSearchMaxDepth) {
    const double g = 0.5 * h;
    // The 3 x 3 grid of the children's corners, (i, j) at (u0 + i g, v0 + j g).
    std::array<SearchPoint, 9> grid;
    auto at = [&](int i, int j) -> SearchPoint& { return grid[static_cast<std::size_t>(3 * j + i)]; };
    at(0, 0) = corner[0], at(2, 0) = corner[1], at(0, 2) = corner[2], at(2, 2) = corner[3], at(1, 1) = centre;
    for (const auto& [i, j] : {std::pair{1, 0}, {0, 1}, {2, 1}, {1, 2}})
      at(i, j) = EvalSearchPoint(shape, map, u0 + i * g, v0 + j * g);
    for (const auto& [a, b] : {std::pair{0, 0}, {1, 0}, {0, 1}, {1, 1}})
      FindCrossingsInCell(shape, map, yScan, u0 + a * g, v0 + b * g, g, depth + 1,
                          {at(a, b), at(a + 1, b), at(a, b + 1), at(a + 1, b + 1)}, found);
    return;
  }
  const auto r = SolveNewton2(
      [&](const Vec2& p, Vec2* f, Mat2* j) { SilhouetteSystem(shape, map, yScan, p, f, j); },
      Vec2(u0 + 0.5 * h, v0 + 0.5 * h), Vec2(kEdgeTolPx, kEdgeTolPx));
  if (r.status != NewtonStatus::Converged) return;
  const double grow = 0.5 * h;
  if (r.uv.x() < u0 - grow || r.uv.x() > u0 + h + grow || r.uv.y() < v0 - grow || r.uv.y() > v0 + h + grow)
    return;
  // A collapsed edge (a pole, the lid apex) solves J = 0 everywhere along it: no silhouette.
  ScreenDerivs d;
  EvaluateScreen(shape, map, r.uv.x(), r.uv.y(), DerivOrder::First, &d);
  if (d.dpdu.head<2>().norm() < kCollapsedRel * d.dpdv.head<2>().norm() ||
      d.dpdv.head<2>().norm() < kCollapsedRel * d.dpdu.head<2>().norm())
    return;
  for (const Vec2& q : *found)
    if ((q - r.uv).norm() < kSameTrackerUv) return;
  found->push_back(r.uv);
}

// The search over the square [u0, u0 + h] x [v0, v0 + h] of the domain.
template <class ShapeT>
void FindCrossingsBySubdivision(const ShapeT& shape, const ScreenMap& map, double yScan, std::vector<Vec2>* found,
                                double u0, double v0, double h) {
  FindCrossingsInCell(shape, map, yScan, u0, v0, h, 0,
                      {EvalSearchPoint(shape, map, u0, v0), EvalSearchPoint(shape, map, u0 + h, v0),
                       EvalSearchPoint(shape, map, u0, v0 + h), EvalSearchPoint(shape, map, u0 + h, v0 + h)},
                      found);
}

// Two trackers dying on one line whose failed iterations ended this much closer together
// than the trackers had been (as a fraction of that distance) ran into each other: the
// silhouette curve's lowest point passed between the lines (Blinn 1978 §3.2.3's minimum,
// where Newton fails to converge). Measured on the teapot's pairs at 1024x768: 1e-4 to
// 0.07; a lost tracker's failure point has no partner.
constexpr double kMetFraction = 0.25;
// The square searched around such a pair: the box of the pair's last crossings and
// failure points, grown on each side by this fraction of its side (and at least
// kMinimumBoxMin), where the curve's remaining crossings would be if the pair had been
// lost rather than met.
constexpr double kMinimumBoxGrow = 0.5;
constexpr double kMinimumBoxMin = 1.0 / 64.0;

// Convergence in y: as for the edge trackers.
const Vec2 kTolerance(kEdgeTolPx, kEdgeTolPx);

// Steps between scan lines within this fraction of each other are equal.
constexpr double kEqualStepRel = 1e-9;

// Where a tracker's iteration starts on line yScan: ExtrapolatedStart (Blinn 1978 §3.5) where
// the lines of its last solutions were equally spaced, as the exact scan's are; else the
// line through its last two solutions, in screen y. θ slabs step half a row from a line to
// the first row, a row, half a row to the next line, or a whole interval from line to line:
// extrapolated as if equal, the start lay up to three rows' motion off.
Vec2 StartOn(const SilhouetteTracker& t, double yScan, bool quadratic) {
  const double h0 = yScan - t.y, h1 = t.y - t.yPrev, h2 = t.yPrev - t.yPrev2;
  const auto equal = [](double a, double b) { return std::abs(a - b) <= kEqualStepRel * std::abs(b); };
  if (t.nSolved < 2 || !std::isfinite(h1) || h1 == 0.0 ||
      (equal(h0, h1) && (!quadratic || t.nSolved < 3 || equal(h1, h2))))
    return ExtrapolatedStart(t.uv, t.uvPrev, t.uvPrev2, t.nSolved, quadratic);
  return t.uv + (h0 / h1) * (t.uv - t.uvPrev);
}

}  // namespace

SilhouetteScan::SilhouetteScan(const Surface& s, const ScreenMap& map, std::vector<Stationary> stationary,
                               Counters& counters, bool extrapolate)
    : surface_(s), map_(map), stationary_(std::move(stationary)), extrapolate_(extrapolate), counters_(counters) {
  std::erase_if(stationary_, [](const Stationary& p) {
    return p.kind != StationaryKind::StrictMaximum && p.kind != StationaryKind::Saddle;
  });
  std::stable_sort(stationary_.begin(), stationary_.end(),
                   [](const Stationary& a, const Stationary& b) { return a.y < b.y; });
}

template <class ShapeT>
bool SilhouetteScan::Solve(const ShapeT& shape, double yScan, const Vec2& start, Vec2* uv,
                           DomainRule domain) {
  NewtonOptions opt;
  opt.domain = domain;
  ++counters_[Counter::SilhouetteNewtonCalls];
  const auto r = SolveNewton2(
      [&](const Vec2& p, Vec2* f, Mat2* j) { SilhouetteSystem(shape, map_, yScan, p, f, j); },
      start.cwiseMax(0.0).cwiseMin(1.0), kTolerance, opt);
  counters_[Counter::SilhouetteNewtonIterations] += r.iterations;
  *uv = r.uv;
  if (r.status == NewtonStatus::LeftDomain) {
    ++counters_[Counter::SilhouettesLeft];
    ++events_;
  }
  return r.status == NewtonStatus::Converged;
}

template <class ShapeT>
void SilhouetteScan::AdvanceImpl(const ShapeT& shape, double yScan, const EdgeScan& edges) {
  // Step 1: move the existing trackers; a failure is a minimum or an exit (§3.2.3).
  deaths_.clear();
  births_.clear();
  exits_.clear();
  insideDeaths_.clear();
  PATCHSCAN_DCHECK(!(yScan < yLast_), "a surface's scan lines non-decreasing (Save and Restore to go back)");
  yLast_ = yScan;
  bool search = false;  // an event no tracker explains: look for the crossings again
  std::erase_if(trackers_, [&](SilhouetteTracker& t) {
    const Vec2 start = extrapolate_ ? StartOn(t, yScan, kEdgeTolPx <= kQuadraticExtrapolationTolPx) : t.uv;
    Vec2 uv;
    // Steps are clipped at the boundary, not refused: a path that grazes an edge on its
    // way to a crossing inside still arrives; one whose crossing has left the domain
    // stalls on the boundary and fails.
    if (!Solve(shape, yScan, start, &uv, DomainRule::Clip)) {
      ++counters_[Counter::SilhouettesDied];
      ++events_;
      deaths_.push_back(t.uv);
      // A death inside the domain is a minimum of the curve, or a lost tracker: only a
      // search can tell. One on the boundary is the curve leaving the patch.
      if (OnBoundary(uv))
        exits_.push_back(BoundarySides(uv));
      else
        insideDeaths_.push_back({t.uv, uv, -1});
      return true;
    }
    t.uvPrev2 = t.uvPrev;
    t.uvPrev = t.uv;
    t.uv = uv;
    t.yPrev2 = t.yPrev;
    t.yPrev = t.y;
    t.y = yScan;
    t.hasPrev = true;
    ++t.nSolved;
    return false;
  });
  // A new tracker's seed may sit on the boundary (a fold) with the first step pointing
  // out: seeds are solved with steps clipped at the boundary.
  auto add = [&](const Vec2& start, Counter born) {
    Vec2 uv;
    if (!Solve(shape, yScan, start, &uv, DomainRule::Clip)) return false;
    if (Tracked(uv)) return true;
    trackers_.push_back(NewTracker(uv));
    births_.push_back(uv);
    ++counters_[born];
    ++events_;
    return true;
  };
  // Step 2: maxima and saddles passed since the last scan line.
  for (; nextStationary_ < stationary_.size() && stationary_[nextStationary_].y <= yScan;
       ++nextStationary_) {
    const Stationary& p = stationary_[nextStationary_];
    const double drop = yScan - p.y;  // how far h has fallen below the point
    // A maximum on the line itself (to the trackers' tolerance: an orthographic sphere's top
    // lies exactly on a sample row) is one point of it, where both seeds below coincide and
    // the system is singular; its trackers are born on the next line.
    if (p.kind == StationaryKind::StrictMaximum && drop <= kEdgeTolPx) break;
    ScreenDerivs d;
    EvaluateScreen(shape, map_, p.uv.x(), p.uv.y(), DerivOrder::First, &d);
    const Vec2 gx(d.dpdu.x(), d.dpdv.x());  // screen x gradient
    if (p.kind == StationaryKind::StrictMaximum) {
      // Level curve h = h_max - drop ~ ellipse d^T (-H) d = 2 drop; its points of extreme
      // x are the silhouette: d = +-sqrt(2 drop / g^T (-H)^-1 g) (-H)^-1 g (§3.2.2.2).
      const Mat2 negH = -p.hessH;
      const Vec2 w = negH.inverse() * gx;
      const double q = gx.dot(w);
      bool born = false;
      if (q > 0 && drop >= 0) {
        const Vec2 delta = std::sqrt(2.0 * drop / q) * w;
        born |= add(p.uv + delta, Counter::SilhouettesBornAtMaxima);
        born |= add(p.uv - delta, Counter::SilhouettesBornAtMaxima);
      }
      if (!born) search = true;  // a closed curve appeared and the seeds missed it
    } else {
      // Below a saddle the level curve is a hyperbola whose vertices lie along the
      // Hessian's negative eigenvector: seeds there, and along the positive one for the
      // silhouette branches passing through (§3.2.2.4).
      const Eigen::SelfAdjointEigenSolver<Mat2> eig(p.hessH);
      for (int k = 0; k < 2; ++k) {
        const double lambda = std::abs(eig.eigenvalues()[k]);
        if (lambda == 0.0) continue;
        const Vec2 delta = std::sqrt(2.0 * std::max(drop, 1e-3) / lambda) * eig.eigenvectors().col(k);
        add(p.uv + delta, Counter::SilhouettesBornAtSaddles);
        add(p.uv - delta, Counter::SilhouettesBornAtSaddles);
      }
    }
  }
  // Step 3: folds: J changed sign at a boundary-edge tracker (§3.2.2.3).
  // The crossing may have run well inside since it crossed the edge: when Newton from
  // the edge point fails, start again a quarter and half way towards the domain's centre.
  // A fold where no crossing is born is explained when a tracker left the patch across the
  // same edge on this line (J changes sign where the curve leaves as where it enters);
  // each exit explains one fold. Any other is an event the trackers missed.
  for (const Vec2& uv : edges.Folds()) {
    bool born = false;
    for (double towards : {0.0, 0.25, 0.5})
      if ((born = add(uv + towards * (Vec2(0.5, 0.5) - uv), Counter::SilhouettesBornAtFolds))) break;
    if (born) continue;
    const auto exit = std::find_if(exits_.begin(), exits_.end(), [&](unsigned sides) { return (sides & BoundarySides(uv)) != 0; });
    if (exit != exits_.end())
      *exit = 0;  // used
    else
      search = true;
  }
  // Step 3b: deaths inside the domain. Trackers that died in pairs, each pair's failed
  // iterations ending together, met at a minimum of their curve: a search of the square
  // around each pair tells a minimum (nothing there) from two lost trackers. A death with
  // no such partner needs the whole domain searched.
  for (size_t a = 0; a < insideDeaths_.size() && !search; ++a) {
    InsideDeath& p = insideDeaths_[a];
    for (size_t b = a + 1; b < insideDeaths_.size() && p.partner < 0; ++b) {
      InsideDeath& q = insideDeaths_[b];
      if (q.partner < 0 && (p.failed - q.failed).norm() < kMetFraction * (p.last - q.last).norm())
        p.partner = static_cast<int>(b), q.partner = static_cast<int>(a);
    }
    search = p.partner < 0;
  }
  for (size_t a = 0; a < insideDeaths_.size() && !search; ++a) {
    const InsideDeath &p = insideDeaths_[a], &q = insideDeaths_[static_cast<size_t>(p.partner)];
    if (p.partner < static_cast<int>(a)) continue;  // searched with its partner
    const Vec2 lo = p.last.cwiseMin(p.failed).cwiseMin(q.last).cwiseMin(q.failed);
    const Vec2 hi = p.last.cwiseMax(p.failed).cwiseMax(q.last).cwiseMax(q.failed);
    const double side =
        std::min(1.0, std::max((1.0 + 2.0 * kMinimumBoxGrow) * (hi - lo).maxCoeff(), kMinimumBoxMin));
    const Vec2 corner = (0.5 * (lo + hi) - Vec2::Constant(0.5 * side)).cwiseMax(0.0).cwiseMin(1.0 - side);
    ++counters_[Counter::MinimumSearches];
    ++events_;
    searchFound_.clear();
    FindCrossingsBySubdivision(shape, map_, yScan, &searchFound_, corner.x(), corner.y(), side);
    AddFound();
  }
  // Step 3c: repair by subdivision (when an event is not explained by the trackers).
  if (search) {
    ++counters_[Counter::RepairSearches];
    ++events_;
    searchFound_.clear();
    FindCrossingsBySubdivision(shape, map_, yScan, &searchFound_, 0.0, 0.0, 1.0);
    AddFound();
  }
  // Step 4: trackers that converged onto one crossing are one tracker.
  for (size_t a = 0; a < trackers_.size(); ++a)
    for (size_t b = a + 1; b < trackers_.size();)
      if ((trackers_[a].uv - trackers_[b].uv).norm() < kSameTrackerUv) {
        trackers_.erase(trackers_.begin() + static_cast<long>(b));
        ++counters_[Counter::SilhouettesMerged];
        ++events_;
      } else {
        ++b;
      }
}

void SilhouetteScan::AddFound() {
  for (const Vec2& uv : searchFound_) {
    if (Tracked(uv)) continue;
    trackers_.push_back(NewTracker(uv));
    births_.push_back(uv);
    ++counters_[Counter::RepairedBySearch];
  }
}

bool SilhouetteScan::Tracked(const Vec2& uv) const {
  return std::any_of(trackers_.begin(), trackers_.end(),
                     [&](const SilhouetteTracker& t) { return (t.uv - uv).norm() < kSameTrackerUv; });
}

void SilhouetteScan::Adopt(const Vec2& uv) {
  if (Tracked(uv)) return;
  trackers_.push_back(NewTracker(uv));
  ++counters_[Counter::SilhouettesAdopted];
  ++events_;
}

void SilhouetteScan::Advance(double yScan, const EdgeScan& edges) {
  VisitShape(surface_, [&](const auto& shape) { AdvanceImpl(shape, yScan, edges); });
}

std::vector<Vec2> SilhouetteCrossingsBySubdivision(const Surface& s, const ScreenMap& map, double yScan,
                                                   double u0, double v0, double side) {
  std::vector<Vec2> found;
  VisitShape(s, [&](const auto& shape) { FindCrossingsBySubdivision(shape, map, yScan, &found, u0, v0, side); });
  return found;
}

std::vector<Vec2> SilhouetteCrossingsBruteForce(const Surface& s, const ScreenMap& map,
                                                 double yScan, int grid) {
  std::vector<Vec2> found;
  VisitShape(s, [&](const auto& shape) {
    NewtonOptions opt;
    opt.domain = DomainRule::Fail;
    opt.maxIterations = 50;
    for (int j = 0; j <= grid; ++j)
      for (int i = 0; i <= grid; ++i) {
        const auto r = SolveNewton2(
            [&](const Vec2& p, Vec2* f, Mat2* jac) { SilhouetteSystem(shape, map, yScan, p, f, jac); },
            Vec2(double(i) / grid, double(j) / grid), kTolerance, opt);
        if (r.status != NewtonStatus::Converged) continue;
        bool seen = false;
        for (const Vec2& q : found) seen = seen || (q - r.uv).norm() < kSameTrackerUv * 100;
        if (!seen) found.push_back(r.uv);
      }
  });
  return found;
}

}  // namespace patchscan
