#include "raster/bump.h"

namespace patchscan::raster {

Vec3 SurfaceGradient(const ScreenRows& screen, const Vec3& p, const Vec3& n, const Vec2& perPixel) {
  const Eigen::Vector4d ph(p.x(), p.y(), p.z(), 1.0);
  const Vec3 h = screen * ph;  // (X, Y, W)
  if (!(h.z() > 0.0)) return Vec3::Zero();
  const double invW = 1.0 / h.z(), x = h.x() * invW, y = h.y() * invW;
  const Vec3 mw = screen.block<1, 3>(2, 0).transpose();
  // x = X / W: dx = (M_x - x M_w) . dp / W, and likewise y.
  const Vec3 gradX = (screen.block<1, 3>(0, 0).transpose() - x * mw) * invW;
  const Vec3 gradY = (screen.block<1, 3>(1, 0).transpose() - y * mw) * invW;
  const Vec3 g = perPixel.x() * gradX + perPixel.y() * gradY;
  // Within the tangent plane: along any tangent t, g . t is then the function's change (the
  // screen's change along t, weighted by the change per pixel), and nothing along n.
  return g - g.dot(n) * n;
}

Vec3 BumpedNormal(const ScreenRows& screen, const Vec3& p, const Vec3& n, const Vec2& heightGradient,
                  const Vec2& duvdx, const Vec2& duvdy) {
  const double len = n.norm();
  if (!(len > 0.0)) return n;
  const Vec3 unit = n / len;
  // dh/dx = B_s ds/dx + B_t dt/dx, and likewise in y.
  const Vec2 perPixel(heightGradient.dot(duvdx), heightGradient.dot(duvdy));
  const Vec3 bumped = unit - SurfaceGradient(screen, p, unit, perPixel);
  return bumped.allFinite() ? bumped : unit;
}

}  // namespace patchscan::raster
