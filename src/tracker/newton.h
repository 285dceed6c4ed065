// Newton solvers for the trackers (Blinn 1978 §3.2.1, §3.5): univariate for edge trackers,
// bivariate for silhouette and X-scan trackers and for stationary points. Every solver is
// damped by halving the step while the residual does not decrease (Blinn's thesis), is
// capped, never returns NaN, and says how it ended. Templates over the function, so a
// tracker's inner loop has no indirect call; nothing allocates.
#pragma once

#include <Eigen/Core>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>

#include "core/check.h"
#include "core/vec.h"

namespace patchscan {

enum class NewtonStatus {
  Converged,      // |f| within tolerance
  IterationCap,   // ran out of iterations
  Singular,       // zero derivative / Jacobian, or no damped step reduced the residual
  LeftDomain,     // the iteration wanted to leave [lo, hi] (or [0,1]^2) and the rule says fail
};

const char* ToString(NewtonStatus s);

// What to do with an iterate that would leave the domain.
enum class DomainRule {
  Clip,  // clip the step at the boundary (maxima search, edge trackers)
  Fail,  // stop with LeftDomain (silhouette trackers: deleted when they leave [0,1]^2)
};

struct NewtonOptions {
  int maxIterations = 20;   // Blinn reports ~2.5 per step unextrapolated; 20 is never needed when converging
  int maxHalvings = 30;     // 2^-30 of a step is below double resolution of a unit domain
  DomainRule domain = DomainRule::Clip;
};

// The start of a tracker's Newton iteration on the next scan line from its solutions on the
// last ones: p0 on the latest, p1 and p2 before it, `nSolved` of them known. Paper 001 §3.5
// extrapolates linearly from two; with three and `quadratic`, the parabola through them
// (3 p0 − 3 p1 + p2) errs by O(h³) instead of O(h²) but multiplies the solutions' own
// errors by 7 instead of 3: better at tight tolerances, worse at loose ones (see
// kQuadraticExtrapolationTolPx). Assumes equally spaced scan lines; any start converges,
// a worse one takes longer.
template <class T>
T ExtrapolatedStart(const T& p0, const T& p1, const T& p2, int nSolved, bool quadratic) {
  if (quadratic && nSolved >= 3) return T(3.0 * p0 - 3.0 * p1 + p2);
  if (nSolved >= 2) return T(2.0 * p0 - p1);
  return p0;
}

// Trackers solved to this tolerance or tighter extrapolate quadratically. Measured on the
// teapot's edge trackers at 1024×768 (EdgeScan.ExtrapolationCutsNewtonIterations): at 1e-7 px
// 1.66 iterations per tracker per line linear, 1.33 quadratic; at 0.1 px 0.46 linear, 0.62
// quadratic (the solutions' errors, amplified, dominate).
constexpr double kQuadraticExtrapolationTolPx = 1e-3;

struct Newton1Result {
  double t = 0.0;
  double f = 0.0;  // residual at t
  int iterations = 0;
  NewtonStatus status = NewtonStatus::Converged;
};

// Solves f(t) = 0 on [lo, hi] from t0. `eval(t, &f, &dfdt)` evaluates the function and
// its derivative. Converged when |f| <= tolerance.
template <class Eval>
Newton1Result SolveNewton1(Eval&& eval, double t0, double lo, double hi, double tolerance,
                           const NewtonOptions& opt = {}) {
  PATCHSCAN_DCHECK(lo <= hi, "Newton's bracket [lo, hi] not empty");
  Newton1Result r;
  r.t = std::clamp(t0, lo, hi);
  double df = 0.0;
  eval(r.t, &r.f, &df);
  if (!std::isfinite(r.f)) return {r.t, 0.0, 0, NewtonStatus::Singular};
  for (;;) {
    if (std::abs(r.f) <= tolerance) return r;
    if (r.iterations == opt.maxIterations) {
      r.status = NewtonStatus::IterationCap;
      return r;
    }
    ++r.iterations;
    if (!(std::abs(df) > 0.0) || !std::isfinite(df)) {
      r.status = NewtonStatus::Singular;
      return r;
    }
    double step = -r.f / df;
    // Step 1: the domain.
    if (r.t + step < lo || r.t + step > hi) {
      if (opt.domain == DomainRule::Fail) {
        r.status = NewtonStatus::LeftDomain;
        return r;
      }
      step = std::clamp(r.t + step, lo, hi) - r.t;
      if (step == 0.0) {  // pinned at the boundary, pushing out
        r.status = NewtonStatus::LeftDomain;
        return r;
      }
    }
    // Step 2: halve the step while the residual does not decrease.
    double t = r.t + step, f = 0.0, d = 0.0;
    int halvings = 0;
    for (;;) {
      eval(t, &f, &d);
      if (std::isfinite(f) && std::abs(f) < std::abs(r.f)) break;
      if (++halvings > opt.maxHalvings) {
        r.status = NewtonStatus::Singular;
        return r;
      }
      step *= 0.5;
      t = r.t + step;
    }
    r.t = t;
    r.f = f;
    df = d;
  }
}

// Whether a 2x2 Jacobian with determinant `det` is singular for Newton's purposes: its
// determinant, relative to its entries, below kSingularRelDet (the step would be noise).
constexpr double kSingularRelDet = 1e-14;
inline bool SingularJacobian(const Mat2& jac, double det) {
  return !std::isfinite(det) || std::abs(det) <= kSingularRelDet * jac.squaredNorm();
}

struct Newton2Result {
  Vec2 uv = Vec2::Zero();
  Vec2 f = Vec2::Zero();  // residual at uv
  int iterations = 0;
  NewtonStatus status = NewtonStatus::Converged;
};

// Solves F(u,v) = 0 for two functions on [0,1]^2 from uv0. `eval(uv, &f, &jacobian)`
// evaluates F and its Jacobian (rows: functions, columns: d/du, d/dv). Converged when
// |f_i| <= tolerance_i for both; the residual that damping compares is
// max_i |f_i| / tolerance_i, so the two functions may have different units.
template <class Eval>
Newton2Result SolveNewton2(Eval&& eval, const Vec2& uv0, const Vec2& tolerance,
                           const NewtonOptions& opt = {}) {
  Newton2Result r;
  r.uv = uv0.cwiseMax(0.0).cwiseMin(1.0);
  Mat2 jac;
  eval(r.uv, &r.f, &jac);
  if (!r.f.allFinite()) return {r.uv, Vec2::Zero(), 0, NewtonStatus::Singular};
  auto size = [&](const Vec2& f) { return f.cwiseAbs().cwiseQuotient(tolerance).maxCoeff(); };
  double residual = size(r.f);
  for (;;) {
    if (residual <= 1.0) return r;
    if (r.iterations == opt.maxIterations) {
      r.status = NewtonStatus::IterationCap;
      return r;
    }
    ++r.iterations;
    const double det = jac.determinant();
    if (SingularJacobian(jac, det)) {
      r.status = NewtonStatus::Singular;
      return r;
    }
    Vec2 step = -jac.inverse() * r.f;
    // Step 1: the domain [0,1]^2; a clipped step keeps its direction.
    const Vec2 target = r.uv + step;
    if ((target.array() < 0.0).any() || (target.array() > 1.0).any()) {
      if (opt.domain == DomainRule::Fail) {
        r.uv = target;  // where it wanted to go: the caller may use it to see which edge
        r.status = NewtonStatus::LeftDomain;
        return r;
      }
      double scale = 1.0;
      for (int k = 0; k < 2; ++k) {
        if (target[k] < 0.0) scale = std::min(scale, -r.uv[k] / step[k]);
        if (target[k] > 1.0) scale = std::min(scale, (1.0 - r.uv[k]) / step[k]);
      }
      step *= std::max(scale, 0.0);
      if (step.squaredNorm() == 0.0) {
        r.status = NewtonStatus::LeftDomain;
        return r;
      }
    }
    // Step 2: halve the step while the residual does not decrease.
    Vec2 uv = (r.uv + step).cwiseMax(0.0).cwiseMin(1.0), f;
    Mat2 j;
    int halvings = 0;
    double next;
    for (;;) {
      eval(uv, &f, &j);
      next = f.allFinite() ? size(f) : INFINITY;
      if (next < residual) break;
      if (++halvings > opt.maxHalvings) {
        r.status = NewtonStatus::Singular;
        return r;
      }
      step *= 0.5;
      uv = (r.uv + step).cwiseMax(0.0).cwiseMin(1.0);
    }
    r.uv = uv;
    r.f = f;
    jac = j;
    residual = next;
  }
}

}  // namespace patchscan
