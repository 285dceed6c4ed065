#include "tracker/edge_crossings.h"

#include <algorithm>
#include <cmath>

#include "core/sign_changes.h"
#include "tracker/trim_scan.h"

namespace patchscan {
namespace {

// The crossing is solved to this (pixels in y): far below kColumnEpsPx, so that the x it
// gives is as good as the edge itself.
constexpr double kCrossingTolPx = 1e-10;
// Newton iterations on a piece, each at worst a bisection: 100 halve any bracket to below
// kCrossingBracketT, where the crossing is as exact as the segment's parameter can say.
constexpr int kCrossingMaxIterations = 100;
constexpr double kCrossingBracketT = 1e-15;

}  // namespace

EdgeCrossings::EdgeCrossings(const EdgeCurve& edge, const ScreenMap& map) : edge_(edge), map_(map) {
  for (std::size_t k = 0; k < edge_.Segments(); ++k) {
    // The projected control points hold the segment's screen image when all are in front of
    // the eye (a rational curve is their convex combination there); a segment whose hull
    // reaches behind the eye is left to the faces' own ends.
    const std::vector<Vec4>& hull = edge_.Points(k);
    double xLo = INFINITY, xHi = -INFINITY;
    bool visible = true;
    for (const Vec4& h : hull) {
      const Vec4 s = map_.ScreenFromObject() * h;
      visible = visible && s.w() > 0.0;
      xLo = std::min(xLo, s.x() / s.w()), xHi = std::max(xHi, s.x() / s.w());
    }
    if (!visible) continue;
    std::vector<double> turns = {0.0};
    if (hull.size() > 2)  // a straight segment's screen y is monotone
      SignChanges([&](double t) {
        Vec2 p, d;
        Screen(k, t, &p, &d);
        return std::pair(d.y(), NAN);
      }, 0.0, 1.0, kTrimCriticalSamples, &turns);
    turns.push_back(1.0);
    for (std::size_t m = 0; m + 1 < turns.size(); ++m) {
      if (!(turns[m + 1] > turns[m])) continue;
      Vec2 a, b, d;
      Screen(k, turns[m], &a, &d);
      Screen(k, turns[m + 1], &b, &d);
      pieces_.push_back({k, turns[m], turns[m + 1], a.y(), b.y(), xLo, xHi});
    }
  }
}

bool EdgeCrossings::Screen(std::size_t k, double t, Vec2* p, Vec2* d) const {
  Vec3 dc;
  const Vec3 c = edge_.At(k, t, &dc);
  const Vec4 h = map_.Homogeneous(c);
  const Vec4 dh = map_.ScreenFromObject().block<4, 3>(0, 0) * dc;
  if (!(h.w() > 0.0)) return false;
  *p = h.head<2>() / h.w();
  *d = (dh.head<2>() - dh.w() * *p) / h.w();  // the quotient rule
  return true;
}

double EdgeCrossings::Solve(const Piece& piece, double ys) const {
  Vec2 p, d;
  double a = piece.t0, b = piece.t1;
  double fa = piece.y0 - ys;
  const double fb = piece.y1 - ys;
  double t = fa == fb ? 0.5 * (a + b) : std::clamp(a + (b - a) * fa / (fa - fb), a, b);
  for (int it = 0; it < kCrossingMaxIterations; ++it) {
    Screen(piece.segment, t, &p, &d);
    const double f = p.y() - ys;
    if (std::abs(f) <= kCrossingTolPx || !(b - a > kCrossingBracketT)) return p.x();
    if ((f > 0) == (fa > 0)) a = t, fa = f;
    else b = t;
    const double newton = t - f / d.y();
    t = newton > a && newton < b && std::isfinite(newton) ? newton : 0.5 * (a + b);
  }
  return NAN;  // not settled: the faces keep their own ends on this line
}

double EdgeCrossings::Nearest(double ys, double x, double maxPx) const {
  double best = NAN, bestDistance = maxPx;
  for (const Piece& piece : pieces_) {
    if (ys < std::min(piece.y0, piece.y1) || ys > std::max(piece.y0, piece.y1) || x < piece.xLo - bestDistance ||
        x > piece.xHi + bestDistance)
      continue;
    const double xe = Solve(piece, ys);
    if (std::isfinite(xe) && std::abs(xe - x) <= bestDistance) best = xe, bestDistance = std::abs(xe - x);
  }
  return best;
}

}  // namespace patchscan
