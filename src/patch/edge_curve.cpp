#include "patch/edge_curve.h"

#include "patch/nurbs.h"

namespace patchscan {

EdgeCurve::EdgeCurve(int order, const std::vector<double>& knot, double tmin, double tmax, const std::vector<Vec4>& points)
    : segments_(SplitNurbsCurve(order, knot, tmin, tmax, points)) {}

Vec3 EdgeCurve::At(std::size_t k, double t, Vec3* d) const {
  return RationalBezierAt<3>(std::span<const Vec4>(segments_[k]), t, d);
}

}  // namespace patchscan
