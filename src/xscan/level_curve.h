// One surface's level curve on one scan line, y(u,v) = ys (Blinn 1978 §3.3): its points,
// the point at a sample column by bivariate Newton, and the silhouette point between two
// of its points. What the walks (xscan/level_walk.h, xscan/theta_walk.h) stand on.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <optional>
#include <vector>

#include "core/counters.h"
#include "core/hermite.h"
#include "patch/screen.h"
#include "raster/fragment.h"
#include "tracker/level_point.h"
#include "tracker/newton.h"
#include "tracker/silhouette_scan.h"

namespace patchscan {

// Where the walks repaired a tracker miss and where they gave up, for the trace.
struct WalkEvents {
  std::vector<Vec2> repairs, failures;
  std::vector<Vec2> untrackedSilhouettes;  // also in repairs: for the Y scan to adopt
  void Clear() {
    repairs.clear();
    failures.clear();
    untrackedSilhouettes.clear();
  }
};

// A sample column this close to a walk point in x (pixels) counts as passed (the back
// end's rule for chords too).
using raster::kColumnEpsPx;
// Two points of a curve this close in (u,v) are the same crossing.
constexpr double kSameCrossingUv = 1e-6;

template <class ShapeT>
class LevelCurve {
 public:
  // `events` may be null.
  LevelCurve(const ShapeT& shape, const ScreenMap& map, double ys, const raster::SampleColumns& cols,
             Counters* counters, WalkEvents* events)
      : shape_(shape), map_(map), ys_(ys), cols_(cols), counters_(counters), events_(events) {}

  // The point of the surface at uv (tracker/level_point.h).
  LevelPoint Eval(const Vec2& uv, DerivOrder order = DerivOrder::First) const {
    return EvalLevelPoint(shape_, map_, uv, order);
  }

 protected:
  void Failed(const Vec2& uv) {
    ++(*counters_)[Counter::Failures];
    if (events_) events_->failures.push_back(uv);
  }
  void Repaired(const Vec2& uv, Counter counter) {
    ++(*counters_)[counter];
    if (events_) events_->repairs.push_back(uv);
  }

  // The unit tangent of the level curve, (-y_v, y_u) / |grad y|, times the walk's sense.
  static Vec2 Tangent(const LevelPoint& p, double sense) {
    return sense * Vec2(-p.gradY.y(), p.gradY.x()) / p.gradY.norm();
  }
  static bool Inside(const Vec2& uv) {
    return uv.x() >= 0.0 && uv.x() <= 1.0 && uv.y() >= 0.0 && uv.y() <= 1.0;
  }

  // The walk's sense whose tangent at p, on boundary edge `edge`, points into the domain;
  // 0 when the curve only touches the edge there (the scan line at an edge extremum).
  static double InwardSense(const LevelPoint& p, PatchEdge edge) {
    const Vec2 t = Tangent(p, 1.0);
    double inward = 0.0;
    switch (edge) {
      case PatchEdge::U0: inward = t.x(); break;
      case PatchEdge::U1: inward = -t.x(); break;
      case PatchEdge::V0: inward = t.y(); break;
      case PatchEdge::V1: inward = -t.y(); break;
    }
    constexpr double kTangentialInward = 1e-12;
    if (std::abs(inward) <= kTangentialInward) return 0.0;
    return inward > 0 ? 1.0 : -1.0;
  }

  // Marks the trackers among `points` at uv as passed in *used; false if none is there.
  static bool UseTracker(const std::vector<Vec2>& points, std::vector<char>* used, const Vec2& uv) {
    bool found = false;
    for (size_t k = 0; k < points.size(); ++k)
      if ((points[k] - uv).norm() <= kSameCrossingUv) {
        (*used)[k] = 1;
        found = true;
      }
    return found;
  }

  // Back onto the level curve from q, moving along grad y (the shortest way to first
  // order). Allowed to leave the domain slightly: the caller checks.
  LevelPoint Correct(Vec2 q) const {
    constexpr int kMaxCorrections = 12;
    for (int k = 0; k < kMaxCorrections; ++k) {
      const LevelPoint p = Eval(q);
      if (!p.ok) return p;
      const double f = p.y - ys_;
      if (std::abs(f) <= kEdgeTolPx) return p;
      q -= f * p.gradY / p.gradY.squaredNorm();
    }
    LevelPoint p = Eval(q);
    p.ok = p.ok && std::abs(p.y - ys_) <= kEdgeTolPx;
    return p;
  }

  // The point of the level curve at column c, by Newton from `seed`.
  bool SolveColumn(int c, const Vec2& seed, LevelPoint* out) const {
    ++(*counters_)[Counter::XscanNewtonCalls];
    return SolveX(cols_.At(c), seed, out, &(*counters_)[Counter::XscanNewtonIterations]);
  }
  // The point of the level curve at x = xs, by Newton from `seed`; adds the iterations.
  bool SolveX(double xs, const Vec2& seed, LevelPoint* out, std::int64_t* iterations) const {
    // The solver's last evaluation is at the point it returns: kept, not repeated.
    const auto r = SolveNewton2(
        [&](const Vec2& uv, Vec2* f, Mat2* jac) {
          *out = Eval(uv);
          const LevelPoint& p = *out;
          *f = Vec2(p.x - xs, p.y - ys_);
          *jac << p.gradX.x(), p.gradX.y(), p.gradY.x(), p.gradY.y();
          if (!p.ok) *f = Vec2(NAN, NAN);
        },
        seed, Vec2(kEdgeTolPx, kEdgeTolPx));
    *iterations += r.iterations;
    if (r.status != NewtonStatus::Converged) return false;
    if (out->uv != r.uv) *out = Eval(r.uv);
    return out->ok;
  }

