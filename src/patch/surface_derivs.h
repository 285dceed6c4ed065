// What a surface evaluation returns: position and partial derivatives at (u,v).
#pragma once

#include <algorithm>

#include "patch/geometry.h"

namespace patchscan {

// How much of SurfaceDerivs an evaluation fills in; higher orders include lower ones.
// Fields beyond the requested order are left untouched (not zeroed).
enum class DerivOrder { Position = 0, First = 1, Second = 2 };

// Position and derivatives of S(u,v) in one space (object or screen, as the producer says).
struct SurfaceDerivs {
  Vec3 p, dpdu, dpdv;
  Vec3 d2pdu2, d2pduv, d2pdv2;
};

// A boundary edge is collapsed (a pole, the teapot lid's apex) where one first derivative
// vanishes against the other: a tangent along the edge this small relative to the
// derivative across it, or a normal dp/du x dp/dv this small relative to |dp/du| |dp/dv|,
// or (for control points) points this close relative to the patch's extent. An exact
// collapse leaves rounding of ~1e-16 relative; a real edge, even a sliver seen edge-on, is
// many orders above. One threshold for every test of it: the edge trackers, the maxima
// pre-pass, the silhouette search, the normals and `patchscan info`.
constexpr double kCollapsedRel = 1e-9;

// True where dp/du x dp/dv is rounding, not a normal: one tangent vanishing against the
// other (at a collapsed edge the vanishing one is rounding noise in any direction, so the
// cross product's own size says nothing) or the two parallel. Normals there are limits
// from inside (WorldNormal).
inline bool NormalVanishes(const Vec3& pu, const Vec3& pv) {
  const double a = pu.norm(), b = pv.norm();
  return !(pu.cross(pv).norm() > kCollapsedRel * a * b) || !(std::min(a, b) > kCollapsedRel * std::max(a, b));
}

inline bool Wants(DerivOrder order, DerivOrder level) {
  return static_cast<int>(order) >= static_cast<int>(level);
}

}  // namespace patchscan
