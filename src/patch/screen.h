// The screen-space view of a surface: S(u,v) carried through the camera's projective map
// with the quotient rule, to second order. In screen space view rays
// are parallel to the depth axis, so Blinn's orthographic formulas (Blinn 1978 §3) hold.
#pragma once

#include <optional>

#include "patch/camera.h"
#include "patch/surface.h"

namespace patchscan {

// Screen-space position (x, y, depth) and derivatives, plus w, the distance along the
// view axis (perspective: w <= 0 is at or behind the eye, where x, y and depth are
// meaningless; orthographic: behind the camera plane).
struct ScreenDerivs : SurfaceDerivs {
  double w = 0.0;
};

// screenFromObject for one surface and camera: prepared once, then maps object-space
// derivatives to screen space. Allocates nothing.
class ScreenMap {
 public:
  ScreenMap(const Camera& camera, const Affine3& worldFromObject)
      : m_(ScreenFromWorld(camera) * worldFromObject.matrix()),
        depth_((ViewDepthRow(camera).transpose() * worldFromObject.matrix()).transpose()),
        affine_(camera.orthographic) {}

  // The map of another space, placed in this map's object space by objectFromOther.
  ScreenMap(const ScreenMap& map, const Affine3& objectFromOther)
      : m_(map.m_ * objectFromOther.matrix()),
        depth_((map.depth_.transpose() * objectFromOther.matrix()).transpose()),
        affine_(map.affine_) {}

  const Mat4& ScreenFromObject() const { return m_; }

  // Distance of an object-space point along the view axis (ScreenDerivs::w).
  double ViewDepth(const Vec3& pObject) const { return depth_.head<3>().dot(pObject) + depth_[3]; }
  // Its change along an object-space direction (a derivative of the point).
  double ViewDepthChange(const Vec3& dObject) const { return depth_.head<3>().dot(dObject); }

  // Homogeneous screen point (X, Y, D, W) of an object-space point.
  Vec4 Homogeneous(const Vec3& pObject) const {
    return m_.block<4, 3>(0, 0) * pObject + m_.col(3);
  }

  // Screen derivatives of the orders requested, from object-space ones of at least those
  // orders. With s = (X, Y, D) / W:  s_u = (H_u - s W_u) / W,
  // s_uu = (H_uu - 2 s_u W_u - s W_uu) / W,  s_uv = (H_uv - s_u W_v - s_v W_u - s W_uv) / W.
  void FromObject(const SurfaceDerivs& o, DerivOrder order, ScreenDerivs* s) const;

 private:
  Mat4 m_;
  Vec4 depth_;   // object space: the view-depth row
  bool affine_;  // orthographic: W = 1, and w comes from depth_
};

// Evaluate a shape (any type with the shapes' Evaluate) in screen space. Inline, no
// dispatch: hot code calls this inside one VisitShape.
template <class ShapeT>
inline void EvaluateScreen(const ShapeT& shape, const ScreenMap& map, double u, double v,
                           DerivOrder order, ScreenDerivs* out) {
  SurfaceDerivs o;
  shape.Evaluate(u, v, order, &o);
  map.FromObject(o, order, out);
}

// Screen-space evaluation of any surface: one dispatch per call (tests, non-hot code).
inline void EvaluateScreen(const Surface& s, const ScreenMap& map, double u, double v,
                           DerivOrder order, ScreenDerivs* out) {
  VisitShape(s, [&](const auto& shape) { EvaluateScreen(shape, map, u, v, order, out); });
}

// Blinn's silhouette function Zn (Blinn 1978 §3.1): the depth component of the screen
// normal, J = x_u y_v - x_v y_u. Zero on the silhouette; its sign says which side faces
// the eye. Needs first derivatives.
inline double SilhouetteJ(const SurfaceDerivs& s) {
  return s.dpdu.x() * s.dpdv.y() - s.dpdv.x() * s.dpdu.y();
}

// The screen-space normal s_u x s_v (unnormalized; z component is J).
inline Vec3 ScreenNormal(const SurfaceDerivs& s) { return s.dpdu.cross(s.dpdv); }

// Conservative screen box (x, y, depth) of a surface: the box of its projected hull
// points. nullopt when some hull point is not in front of the eye (w <= 0), where the
// projection of the hull is unbounded.
std::optional<Bounds3> ScreenBounds(const Surface& s, const ScreenMap& map);

// True when every hull point is nearer to the eye than `hither` along the view axis (or
// behind the eye): nothing of the surface can be seen.
bool WhollyBeforeHither(const Surface& s, const ScreenMap& map, double hither);

// ---- inline ----

inline void ScreenMap::FromObject(const SurfaceDerivs& o, DerivOrder order,
                                  ScreenDerivs* s) const {
  const Eigen::Matrix<double, 4, 3> a = m_.block<4, 3>(0, 0);
  const Vec4 h = a * o.p + m_.col(3);
  const double w = h.w(), invW = 1.0 / w;
  s->w = affine_ ? ViewDepth(o.p) : w;
  s->p = h.head<3>() * invW;
  if (!Wants(order, DerivOrder::First)) return;
  const Vec4 hu = a * o.dpdu, hv = a * o.dpdv;
  s->dpdu = (hu.head<3>() - s->p * hu.w()) * invW;
  s->dpdv = (hv.head<3>() - s->p * hv.w()) * invW;
  if (!Wants(order, DerivOrder::Second)) return;
  const Vec4 huu = a * o.d2pdu2, huv = a * o.d2pduv, hvv = a * o.d2pdv2;
  s->d2pdu2 = (huu.head<3>() - 2.0 * s->dpdu * hu.w() - s->p * huu.w()) * invW;
  s->d2pdv2 = (hvv.head<3>() - 2.0 * s->dpdv * hv.w() - s->p * hvv.w()) * invW;
  s->d2pduv = (huv.head<3>() - s->dpdu * hv.w() - s->dpdv * hu.w() - s->p * huv.w()) * invW;
}

}  // namespace patchscan
