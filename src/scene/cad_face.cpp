#include "scene/cad_face.h"

#include <BRepBuilderAPI_NurbsConvert.hxx>
#include <BRepTools.hxx>
#include <BRepTools_WireExplorer.hxx>
#include <BRep_Tool.hxx>
#include <Geom2dConvert.hxx>
#include <Geom2d_BSplineCurve.hxx>
#include <Geom2d_TrimmedCurve.hxx>
#include <GeomConvert.hxx>
#include <Geom_BSplineCurve.hxx>
#include <Geom_TrimmedCurve.hxx>
#include <Geom_BSplineSurface.hxx>
#include <Geom_BezierSurface.hxx>
#include <Geom_RectangularTrimmedSurface.hxx>
#include <TopExp.hxx>
#include <TopExp_Explorer.hxx>
#include <TopTools_IndexedDataMapOfShapeListOfShape.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Face.hxx>
#include <TopoDS_Wire.hxx>

#include <algorithm>
#include <cmath>
#include <memory>
#include <stdexcept>
#include <string>

#include "patch/trim.h"

namespace patchscan {
namespace {

using Curve2 = Handle(Geom2d_BSplineCurve);

// The face's B-spline or Bezier surface as a B-spline (a Bezier one's parameters kept), not
// periodic (a periodic one's knots would not give RenderMan's clamped NuPatch); null for
// any other surface.
Handle(Geom_BSplineSurface) BSplineOf(const TopoDS_Face& face) {
  TopLoc_Location location;
  Handle(Geom_Surface) s = BRep_Tool::Surface(face, location);
  while (auto t = Handle(Geom_RectangularTrimmedSurface)::DownCast(s)) s = t->BasisSurface();
  Handle(Geom_BSplineSurface) b;
  if (auto bezier = Handle(Geom_BezierSurface)::DownCast(s)) b = GeomConvert::SurfaceToBSplineSurface(bezier);
  else b = Handle(Geom_BSplineSurface)::DownCast(s);
  if (b.IsNull()) return b;
  if (b->IsUPeriodic() || b->IsVPeriodic()) {
    b = Handle(Geom_BSplineSurface)::DownCast(b->Copy());
    if (b->IsUPeriodic()) b->SetUNotPeriodic();
    if (b->IsVPeriodic()) b->SetVNotPeriodic();
  }
  return b;
}

std::vector<double> Knots(const TColStd_Array1OfReal& k) { return {k.begin(), k.end()}; }

// How far a face's parameter box may reach past its surface's before the surface is
// repeated one period on (OCCT's UVBounds are of the pcurves: rounding, not a wrap), as a
// fraction of the surface's range.
constexpr double kPastRangeRel = 1e-9;
// The first and last rows of a closed surface's control points agree this closely (of the
// largest homogeneous control point): NurbsConvert copies the seam's points.
constexpr double kClosedRel = 1e-7;

// The NuPatch of `b` over the face's parameter box: a box past the surface's range on a
// closed surface (a thread's face winding round a cylinder twice, a face whose pcurves lie
// one period on) repeats the surface there; on an open one it is cut to the surface's.
NurbsSurface NuPatchOf(const Handle(Geom_BSplineSurface)& b, const TopoDS_Face& face) {
  NurbsSurface n;
  n.nu = b->NbUPoles();
  n.nv = b->NbVPoles();
  n.uorder = b->UDegree() + 1;
  n.vorder = b->VDegree() + 1;
  n.uknot = Knots(b->UKnotSequence());
  n.vknot = Knots(b->VKnotSequence());
  double scale = 0.0;
  n.pw.reserve(static_cast<std::size_t>(n.nu) * static_cast<std::size_t>(n.nv));
  for (int j = 1; j <= n.nv; ++j)
    for (int i = 1; i <= n.nu; ++i) {
      const gp_Pnt& p = b->Pole(i, j);
      const double w = b->Weight(i, j);
      n.pw.emplace_back(w * p.X(), w * p.Y(), w * p.Z(), w);
      scale = std::max(scale, n.pw.back().norm());
    }
  double su0, su1, sv0, sv1, u0, u1, v0, v1;
  b->Bounds(su0, su1, sv0, sv1);
  BRepTools::UVBounds(face, u0, u1, v0, v1);
  n.umin = su0, n.umax = su1, n.vmin = sv0, n.vmax = sv1;
  const auto past = [](double lo, double hi, double s0, double s1) {
    const double slack = kPastRangeRel * (s1 - s0);
    return lo < s0 - slack || hi > s1 + slack;
  };
  try {
    if (past(u0, u1, su0, su1) && b->IsUClosed()) n = RepeatPeriods(n, true, u0, u1, kClosedRel * scale);
    if (past(v0, v1, sv0, sv1) && b->IsVClosed()) n = RepeatPeriods(n, false, v0, v1, kClosedRel * scale);
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(std::string("its parameter box reaches past its surface's, which cannot be repeated: ") + e.what());
  }
  n.umin = std::clamp(u0, n.umin, n.umax), n.umax = std::clamp(u1, n.umin, n.umax);
  n.vmin = std::clamp(v0, n.vmin, n.vmax), n.vmax = std::clamp(v1, n.vmin, n.vmax);
  if (!(n.umin < n.umax && n.vmin < n.vmax)) throw std::runtime_error("its wires span no area of its surface");
  return n;
}

// The pcurve of `edge` on `face` over the edge's range, the way the wire runs, clamped (its
// ends are its first and last poles).
Curve2 PcurveOf(const TopoDS_Edge& edge, const TopoDS_Face& face) {
  double first = 0, last = 0;
  Handle(Geom2d_Curve) c = BRep_Tool::CurveOnSurface(edge, face, first, last);
  if (c.IsNull()) throw std::runtime_error("an edge has no curve on the face (pcurve)");
  if (!(first < last)) throw std::runtime_error("an edge's range is empty");
  Curve2 b = Geom2dConvert::CurveToBSplineCurve(new Geom2d_TrimmedCurve(c, first, last));
  if (b->IsPeriodic()) b->SetNotPeriodic();
  const int ends = b->Degree() + 1;
  if (b->Multiplicity(1) != ends || b->Multiplicity(b->NbKnots()) != ends) b->Segment(b->FirstParameter(), b->LastParameter());
  if (edge.Orientation() == TopAbs_REVERSED) b->Reverse();
  return b;
}

// The 3D curve of `edge` over its range, in the coordinates of `face`'s surface (without the
// face's location), as the faces that share it meet along it; null for a degenerate edge
// (a pole, a cone's apex) or one without a 3D curve.
std::shared_ptr<const EdgeCurve> EdgeCurveOf(const TopoDS_Edge& edge, const TopoDS_Face& face) {
  if (BRep_Tool::Degenerated(edge)) return nullptr;
  TopLoc_Location edgeLocation, faceLocation;
  double first = 0, last = 0;
  const Handle(Geom_Curve) c = BRep_Tool::Curve(edge, edgeLocation, first, last);
  BRep_Tool::Surface(face, faceLocation);
  if (c.IsNull() || !(first < last)) return nullptr;
  Handle(Geom_BSplineCurve) b = GeomConvert::CurveToBSplineCurve(new Geom_TrimmedCurve(c, first, last));
  if (b->IsPeriodic()) b->SetNotPeriodic();
  b->Transform(faceLocation.Inverted().Multiplied(edgeLocation).Transformation());
  std::vector<Vec4> points;
  for (int i = 1; i <= b->NbPoles(); ++i) {
    const gp_Pnt& p = b->Pole(i);
    const double w = b->Weight(i);
    points.emplace_back(w * p.X(), w * p.Y(), w * p.Z(), w);
  }
  return std::make_shared<const EdgeCurve>(b->Degree() + 1, Knots(b->KnotSequence()), b->FirstParameter(),
                                           b->LastParameter(), points);
}

TrimCurveInput TrimCurveOf(const Curve2& b) {
  TrimCurveInput t;
  t.order = b->Degree() + 1;
  t.knot = Knots(b->KnotSequence());
  t.tmin = b->FirstParameter();
  t.tmax = b->LastParameter();
  for (int i = 1; i <= b->NbPoles(); ++i) {
    const gp_Pnt2d& p = b->Pole(i);
    const double w = b->Weight(i);
    t.uvw.emplace_back(w * p.X(), w * p.Y(), w);
  }
  return t;
}

// The loop of one wire, its joints moved to their midpoints; the widest joint on the
// surface goes to *gap.
std::vector<TrimCurveInput> LoopOf(const TopoDS_Wire& wire, const TopoDS_Face& face, const Handle(Geom_Surface)& surface,
                                   double* gap) {
  std::vector<Curve2> curves;
  std::vector<std::shared_ptr<const EdgeCurve>> edges3d;
  for (BRepTools_WireExplorer e(wire, face); e.More(); e.Next()) {
    curves.push_back(PcurveOf(e.Current(), face));
    edges3d.push_back(EdgeCurveOf(e.Current(), face));
  }
  int edges = 0;
  for (TopExp_Explorer e(wire, TopAbs_EDGE); e.More(); e.Next()) ++edges;
  if (curves.empty() || static_cast<int>(curves.size()) < edges)
    throw std::runtime_error("a wire's edges do not join into one loop (" + std::to_string(curves.size()) + " of " +
                             std::to_string(edges) + " connected)");
  for (std::size_t k = 0; k < curves.size(); ++k) {
    const Curve2& a = curves[k];
    const Curve2& b = curves[(k + 1) % curves.size()];
    const gp_Pnt2d end = a->Pole(a->NbPoles()), start = b->Pole(1);
    *gap = std::max(*gap, surface->Value(end.X(), end.Y()).Distance(surface->Value(start.X(), start.Y())));
    const gp_Pnt2d mid((end.XY() + start.XY()) / 2);
    a->SetPole(a->NbPoles(), mid);
    b->SetPole(1, mid);
  }
  std::vector<TrimCurveInput> loop;
  loop.reserve(curves.size());
  for (std::size_t k = 0; k < curves.size(); ++k) {
    loop.push_back(TrimCurveOf(curves[k]));
    loop.back().edge = std::move(edges3d[k]);
  }
  return loop;
}

// The point of `edge`'s pcurve on `face` at the fraction s of its range, on the surface, in
// the shape's coordinates.
gp_Pnt PointOnFace(const TopoDS_Edge& edge, const TopoDS_Face& face, double s) {
  double first = 0, last = 0;
  Handle(Geom2d_Curve) c = BRep_Tool::CurveOnSurface(edge, face, first, last);
  TopLoc_Location location;
  Handle(Geom_Surface) surface = BRep_Tool::Surface(face, location);
  if (c.IsNull() || surface.IsNull()) throw std::runtime_error("an edge has no curve on a face it bounds");
  const gp_Pnt2d uv = c->Value(first + s * (last - first));
  // Past a closed surface's range the render repeats it (NuPatchOf): wrap there.
  double u0, u1, v0, v1;
  surface->Bounds(u0, u1, v0, v1);
  const auto wrap = [](double t, double lo, double hi, bool closed) {
    return closed && (t < lo || t > hi) ? lo + std::fmod(std::fmod(t - lo, hi - lo) + (hi - lo), hi - lo) : t;
  };
  const double u = wrap(uv.X(), u0, u1, surface->IsUClosed()), v = wrap(uv.Y(), v0, v1, surface->IsVClosed());
  return surface->Value(u, v).Transformed(location.Transformation());
}

}  // namespace

Affine3 AffineOf(const gp_Trsf& t) {
  Affine3 a = Affine3::Identity();
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 4; ++c) a.matrix()(r, c) = t.Value(r + 1, c + 1);
  return a;
}

