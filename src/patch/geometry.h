// Axis-aligned boxes in any space (the vectors are core/vec.h's).
#pragma once

#include <algorithm>
#include <array>
#include <limits>

#include "core/vec.h"

namespace patchscan {

// An axis-aligned box in any space; empty until a point is added. Never allocates.
template <int N>
struct Bounds {
  using Point = Eigen::Matrix<double, N, 1>;
  Point lo = Point::Constant(std::numeric_limits<double>::infinity());
  Point hi = Point::Constant(-std::numeric_limits<double>::infinity());

  bool Empty() const { return (lo.array() > hi.array()).any(); }
  void Extend(const Point& p) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  void Extend(const Bounds& b) {
    lo = lo.cwiseMin(b.lo);
    hi = hi.cwiseMax(b.hi);
  }
  Point Centre() const { return 0.5 * (lo + hi); }
  Point Diagonal() const { return hi - lo; }
};

using Bounds2 = Bounds<2>;
using Bounds3 = Bounds<3>;

// The eight corners of a box (bit 0 of the index picks x, bit 1 y, bit 2 z).
using BoxHull = std::array<Vec3, 8>;
inline BoxHull BoxCorners(const Bounds3& box) {
  BoxHull c;
  for (int k = 0; k < 8; ++k)
    c[k] = Vec3((k & 1) ? box.hi.x() : box.lo.x(), (k & 2) ? box.hi.y() : box.lo.y(),
                (k & 4) ? box.hi.z() : box.lo.z());
  return c;
}

}  // namespace patchscan
