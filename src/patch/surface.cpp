#include "patch/surface.h"

namespace patchscan {

Bounds3 WorldBounds(const Surface& s) {
  Bounds3 b;
  for (const Vec3& p : ObjectHull(s)) b.Extend(s.worldFromObject * p);
  return b;
}

std::string Describe(const Surface& s) {
  std::string d = VisitShape(s, [](const auto& shape) { return shape.Describe(); });
  if (s.trim)
    d += ", trimmed: " + std::to_string(s.trim->segments.size()) + " of " +
         std::to_string(s.trim->loops->Segments().size()) + " trim segments reach it";
  return d;
}

}  // namespace patchscan
