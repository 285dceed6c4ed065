#include "raster/environment.h"

namespace patchscan::raster {

Reflection ReflectedView(const ScreenRows& screen, const Vec3& p, const Vec3& n, const Vec3& eye, bool orthographic) {
  const Vec3 unit = n.normalized();
  const Vec3 toPoint = p - eye;
  const double distance = toPoint.norm();
  const Vec3 view = toPoint / distance;  // I, the unit view direction
  // R = I - 2 (N . I) N, whichever side N is on.
  const auto reflect = [&](const Vec3& v) { return Vec3(v - 2.0 * unit.dot(v) * unit); };
  Reflection out{reflect(view), Vec3::Zero(), Vec3::Zero()};
  if (orthographic || !(distance > 0.0)) return out;  // parallel view rays: no change
  // The view direction's change as the point moves one pixel in the tangent plane, dI =
  // (dP - I (I . dP)) / |P - E|, reflected (the normal held).
  const auto [dpdx, dpdy] = ScreenTangents(screen, p, unit);
  const auto change = [&](const Vec3& dp) { return Vec3((dp - view * view.dot(dp)) / distance); };
  out.drdx = reflect(change(dpdx));
  out.drdy = reflect(change(dpdy));
  return out;
}

}  // namespace patchscan::raster
