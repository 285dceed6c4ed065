// A Surface: one shape of any kind, placed in the world. Dispatch over the kinds happens
// once per call of VisitShape (a std::visit); the shapes' own Evaluate functions are
// inline and non-virtual, so a tracker that visits once per scan line pays no dispatch
// per Newton iteration.
#pragma once

#include <Eigen/Geometry>
#include <memory>
#include <span>
#include <string>
#include <variant>

#include "patch/bicubic.h"
#include "patch/curves.h"
#include "patch/nurbs.h"
#include "patch/quadrics.h"
#include "patch/subdiv.h"
#include "patch/trim.h"

namespace patchscan {

using Shape = std::variant<BicubicPatch, BilinearPatch, Sphere, Cylinder, Cone, Paraboloid,
                           Hyperboloid, Disk, Torus, Saddle, MonkeySaddle, SubdivFace, NurbsPiece, CurveRibbon>;

using Affine3 = Eigen::Affine3d;

struct Surface {
  Shape shape;
  Affine3 worldFromObject = Affine3::Identity();
  // The trim curves that cut into the surface (trim.h), or null: the surface is whole.
  std::shared_ptr<const PieceTrim> trim = nullptr;
};

template <class F>
decltype(auto) VisitShape(const Surface& s, F&& f) {
  return std::visit(std::forward<F>(f), s.shape);
}

// The surface's trim; null where it is whole.
inline const PieceTrim* TrimOf(const Surface& s) { return s.trim.get(); }

// Texture coordinates at (u, v) with their derivatives in (u, v): a subdivision face's "st"
// where its cage has them, else (u, v) itself.
inline TexCoords TextureCoordsAt(const Surface& s, double u, double v) {
  if (const auto* f = std::get_if<SubdivFace>(&s.shape))
    if (auto st = f->TextureCoords(u, v)) return *st;
  return TexCoords{Vec2(u, v), Vec2(1.0, 0.0), Vec2(0.0, 1.0)};
}

// Holds what a surface prepares on demand (a subdivision face's Bfr surface, patch/subdiv.h)
// for the holder's lifetime; the last hold's end frees it. Other kinds prepare nothing.
// fit: the holder evaluates the surface many times (a scan), worth fitting a subdivision
// face's bicubic pieces for (SubdivFace::Hold).
class SurfaceHold {
 public:
  explicit SurfaceHold(const Surface& s, bool fit = false) : face_(std::get_if<SubdivFace>(&s.shape)) {
    if (face_) face_->Hold(fit);
  }
  ~SurfaceHold() {
    if (face_) face_->Release();
  }
  SurfaceHold(const SurfaceHold&) = delete;
  SurfaceHold& operator=(const SurfaceHold&) = delete;

 private:
  const SubdivFace* face_;
};

// Object-space evaluation of any surface (one dispatch per call: for tests and
// non-hot code; hot code visits once and calls the shape's Evaluate directly).
inline void EvaluateObject(const Surface& s, double u, double v, DerivOrder order,
                           SurfaceDerivs* out) {
  VisitShape(s, [&](const auto& shape) { shape.Evaluate(u, v, order, out); });
}

// Points whose convex hull contains the surface, in object space.
inline std::span<const Vec3> ObjectHull(const Surface& s) {
  return VisitShape(s, [](const auto& shape) { return shape.Hull(); });
}

// A conservative world-space box of the surface (its hull's box, transformed).
Bounds3 WorldBounds(const Surface& s);

// One line naming the kind and its parameters.
std::string Describe(const Surface& s);

}  // namespace patchscan
