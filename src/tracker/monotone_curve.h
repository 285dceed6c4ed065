// What the Y scan's curve trackers share (Blinn 1978 §3.2.1): a curve in the domain —
// a boundary edge, or a trim curve — is cut where screen y turns, so that each piece holds
// one crossing of any scan line between its ends; the crossing is found by univariate
// Newton from an extrapolated start (§3.5), or by Newton kept inside the piece, which
// brackets it, when that fails or has no start yet.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <utility>
#include <vector>

#include "core/check.h"
#include "core/sign_changes.h"
#include "tracker/newton.h"

namespace patchscan {

// The crossing f(t) = 0 on a piece [t0, t1] on which f is monotone and changes sign, to
// rounding: Newton kept inside the bracket, bisection where its step leaves it, fails to
// halve the step before last (so that the bracket shrinks at least geometrically) or f'
// is not finite (a tracker's birth at a piece's top, where f' may vanish; a repair). A
// Newton step below kPieceNewtonStep of the unit parameter ends the search (the root is
// then within about its square), in ~6 evaluations where bisection alone took ~50;
// without one the bracket is bisected down to adjacent doubles and its end nearer the
// crossing (|f| < `tolerance`) returned.
constexpr double kPieceNewtonStep = 1e-14;

template <class F>
double CrossingOnPiece(F&& f, double t0, double t1, double tolerance) {
  double lo = t0, hi = t1, flo, dummy;
  f(lo, &flo, &dummy);
#if PATCHSCAN_CHECKS_ON
  double fhi;
  f(hi, &fhi, &dummy);
  PATCHSCAN_DCHECK(lo <= hi && (!(flo * fhi > 0.0) || std::min(std::abs(flo), std::abs(fhi)) < tolerance),
                   "Newton's bracket holds a crossing: f changes sign on [t0, t1], or is within tolerance of 0 at an end");
#endif
  double x = 0.5 * (lo + hi), stepBefore = hi - lo, step = stepBefore;
  for (int it = 0; it < 200; ++it) {
    if (x <= lo || x >= hi) break;  // the bracket is down to adjacent doubles
    double fx, dx;
    f(x, &fx, &dx);
    if (fx == 0.0) return x;
    if ((fx > 0) == (flo > 0)) lo = x, flo = fx;
    else hi = x;
    const double newton = x - fx / dx;
    const double stepBeforeLast = stepBefore;
    stepBefore = step;
    if (std::isfinite(newton) && newton > lo && newton < hi && std::abs(newton - x) < 0.5 * stepBeforeLast) {
      step = std::abs(newton - x);
      if (step <= kPieceNewtonStep) return newton;
      x = newton;
    } else {
      x = 0.5 * (lo + hi);
      step = 0.5 * (hi - lo);
    }
  }
  return std::abs(flo) < tolerance ? lo : hi;
}

// One tracker's step on its monotone piece [t0, t1]: Newton on f(t) = 0 (`f(t, &v, &d)`)
// from `start` when the tracker has a position, else CrossingOnPiece, which also repairs
// a Newton that fails. Adds the iterations to *iterations and says whether it repaired.
template <class F>
double TrackOnPiece(F&& f, double t0, double t1, double start, bool hasStart, double tolerance, std::int64_t* iterations,
                    bool* repaired) {
  *repaired = false;
  if (!hasStart) return CrossingOnPiece(f, t0, t1, tolerance);
  const auto r = SolveNewton1(f, std::clamp(start, t0, t1), t0, t1, tolerance);
  *iterations += r.iterations;
  if (r.status == NewtonStatus::Converged) return r.t;
  *repaired = true;
  return CrossingOnPiece(f, t0, t1, tolerance);
}

}  // namespace patchscan
