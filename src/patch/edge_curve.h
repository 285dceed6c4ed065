// The curve in space along which two faces of a B-rep meet (Open CASCADE's 3D curve of a
// shared edge), as rational Bézier segments. Each face's trim curve that runs along the
// edge refers to it (TrimCurveInput::edge): the scans end both faces where the scan line
// crosses this one curve, so that faces whose own boundaries lie a tolerance apart
// (B-rep faces meet only within one) leave no crack between them (tracker/edge_crossings.h).
#pragma once

#include <cstddef>
#include <vector>

#include "core/vec.h"

namespace patchscan {

class EdgeCurve {
 public:
  // A NURBS curve over [tmin, tmax]: order, knots (n + order values) and n homogeneous
  // control points (x w, y w, z w, w). Throws std::invalid_argument as SplitNurbsCurve does.
  EdgeCurve(int order, const std::vector<double>& knot, double tmin, double tmax, const std::vector<Vec4>& points);

  std::size_t Segments() const { return segments_.size(); }
  // Segment k's homogeneous control points: the curve lies in their hull.
  const std::vector<Vec4>& Points(std::size_t k) const { return segments_[k]; }
  // The point of segment k at t in [0, 1], and its derivative when `d` is given.
  Vec3 At(std::size_t k, double t, Vec3* d = nullptr) const;

 private:
  std::vector<std::vector<Vec4>> segments_;
};

}  // namespace patchscan