double LargestEdgeGap(const TopoDS_Shape& shape, int samples) {
  TopTools_IndexedDataMapOfShapeListOfShape edgeFaces;
  TopExp::MapShapesAndAncestors(shape, TopAbs_EDGE, TopAbs_FACE, edgeFaces);
  double gap = 0.0;
  std::vector<TopoDS_Face> faces;
  std::vector<gp_Pnt> points;
  for (int i = 1; i <= edgeFaces.Extent(); ++i) {
    const TopoDS_Edge& edge = TopoDS::Edge(edgeFaces.FindKey(i));
    if (BRep_Tool::Degenerated(edge)) continue;
    faces.clear();
    for (const TopoDS_Shape& f : edgeFaces(i))
      if (std::none_of(faces.begin(), faces.end(), [&](const TopoDS_Face& g) { return g.IsSame(f); }))
        faces.push_back(TopoDS::Face(f));
    if (faces.size() < 2) continue;
    for (int k = 0; k < samples; ++k) {
      const double s = samples > 1 ? static_cast<double>(k) / (samples - 1) : 0.5;
      points.clear();
      for (const TopoDS_Face& f : faces) points.push_back(PointOnFace(edge, f, s));
      for (std::size_t a = 0; a < points.size(); ++a)
        for (std::size_t b = a + 1; b < points.size(); ++b) gap = std::max(gap, points[a].Distance(points[b]));
    }
  }
  return gap;
}

