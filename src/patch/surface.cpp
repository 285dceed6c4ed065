#include "patch/surface.h"

namespace patchscan {

Bounds3 WorldBounds(const Surface& s) {
  Bounds3 b;
  for (const Vec3& p : ObjectHull(s)) b.Extend(s.worldFromObject * p);
  return b;
}

std::string Describe(const Surface& s) {
  return VisitShape(s, [](const auto& shape) { return shape.Describe(); });
}

}  // namespace patchscan
