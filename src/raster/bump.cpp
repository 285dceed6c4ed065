#include "raster/bump.h"

#include <Eigen/LU>
#include <cmath>

namespace patchscan::raster {

namespace {

// The world gradients of screen x and y at p; false where p is not in front of the eye.
bool ScreenGradients(const ScreenRows& screen, const Vec3& p, Vec3* gradX, Vec3* gradY) {
  const Vec3 h = screen * p.homogeneous();  // (X, Y, W)
  if (!(h.z() > 0.0)) return false;
  const double invW = 1.0 / h.z(), x = h.x() * invW, y = h.y() * invW;
  const Vec3 mw = screen.block<1, 3>(2, 0).transpose();
  // x = X / W: dx = (M_x - x M_w) . dp / W, and likewise y.
  *gradX = (screen.block<1, 3>(0, 0).transpose() - x * mw) * invW;
  *gradY = (screen.block<1, 3>(1, 0).transpose() - y * mw) * invW;
  return true;
}

}  // namespace

std::pair<Vec3, Vec3> ScreenTangents(const ScreenRows& screen, const Vec3& p, const Vec3& n) {
  Vec3 gradX, gradY;
  if (!ScreenGradients(screen, p, &gradX, &gradY)) return {Vec3::Zero(), Vec3::Zero()};
  // The tangent a with gradX . a = 1, gradY . a = 0, n . a = 0, and b likewise: the first
  // two columns of the inverse of the matrix with those rows.
  Eigen::Matrix3d rows;
  rows << gradX.transpose(), gradY.transpose(), n.transpose();
  const Eigen::Matrix3d inverse = rows.inverse();
  if (!inverse.allFinite()) return {Vec3::Zero(), Vec3::Zero()};
  return {inverse.col(0), inverse.col(1)};
}

Vec3 SurfaceGradient(const ScreenRows& screen, const Vec3& p, const Vec3& n, const Vec2& perPixel) {
  Vec3 gradX, gradY;
  if (!ScreenGradients(screen, p, &gradX, &gradY)) return Vec3::Zero();
  const Vec3 g = perPixel.x() * gradX + perPixel.y() * gradY;
  // Within the tangent plane: along any tangent t, g . t is then the function's change (the
  // screen's change along t, weighted by the change per pixel), and nothing along n.
  return g - g.dot(n) * n;
}

bool TextureTangents(const ScreenRows& screen, const Vec3& p, const Vec3& n, const Vec2& duvdx, const Vec2& duvdy,
                     Vec3* ps, Vec3* pt) {
  const auto [dpdx, dpdy] = ScreenTangents(screen, p, n);
  Eigen::Matrix2d footprint;  // columns d(s, t)/dx and d(s, t)/dy
  footprint << duvdx, duvdy;
  const double det = footprint.determinant();
  if (!(std::abs(det) > 0.0) || dpdx.isZero()) return false;
  // [P_s P_t] footprint = [dP/dx dP/dy]: the chain rule through (s, t).
  const Eigen::Matrix2d inverse = footprint.inverse();
  *ps = inverse(0, 0) * dpdx + inverse(1, 0) * dpdy;
  *pt = inverse(0, 1) * dpdx + inverse(1, 1) * dpdy;
  return ps->allFinite() && pt->allFinite();
}

Vec3 MappedNormal(const ScreenRows& screen, const Vec3& p, const Vec3& n, const Vec2& duvdx, const Vec2& duvdy,
                  const Vec3& rgb) {
  const Vec3 unit = n.normalized();
  Vec3 ps, pt;
  if (!TextureTangents(screen, p, unit, duvdx, duvdy, &ps, &pt)) return n;
  const Vec3 t = (ps - ps.dot(unit) * unit).normalized();
  const Vec3 up = -pt - (-pt).dot(unit) * unit - (-pt).dot(t) * t;
  const Vec3 b = up.normalized();
  const Vec3 m = 2.0 * rgb - Vec3::Ones();
  const Vec3 mapped = m.x() * t + m.y() * b + m.z() * unit;
  return mapped.allFinite() && mapped.squaredNorm() > 0.0 ? mapped : n;
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
