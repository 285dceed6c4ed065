// One face of a B-rep (Open CASCADE's TopoDS_Face) as the trimmed surfaces patchscan scans:
// a plane, cylinder, cone, sphere or torus as its analytic shape (cad_analytic.cpp), a
// B-spline or Bezier surface as a NuPatch over the face's parameter box, any other surface
// first made a B-spline by BRepBuilderAPI_NurbsConvert (which keeps the pcurves on it); its
// wires' pcurves are the trim loops (RenderMan's TrimCurve, patch/trim.h).
//
// A wire's edges come in the order BRepTools_WireExplorer connects them, each pcurve taken
// the way the wire runs; a seam edge of a closed surface comes twice, once per side of the
// parameter box, so the loop closes in (u, v) as the odd winding rule needs; a degenerate
// edge (a pole, a cone's apex) has a pcurve and no 3D curve and closes the loop the same way.
// B-rep edges meet only within a tolerance: where one pcurve ends and the next begins a few
// ulps or a tolerance apart, both ends are moved to their midpoint (the gap, measured on the
// surface, is reported).
#pragma once

#include <cstdint>
#include <memory>
#include <utility>
#include <vector>

#include "patch/nurbs.h"
#include "patch/surface.h"
#include "patch/tessellate.h"
#include "patch/trim.h"

class TopoDS_Face;
class TopoDS_Shape;
class gp_Trsf;

namespace patchscan {

struct CadFace {
  std::vector<Surface> pieces;     // the face's surface without its location, trimmed
  Affine3 location = Affine3::Identity();  // the face's own location in its shape
  bool reversed = false;           // the face's normal is the surface's P_u x P_v reversed
  double largestGap = 0.0;         // the widest joint between consecutive edges of a wire,
                                   // on the surface (model units)
};

// Throws std::runtime_error saying what is wrong: a surface that cannot be made a B-spline,
// a wire whose pcurves are missing or do not close, a NuPatch the pieces refuse (nurbs.h).
CadFace ConvertFace(const TopoDS_Face& face);

// The face's elementary surface as patchscan's analytic shape(s) over the face's parameter
// box, placed in the surface's axes (without the face's location), each cut by `loops`
// (null: whole), appended to *pieces; *mirrored where the axes are left-handed. False,
// appending nothing, for any other surface (and a sphere or torus whose box reaches past
// its own). Throws std::runtime_error for a face of no area or unbounded.
bool AnalyticFace(const TopoDS_Face& face, const std::shared_ptr<const TrimLoops>& loops, std::vector<Surface>* pieces,
                  bool* mirrored);
// Whether the face's surface is elementary with left-handed axes: its analytic shape is then
// placed by a mirroring map, and its appearance's side is turned to match (as RenderMan turns
// it under a mirroring transformation); tess mode's normals follow.
bool HasMirroredAxes(const TopoDS_Face& face);

// Open CASCADE's transformation (rotation, scale, translation) as an affine map.
Affine3 AffineOf(const gp_Trsf& t);

// The widest gap between two faces of `shape` along an edge they share: each face's pcurve of
// the edge mapped through its surface at `samples` points of the edge's range, the largest
// distance between the faces' points (model units). The scans render the faces' own
// surfaces, so this is the crack they could open.
double LargestEdgeGap(const TopoDS_Shape& shape, int samples);

// One placed part for MeshCad: the part (an index into its parts), where it is placed, and
// its faces rendered: (the face's number in TopExp::MapShapes order, from 1; the surface id
// its triangles take).
struct CadPlacedPart {
  std::size_t part = 0;
  Affine3 placement = Affine3::Identity();
  std::vector<std::pair<int, std::uint32_t>> faces;
};

// The placed parts' faces as Open CASCADE's BRepMesh_IncrementalMesh meshes them (what a
// CAD viewer shows) with a chord deviation of at most `deflection` (model units) and the
// angular deflection kCadMeshAngleRad, in world space: positions from the mesh, normals from
// each face's surface at the nodes' (u, v) (P_u x P_v, as the direct modes give them: a
// reversed face's appearance says which side is its front), a node where the surface's
// normal vanishes (a pole) taking its triangles' mean. Each part's earlier mesh is removed
// first. Throws std::runtime_error, naming the part, where the mesher fails.
TessMesh MeshCad(const std::vector<TopoDS_Shape>& parts, const std::vector<CadPlacedPart>& placed, double deflection);

}  // namespace patchscan
