#include <BRepMesh_IncrementalMesh.hxx>
#include <BRepTools.hxx>
#include <BRep_Tool.hxx>
#include <Geom_Surface.hxx>
#include <Poly_Triangulation.hxx>
#include <Standard_Failure.hxx>
#include <TopExp.hxx>
#include <TopTools_IndexedMapOfShape.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Face.hxx>

#include <stdexcept>
#include <string>

#include "scene/cad_face.h"

namespace patchscan {
namespace {

// BRepMesh's angular deflection: the most two neighbouring facets' normals may turn. The
// linear deflection, from the screen, bounds the silhouette's error; this keeps the shading
// of small, strongly curved faces (fillets a fraction of a pixel deep) from going flat.
constexpr double kCadMeshAngleRad = 0.2;

Vec3 ToVec(const gp_XYZ& p) { return {p.X(), p.Y(), p.Z()}; }

// Appends one located face's triangulation, placed by `placement`, its triangles taking `id`.
void AppendFace(const TopoDS_Face& face, const Affine3& placement, std::uint32_t id, TessMesh* out) {
  TopLoc_Location location;
  const Handle(Poly_Triangulation) tri = BRep_Tool::Triangulation(face, location);
  if (tri.IsNull() || tri->NbNodes() == 0) return;
  TopLoc_Location surfaceLocation;
  const Handle(Geom_Surface) surface = BRep_Tool::Surface(face, surfaceLocation);
  const Affine3 nodes = placement * AffineOf(location.Transformation());
  const Affine3 tangents = placement * AffineOf(surfaceLocation.Transformation());
  const auto base = static_cast<std::uint32_t>(out->vertices.size());
  // P_u x P_v as the direct modes give it: turned where the analytic shape is placed by a
  // mirroring map (cad_face.h HasMirroredAxes), which the face's appearance turns back.
  const Eigen::Matrix3d normalMatrix = (HasMirroredAxes(face) ? -1.0 : 1.0) * tangents.linear().inverse().transpose();
  std::vector<bool> vanished(static_cast<std::size_t>(tri->NbNodes()), false);
  for (int i = 1; i <= tri->NbNodes(); ++i) {
    TessVertex v{Vec3::Zero(), Vec3(0, 0, 1), Vec2::Zero(), Vec2::Zero()};
    v.position = nodes * ToVec(tri->Node(i).XYZ());
    Vec3 n = Vec3::Zero();
    if (tri->HasUVNodes() && !surface.IsNull()) {
      const gp_Pnt2d uv = tri->UVNode(i);
      gp_Pnt p;
      gp_Vec du, dv;
      surface->D1(uv.X(), uv.Y(), p, du, dv);
      n = normalMatrix * ToVec(du.Crossed(dv).XYZ());
      v.uv = v.st = Vec2(uv.X(), uv.Y());
    }
    if (n.norm() > 0.0) v.normal = n.normalized();
    else vanished[static_cast<std::size_t>(i - 1)] = true;
    out->vertices.push_back(v);
  }
  std::vector<Vec3> sums(vanished.size(), Vec3::Zero());
  for (int k = 1; k <= tri->NbTriangles(); ++k) {
    int a, b, c;
    tri->Triangle(k).Get(a, b, c);
    const std::array<std::uint32_t, 3> t{base + static_cast<std::uint32_t>(a - 1), base + static_cast<std::uint32_t>(b - 1),
                                         base + static_cast<std::uint32_t>(c - 1)};
    out->triangles.push_back(t);
    out->surfaceOf.push_back(id);
    const Vec3 facet = (out->vertices[t[1]].position - out->vertices[t[0]].position)
                           .cross(out->vertices[t[2]].position - out->vertices[t[0]].position);
    for (std::uint32_t i : t) sums[i - base] += facet;
  }
  for (std::size_t i = 0; i < vanished.size(); ++i)
    if (vanished[i]) out->vertices[base + i].normal = sums[i].norm() > 0.0 ? sums[i].normalized() : Vec3(0, 0, 1);
}

}  // namespace

TessMesh MeshCad(const std::vector<TopoDS_Shape>& parts, const std::vector<CadPlacedPart>& placed, double deflection) {
  std::vector<TopTools_IndexedMapOfShape> faces(parts.size());
  for (std::size_t k = 0; k < parts.size(); ++k) {
    try {
      BRepTools::Clean(parts[k]);
      BRepMesh_IncrementalMesh(parts[k], deflection, Standard_False, kCadMeshAngleRad, Standard_False);
    } catch (const Standard_Failure& e) {  // not a std::exception: the caller's handlers would miss it
      throw std::runtime_error("Open CASCADE's mesher failed on part " + std::to_string(k + 1) + " of " +
                               std::to_string(parts.size()) + ": " + e.GetMessageString());
    }
    TopExp::MapShapes(parts[k], TopAbs_FACE, faces[k]);
  }
  TessMesh out;
  for (const CadPlacedPart& p : placed)
    for (const auto& [number, id] : p.faces) AppendFace(TopoDS::Face(faces[p.part](number)), p.placement, id, &out);
  return out;
}

}  // namespace patchscan
