// The roots of a function of one variable on an interval, found by sampling for sign
// changes and refining each bracket: where a curve's coordinate or screen y turns (the
// trackers' monotone pieces, Blinn 1978 §3.2.1) or crosses a line (trim curves).
#pragma once

#include <cmath>
#include <utility>
#include <vector>

namespace patchscan {

// Where g changes sign on [t0, t1], sampled at `samples` steps and refined in each bracket
// by Newton inside it (bisection where Newton leaves it or gd is not finite). `eval(t)`
// returns {g, dg/dt}; dg/dt may be NaN; `value(t)`, g alone (the samples', where dg/dt
// costs more). Appends the roots to *cuts in increasing order.
template <class Value, class Eval>
void SignChanges(Value&& value, Eval&& eval, double t0, double t1, int samples, std::vector<double>* cuts) {
  // Brackets run from the last sample where g was not zero, so that a root exactly on a
  // sample (a trim curve meeting u = 1 at its midpoint) is bracketed too.
  double tPrev = t0, gPrev = value(t0);
  for (int k = 1; k <= samples; ++k) {
    const double t = t0 + (t1 - t0) * k / samples;
    const double g = value(t);
    if ((gPrev < 0 && g > 0) || (gPrev > 0 && g < 0)) {
      double lo = tPrev, hi = t, glo = gPrev;
      double x = 0.5 * (lo + hi);
      for (int it = 0; it < 200 && hi - lo > 1e-15; ++it) {
        const auto [gx, dgx] = eval(x);
        if (gx == 0.0) break;
        if ((gx > 0) == (glo > 0)) lo = x, glo = gx;
        else hi = x;
        const double newton = x - gx / dgx;
        x = (newton > lo && newton < hi && std::isfinite(newton)) ? newton : 0.5 * (lo + hi);
      }
      cuts->push_back(x);
    }
    if (g != 0.0 || gPrev == 0.0) {
      tPrev = t;
      gPrev = g;
    }
  }
}

template <class Eval>
void SignChanges(Eval&& eval, double t0, double t1, int samples, std::vector<double>* cuts) {
  SignChanges([&](double t) { return eval(t).first; }, eval, t0, t1, samples, cuts);
}

}  // namespace patchscan
