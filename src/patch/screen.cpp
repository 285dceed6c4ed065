#include "patch/screen.h"

namespace patchscan {

std::optional<Bounds3> ScreenBounds(const Surface& s, const ScreenMap& map) {
  // The projective image of a convex set lying wholly in front of the eye is the convex
  // hull of its projected points, so projecting the hull bounds the surface.
  Bounds3 box;
  for (const Vec3& p : ObjectHull(s)) {
    const Vec4 h = map.Homogeneous(p);
    if (!(h.w() > 0.0)) return std::nullopt;
    box.Extend(Vec3(h.head<3>() / h.w()));
  }
  return box;
}

bool WhollyBeforeHither(const Surface& s, const ScreenMap& map, double hither) {
  for (const Vec3& p : ObjectHull(s))
    if (map.ViewDepth(p) >= hither) return false;
  return true;
}

}  // namespace patchscan
