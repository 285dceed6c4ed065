// What the Y scan's curve trackers share (paper 001 §3.2.1): a curve in the domain —
// a boundary edge, or a trim curve — is cut where screen y turns, so that each piece holds
// one crossing of any scan line between its ends; the crossing is found by univariate
// Newton from an extrapolated start (§3.5), or by bisection on the piece, which brackets
// it, when Newton fails or has no start yet.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <utility>
#include <vector>

#include "core/sign_changes.h"
#include "tracker/newton.h"

namespace patchscan {

// The crossing f(t) = 0 on a piece [t0, t1] on which f is monotone and changes sign, by
// bisection to rounding: the end nearer the crossing when within `tolerance`.
template <class F>
double BisectPiece(F&& f, double t0, double t1, double tolerance) {
  double lo = t0, hi = t1, flo, dummy;
  f(lo, &flo, &dummy);
  for (int it = 0; it < 200; ++it) {
    const double mid = 0.5 * (lo + hi);
    if (mid <= lo || mid >= hi) break;
    double fm;
    f(mid, &fm, &dummy);
    if ((fm > 0) == (flo > 0)) lo = mid, flo = fm;
    else hi = mid;
  }
  return std::abs(flo) < tolerance ? lo : hi;
}

// One tracker's step on its monotone piece [t0, t1]: Newton on f(t) = 0 (`f(t, &v, &d)`)
// from `start` when the tracker has a position, else bisection; bisection also repairs a
// Newton that fails. Adds the iterations to *iterations and says whether it repaired.
template <class F>
double TrackOnPiece(F&& f, double t0, double t1, double start, bool hasStart, double tolerance, std::int64_t* iterations,
                    bool* repaired) {
  *repaired = false;
  if (!hasStart) return BisectPiece(f, t0, t1, tolerance);
  const auto r = SolveNewton1(f, std::clamp(start, t0, t1), t0, t1, tolerance);
  *iterations += r.iterations;
  if (r.status == NewtonStatus::Converged) return r.t;
  *repaired = true;
  return BisectPiece(f, t0, t1, tolerance);
}

}  // namespace patchscan
