// A point of a surface seen on the screen, with what the trackers and the X scan's walks
// need there: screen x, y and their (u,v) gradients, the silhouette function J, the eye
// distance, and the object-space derivatives. Every tracker of the scan plane (edge,
// silhouette, θ, turn) and every walk along a level curve y = ys evaluates these.
#pragma once

#include <cmath>

#include "core/vec.h"
#include "patch/screen.h"

namespace patchscan {

struct LevelPoint {
  Vec2 uv;
  double x = 0.0, y = 0.0;
  Vec2 gradX, gradY;
  double j = 0.0;   // J = x_u y_v - x_v y_u (Blinn's Zn: zero on the silhouette)
  double jn = 0.0;  // J / (|grad x| |grad y|): the sine of the angle, scale-free
  double w = 0.0;   // eye distance
  SurfaceDerivs object;  // position and first derivatives in object space (second on request)
  bool second = false;   // `object` has its second derivatives
  bool ok = false;       // finite, in front of the eye, and y varies there
  // The change of (u,v) per pixel along the scan line (y constant, towards +x): x_u du +
  // x_v dv = 1, y_u du + y_v dv = 0. Infinite on the silhouette.
  Vec2 UvPerPixelAlongRow() const { return Vec2(gradY.y(), -gradY.x()) / j; }
};

// The point of `shape` at uv through `map`. `order` Second also fills in the object-space
// second derivatives (the θ trackers' G_i needs the normal's derivatives); the screen
// quantities are first order either way. Never allocates.
template <class ShapeT>
LevelPoint EvalLevelPoint(const ShapeT& shape, const ScreenMap& map, const Vec2& uv,
                          DerivOrder order = DerivOrder::First) {
  LevelPoint p;
  p.uv = uv;
  ScreenDerivs d;
  shape.Evaluate(uv.x(), uv.y(), order, &p.object);
  p.second = Wants(order, DerivOrder::Second);
  map.FromObject(p.object, DerivOrder::First, &d);
  p.w = d.w;
  p.x = d.p.x();
  p.y = d.p.y();
  p.gradX = Vec2(d.dpdu.x(), d.dpdv.x());
  p.gradY = Vec2(d.dpdu.y(), d.dpdv.y());
  p.j = p.gradX.x() * p.gradY.y() - p.gradX.y() * p.gradY.x();
  const double scale = p.gradX.norm() * p.gradY.norm();
  p.jn = scale > 0.0 ? p.j / scale : 0.0;
  p.ok = std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.j) && d.w > 0.0 && p.gradY.squaredNorm() > 0.0;
  return p;
}

}  // namespace patchscan
