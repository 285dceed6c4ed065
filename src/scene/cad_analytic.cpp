// A B-rep face on an elementary surface (plane, cylinder, cone, sphere, torus) as the
// analytic shape patchscan scans, exact and in the face's own parameters, so that the
// face's pcurves trim it as they stand: no conversion, no re-approximated pcurve.
//
// Open CASCADE's elementary surfaces are RenderMan's quadrics in another frame. In the
// surface's own axes (gp_Ax3: X, Y, main direction Z), with u about Z from X:
//   cylinder  P = r (cos u, sin u, 0) + v Z                    Cylinder(r, v0, v1, u1 - u0)
//   cone      P = (R + v sin a)(cos u, sin u, 0) + v cos a Z   Hyperboloid of the generatrix
//   sphere    P = R cos v (cos u, sin u, 0) + R sin v Z        Sphere(R, R sin v0, R sin v1, ...)
//   torus     P = (R + r cos v)(cos u, sin u, 0) + r sin v Z   Torus(R, r, v0, v1, ...)
//   plane     P = u X + v Y                                    the bilinear patch of the box
// RenderMan's u sweeps theta from 0 (RenderMan Interface 3.2, "Quadrics"): the shape made
// for u in [u0, u1] is turned by u0 about Z. Every map from the shape's [0,1]^2 to the
// face's (u, v) is then linear in each, which is what a PieceTrim is (patch/trim.h).
#include <BRepTools.hxx>
#include <BRep_Tool.hxx>
#include <Geom_ConicalSurface.hxx>
#include <Geom_CylindricalSurface.hxx>
#include <Geom_Plane.hxx>
#include <Geom_RectangularTrimmedSurface.hxx>
#include <Geom_SphericalSurface.hxx>
#include <Geom_ToroidalSurface.hxx>
#include <TopoDS_Face.hxx>
#include <gp_Ax3.hxx>

#include <cmath>
#include <functional>
#include <numbers>
#include <stdexcept>

#include "scene/cad_face.h"