CadFace ConvertFace(const TopoDS_Face& face) {
  CadFace out;
  TopLoc_Location location;
  const Handle(Geom_Surface) surface = BRep_Tool::Surface(face, location);
  if (surface.IsNull()) throw std::runtime_error("the face has no surface");
  out.location = AffineOf(location.Transformation());
  out.reversed = (face.Orientation() == TopAbs_REVERSED) != (location.Transformation().IsNegative() != 0);
  std::vector<std::vector<TrimCurveInput>> wires;
  for (TopExp_Explorer w(face, TopAbs_WIRE); w.More(); w.Next())
    wires.push_back(LoopOf(TopoDS::Wire(w.Current()), face, surface, &out.largestGap));
  try {
    const auto loops = wires.empty() ? nullptr : std::make_shared<const TrimLoops>(wires, true);
    bool mirrored = false;
    if (AnalyticFace(face, loops, &out.pieces, &mirrored)) {
      out.reversed = out.reversed != mirrored;
      return out;
    }
    const Handle(Geom_BSplineSurface) b = BSplineOf(face);
    if (b.IsNull()) {
      // Another kind (the model's swept and offset surfaces are made B-splines as it is read:
      // cad_reader.cpp): NurbsConvert's approximation of the face, its pcurves with it.
      BRepBuilderAPI_NurbsConvert convert(face, Standard_True);
      for (TopExp_Explorer f(convert.Shape(), TopAbs_FACE); f.More(); f.Next())
        if (!BSplineOf(TopoDS::Face(f.Current())).IsNull()) return ConvertFace(TopoDS::Face(f.Current()));
      throw std::runtime_error(std::string("its surface, a ") + surface->DynamicType()->Name() + ", cannot be made a B-spline");
    }
    std::vector<NurbsPiece> pieces = SplitNurbs(NuPatchOf(b, face));
    if (!loops) {
      for (NurbsPiece& piece : pieces) out.pieces.push_back(Surface{std::move(piece)});
    } else {
      for (TrimmedPiece& t : TrimPieces(loops, std::move(pieces)))
        out.pieces.push_back(Surface{std::move(t.piece), Affine3::Identity(), std::move(t.trim)});
    }
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(e.what());
  }
  return out;
}

}  // namespace patchscan
