// Shared test helpers: seeded sampling and finite-difference checks of derivatives.
#pragma once

#include <gtest/gtest.h>

#include <functional>
#include <random>
#include <sstream>
#include <string>

#include "patch/surface_derivs.h"

namespace patchscan::test {

// Every random test draws from this fixed seed, so a failure reproduces exactly.
constexpr unsigned kSeed = 20261122;

// (u, v) samples in [kParamMargin, 1 - kParamMargin]^2: central differences reach
// kFdStep outside a sample, and the paraboloid's apex (v = 0) has unbounded derivatives.
constexpr double kParamMargin = 0.02;
// Central-difference step in (u, v). Truncation error h^2/6 |f'''| is ~2e-11 |f'''|;
// rounding error eps |f| / h is ~2e-11 |f|: both far below kFdRelTol.
constexpr double kFdStep = 1e-5;
// Allowed disagreement between an analytic derivative and its central difference,
// relative to the size of the quantities at that point (position plus derivatives).
constexpr double kFdRelTol = 1e-6;

inline std::vector<std::pair<double, double>> SampleParams(int n, unsigned seed = kSeed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> d(kParamMargin, 1.0 - kParamMargin);
  std::vector<std::pair<double, double>> uv;
  for (int i = 0; i < n; ++i) {
    const double u = d(rng);
    uv.emplace_back(u, d(rng));
  }
  return uv;
}

inline std::string Where(double u, double v) {
  std::ostringstream s;
  s.precision(17);
  s << "at (u, v) = (" << u << ", " << v << ")";
  return s.str();
}

// Checks first derivatives against central differences of the position, and second
// derivatives against central differences of the analytic first derivatives.
// `eval(u, v, order, out)` evaluates the surface under test.
using Evaluator = std::function<void(double, double, DerivOrder, SurfaceDerivs*)>;
inline void ExpectDerivativesMatchDifferences(const Evaluator& eval, double u, double v,
                                              const std::string& what) {
  const double h = kFdStep;
  SurfaceDerivs d, pu, mu, pv, mv;
  eval(u, v, DerivOrder::Second, &d);
  eval(u + h, v, DerivOrder::Second, &pu);
  eval(u - h, v, DerivOrder::Second, &mu);
  eval(u, v + h, DerivOrder::Second, &pv);
  eval(u, v - h, DerivOrder::Second, &mv);
  const double scale = d.p.norm() + d.dpdu.norm() + d.dpdv.norm() + d.d2pdu2.norm() +
                       d.d2pduv.norm() + d.d2pdv2.norm();
  const double tol = kFdRelTol * scale;
  auto check = [&](const Vec3& analytic, const Vec3& fd, const char* name) {
    EXPECT_LE((analytic - fd).norm(), tol)
        << what << ": " << name << " " << Where(u, v) << "\n analytic " << analytic.transpose()
        << "\n central difference " << fd.transpose();
  };
  check(d.dpdu, (pu.p - mu.p) / (2 * h), "dp/du");
  check(d.dpdv, (pv.p - mv.p) / (2 * h), "dp/dv");
  check(d.d2pdu2, (pu.dpdu - mu.dpdu) / (2 * h), "d2p/du2");
  check(d.d2pdv2, (pv.dpdv - mv.dpdv) / (2 * h), "d2p/dv2");
  check(d.d2pduv, (pv.dpdu - mv.dpdu) / (2 * h), "d2p/dudv (from dp/du)");
  check(d.d2pduv, (pu.dpdv - mu.dpdv) / (2 * h), "d2p/dudv (from dp/dv)");
  // Lower orders must not depend on whether higher ones were asked for.
  SurfaceDerivs p0, p1;
  eval(u, v, DerivOrder::Position, &p0);
  eval(u, v, DerivOrder::First, &p1);
  EXPECT_LE((p0.p - d.p).norm(), 1e-15 * scale) << what << " position-only " << Where(u, v);
  EXPECT_LE((p1.dpdu - d.dpdu).norm(), 1e-15 * scale) << what << " first-only " << Where(u, v);
}

}  // namespace patchscan::test