namespace patchscan {
namespace {

constexpr double kDegPerRad = 180.0 / std::numbers::pi;
constexpr double kTurn = 2.0 * std::numbers::pi;
// A face's parameter range longer than a turn (a thread winding twice round a cylinder) is
// split into equal parts of at most one turn, as RenderMan's thetamax is at most 360
// degrees; a range longer by rounding only (of OCCT's UVBounds) is one turn.
constexpr double kPastTurnRel = 1e-9;
// A bound this large is OCCT's infinite (Precision::Infinite() is 2e100): a plane, cylinder
// or cone face without wires has no extent.
constexpr double kInfinite = 1e50;

Vec3 ToVec(const gp_XYZ& p) { return {p.X(), p.Y(), p.Z()}; }

// The surface's axes as the map from its own coordinates to the face's.
Affine3 FrameOf(const gp_Ax3& a) {
  Affine3 f = Affine3::Identity();
  f.linear().col(0) = ToVec(a.XDirection().XYZ());
  f.linear().col(1) = ToVec(a.YDirection().XYZ());
  f.linear().col(2) = ToVec(a.Direction().XYZ());
  f.translation() = ToVec(a.Location().XYZ());
  return f;
}

Affine3 TurnedBy(double angle) { return Affine3(Eigen::AngleAxisd(angle, Vec3::UnitZ())); }

Handle(Geom_ElementarySurface) ElementaryOf(const TopoDS_Face& face) {
  TopLoc_Location location;
  Handle(Geom_Surface) s = BRep_Tool::Surface(face, location);
  while (auto t = Handle(Geom_RectangularTrimmedSurface)::DownCast(s)) s = t->BasisSurface();
  return Handle(Geom_ElementarySurface)::DownCast(s);
}

}  // namespace

bool HasMirroredAxes(const TopoDS_Face& face) {
  const Handle(Geom_ElementarySurface) e = ElementaryOf(face);
  return !e.IsNull() && !e->Position().Direct();
}

bool AnalyticFace(const TopoDS_Face& face, const std::shared_ptr<const TrimLoops>& loops, std::vector<Surface>* pieces,
                  bool* mirrored) {
  const Handle(Geom_ElementarySurface) elementary = ElementaryOf(face);
  if (elementary.IsNull()) return false;
  const Handle(Geom_Surface) s(elementary);
  double u0, u1, v0, v1;
  BRepTools::UVBounds(face, u0, u1, v0, v1);
  if (!(std::abs(u0) < kInfinite && std::abs(u1) < kInfinite && std::abs(v0) < kInfinite && std::abs(v1) < kInfinite))
    throw std::runtime_error("no wire bounds its unbounded surface");
  if (!(u0 < u1 && v0 < v1)) throw std::runtime_error("its wires span no area of its surface");
  const Affine3 frame = FrameOf(elementary->Position());
  *mirrored = !elementary->Position().Direct();

  // The shape for the face's u in [a, b] (a part of at most a turn), in the frame turned by a.
  std::function<Shape(double, double)> shape;
  bool revolves = true;
  if (auto plane = Handle(Geom_Plane)::DownCast(s)) {
    revolves = false;
    shape = [&](double a, double b) {
      return BilinearPatch({Vec3(a, v0, 0), Vec3(b, v0, 0), Vec3(a, v1, 0), Vec3(b, v1, 0)});
    };
  } else if (auto cylinder = Handle(Geom_CylindricalSurface)::DownCast(s)) {
    const double r = cylinder->Radius();
    shape = [&, r](double a, double b) { return Cylinder(r, v0, v1, (b - a) * kDegPerRad); };
  } else if (auto cone = Handle(Geom_ConicalSurface)::DownCast(s)) {
    const double r = cone->RefRadius(), sa = std::sin(cone->SemiAngle()), ca = std::cos(cone->SemiAngle());
    shape = [&, r, sa, ca](double a, double b) {
      return Hyperboloid(Vec3(r + v0 * sa, 0, v0 * ca), Vec3(r + v1 * sa, 0, v1 * ca), (b - a) * kDegPerRad);
    };
  } else if (auto sphere = Handle(Geom_SphericalSurface)::DownCast(s)) {
    const double r = sphere->Radius();
    if (v0 < -std::numbers::pi / 2 - kPastTurnRel || v1 > std::numbers::pi / 2 + kPastTurnRel) return false;
    shape = [&, r](double a, double b) { return Sphere(r, r * std::sin(v0), r * std::sin(v1), (b - a) * kDegPerRad); };
  } else if (auto torus = Handle(Geom_ToroidalSurface)::DownCast(s)) {
    const double big = torus->MajorRadius(), small = torus->MinorRadius();
    if (v1 - v0 > kTurn * (1 + kPastTurnRel)) return false;
    shape = [&, big, small](double a, double b) {
      return Torus(big, small, v0 * kDegPerRad, v1 * kDegPerRad, (b - a) * kDegPerRad);
    };
  } else {
    return false;
  }
  const int parts = revolves ? std::max(1, static_cast<int>(std::ceil((u1 - u0) / kTurn - kPastTurnRel))) : 1;
  for (int k = 0; k < parts; ++k) {
    const double a = u0 + (u1 - u0) * k / parts, b = k + 1 == parts ? u1 : u0 + (u1 - u0) * (k + 1) / parts;
    std::shared_ptr<const PieceTrim> trim;
    if (loops && !CutRectangle(loops, a, b, v0, v1, &trim)) continue;
    const Affine3 placed = revolves ? frame * TurnedBy(a) : frame;
    if (trim) {  // the edges are in the face's coordinates, the shape in its axes
      auto inAxes = std::make_shared<PieceTrim>(*trim);
      inAxes->objectFromEdges = placed.inverse();
      trim = std::move(inAxes);
    }
    pieces->push_back(Surface{shape(a, b), placed, std::move(trim)});
  }
  return true;
}

}  // namespace patchscan