  // The x direction in which the curve moves, going with `sense`: dx/ds = -J along
  // (-y_v, y_u).
  static int DirX(const LevelPoint& p, double sense) { return -sense * p.j > 0.0 ? 1 : -1; }

  // The first column beyond x in direction dir, or -1 / n when there is none.
  int NextColumn(double x, int dir) const {
    if (dir > 0) return cols_.Ceil(x + kColumnEpsPx) < cols_.n ? cols_.Ceil(x + kColumnEpsPx) : cols_.n;
    return cols_.Floor(x - kColumnEpsPx);
  }

  // What PredictColumn needs of a point of the walk (copied each step, so kept small).
  struct CurvePoint {
    Vec2 uv = Vec2::Zero();
    double x = 0.0;
    Vec2 gradX = Vec2::Zero(), gradY = Vec2::Zero();
    static CurvePoint Of(const LevelPoint& p) { return {p.uv, p.x, p.gradX, p.gradY}; }
  };
  // Where the exact X scan's solve at screen x starts when the walk's last two points q0
  // and q1 are known: the cubic Hermite interpolant of uv(x) through both, with the level
  // curve's slopes duv/dx = [grad x; grad y]^-1 (1, 0) from the evaluations that found them
  // (so no evaluation is added), extended to x; error O(h^4) where the tangent step's is
  // O(h^2). Only one step on at most (x no farther beyond q1 than q1 is beyond q0, the
  // columns' equal spacing; the points' x are within tolerance of their columns, hence the
  // slack): nullopt otherwise, or where a slope is singular (the curve turning in x).
  static std::optional<Vec2> PredictColumn(const CurvePoint& q0, const CurvePoint& q1, double x) {
    auto slope = [](const CurvePoint& q, Vec2* d) {
      Mat2 jac;
      jac << q.gradX.x(), q.gradX.y(), q.gradY.x(), q.gradY.y();
      if (SingularJacobian(jac, jac.determinant())) return false;
      *d = jac.inverse().col(0);
      return true;
    };
    const double h = q1.x - q0.x;
    constexpr double kEqualStepSlack = 1e-3;
    const double s = std::abs(h) > 0.0 ? (x - q0.x) / h : 0.0;
    Vec2 d0, d1;
    if (!(s > 1.0 && s <= 2.0 + kEqualStepSlack) || !slope(q0, &d0) || !slope(q1, &d1)) return std::nullopt;
    const HermiteBlend w = HermiteWeights(s);
    return Vec2(w.w0 * q0.uv + w.w1 * h * d0 + w.w2 * q1.uv + w.w3 * h * d1);
  }

  // The silhouette point (J = 0) on the arc between a and b, whose J differ in sign:
  // bisection on the chord projected onto the curve, then Newton on the silhouette
  // trackers' system.
  bool LocateSilhouette(LevelPoint a, LevelPoint b, LevelPoint* s) const {
    constexpr double kBracketUv = 1e-5;  // Newton finishes from a bracket this small
    constexpr int kMaxBisections = 60;
    for (int k = 0; k < kMaxBisections && (b.uv - a.uv).norm() > kBracketUv; ++k) {
      const LevelPoint m = Correct(0.5 * (a.uv + b.uv));
      if (!m.ok) return false;
      if ((m.j > 0) == (a.j > 0)) a = m;
      else b = m;
    }
    const auto r = SolveNewton2(
        [&](const Vec2& uv, Vec2* f, Mat2* jac) { SilhouetteSystem(shape_, map_, ys_, uv, f, jac); },
        0.5 * (a.uv + b.uv), Vec2(kEdgeTolPx, kEdgeTolPx));
    const double bracket = (b.uv - a.uv).norm();
    if (r.status == NewtonStatus::Converged && (r.uv - 0.5 * (a.uv + b.uv)).norm() <= bracket + kSameCrossingUv) {
      *s = Eval(r.uv);
      if (s->ok) return true;
    }
    // Newton did not settle inside the bracket: keep bisecting to rounding.
    for (int k = 0; k < kMaxBisections && (b.uv - a.uv).norm() > 1e-13; ++k) {
      const LevelPoint m = Correct(0.5 * (a.uv + b.uv));
      if (!m.ok) break;
      if ((m.j > 0) == (a.j > 0)) a = m;
      else b = m;
    }
    *s = std::abs(a.jn) < std::abs(b.jn) ? a : b;
    return s->ok;
  }

  const ShapeT& shape_;
  const ScreenMap& map_;
  double ys_;
  raster::SampleColumns cols_;
  Counters* counters_;
  WalkEvents* events_;
};

}  // namespace patchscan
