#include "patch/subdiv.h"

#include <opensubdiv/bfr/refinerSurfaceFactory.h>
#include <opensubdiv/bfr/surface.h>
#include <opensubdiv/far/topologyDescriptor.h>
#include <opensubdiv/far/topologyRefinerFactory.h>

#include <stdexcept>

namespace patchscan {

namespace osd = OpenSubdiv;

struct SubdivFace::Prepared {
  std::shared_ptr<const SubdivMesh> cage;
  int face = 0;
  osd::Bfr::Surface<double> surface;
  std::vector<double> patchPoints;  // x y z per point: the control points, then any Bfr adds
  std::vector<Vec3> hull;           // the same points as vectors
};

SubdivFace::SubdivFace(std::shared_ptr<const Prepared> face, int subFace) : face_(std::move(face)), subFace_(subFace) {
  if (subFace_ < 0) return;
  double c00[2], c10[2], c01[2], c11[2];
  const osd::Bfr::Parameterization param = face_->surface.GetParameterization();
  if (param.GetType() == osd::Bfr::Parameterization::TRI) {
    // The kite at corner k of the triangle (0,0), (1,0), (0,1): the corner, the midpoint of
    // the edge after it, the centre, the midpoint of the edge before it.
    const double corner[3][2] = {{0.0, 0.0}, {1.0, 0.0}, {0.0, 1.0}};
    const double* a = corner[subFace_];
    const double* b = corner[(subFace_ + 1) % 3];
    const double* c = corner[(subFace_ + 2) % 3];
    for (int i = 0; i < 2; ++i) {
      c00[i] = a[i];
      c10[i] = 0.5 * (a[i] + b[i]);
      c11[i] = (a[i] + b[i] + c[i]) / 3.0;
      c01[i] = 0.5 * (a[i] + c[i]);
    }
  } else {
    // Bfr's quadrangulated sub-face: an affine map, read off at its corners.
    const double s00[2] = {0.0, 0.0}, s10[2] = {1.0, 0.0}, s01[2] = {0.0, 1.0};
    param.ConvertNormalizedSubFaceToCoord(subFace_, s00, c00);
    param.ConvertNormalizedSubFaceToCoord(subFace_, s10, c10);
    param.ConvertNormalizedSubFaceToCoord(subFace_, s01, c01);
    for (int i = 0; i < 2; ++i) c11[i] = c10[i] + c01[i] - c00[i];
  }
  for (int i = 0; i < 2; ++i) {
    c00_[i] = c00[i];
    eu_[i] = c10[i] - c00[i];
    ev_[i] = c01[i] - c00[i];
    twist_[i] = c11[i] - c10[i] - c01[i] + c00[i];
  }
}

void SubdivFace::Evaluate(double u, double v, DerivOrder order, SurfaceDerivs* out) const {
  const double uv[2] = {c00_[0] + eu_[0] * u + ev_[0] * v + twist_[0] * u * v,
                        c00_[1] + eu_[1] * u + ev_[1] * v + twist_[1] * u * v};
  const osd::Bfr::Surface<double>::PointDescriptor desc(3);
  double p[3], du[3], dv[3], duu[3], duv[3], dvv[3];
  const double* pts = face_->patchPoints.data();
  if (Wants(order, DerivOrder::Second)) face_->surface.Evaluate(uv, pts, desc, p, du, dv, duu, duv, dvv);
  else if (Wants(order, DerivOrder::First)) face_->surface.Evaluate(uv, pts, desc, p, du, dv);
  else face_->surface.Evaluate(uv, pts, desc, p);
  out->p = Vec3(p[0], p[1], p[2]);
  if (!Wants(order, DerivOrder::First)) return;
  const Vec3 Du(du[0], du[1], du[2]), Dv(dv[0], dv[1], dv[2]);
  // The chain rule through the map (u, v) -> (U, V): its Jacobian columns are
  // dU/du = eu + twist v and dU/dv = ev + twist u; its only second derivative is
  // d2U/dudv = twist.
  const double a00 = eu_[0] + twist_[0] * v, a10 = eu_[1] + twist_[1] * v;  // d(U, V)/du
  const double a01 = ev_[0] + twist_[0] * u, a11 = ev_[1] + twist_[1] * u;  // d(U, V)/dv
  out->dpdu = a00 * Du + a10 * Dv;
  out->dpdv = a01 * Du + a11 * Dv;
  if (!Wants(order, DerivOrder::Second)) return;
  const Vec3 Duu(duu[0], duu[1], duu[2]), Duv(duv[0], duv[1], duv[2]), Dvv(dvv[0], dvv[1], dvv[2]);
  out->d2pdu2 = a00 * a00 * Duu + 2.0 * a00 * a10 * Duv + a10 * a10 * Dvv;
  out->d2pduv = a00 * a01 * Duu + (a00 * a11 + a10 * a01) * Duv + a10 * a11 * Dvv + twist_[0] * Du + twist_[1] * Dv;
  out->d2pdv2 = a01 * a01 * Duu + 2.0 * a01 * a11 * Duv + a11 * a11 * Dvv;
}

std::span<const Vec3> SubdivFace::Hull() const { return face_->hull; }

int SubdivFace::Face() const { return face_->face; }

bool SubdivFace::Regular() const { return face_->surface.IsRegular(); }

const SubdivMesh& SubdivFace::Cage() const { return *face_->cage; }

std::string SubdivFace::Describe() const {
  std::string s = "subdivision face " + std::to_string(face_->face);
  if (subFace_ >= 0) s += " (sub-face " + std::to_string(subFace_) + " of " + std::to_string(face_->surface.GetFaceSize()) + ")";
  s += face_->surface.IsRegular() ? ", regular" : ", irregular";
  return s;
}

std::vector<SubdivFace> PrepareSubdivFaces(const SubdivMesh& mesh, SubdivCounts* counts) {
  using osd::Far::Index;
  const int nPoints = static_cast<int>(mesh.points.size());
  // Step 1: what OpenSubdiv cannot be trusted to refuse cleanly, refused here.
  std::size_t total = 0;
  for (std::size_t f = 0; f < mesh.faceSizes.size(); ++f) {
    if (mesh.faceSizes[f] < 3)
      throw std::invalid_argument("face " + std::to_string(f) + " has " + std::to_string(mesh.faceSizes[f]) +
                                  " vertices (at least 3)");
    total += static_cast<std::size_t>(mesh.faceSizes[f]);
  }
  if (total != mesh.faceVertices.size())
    throw std::invalid_argument("the faces' sizes add up to " + std::to_string(total) + " vertices, but " +
                                std::to_string(mesh.faceVertices.size()) + " vertex indices are given");
  auto checkVertex = [&](int v, const std::string& what) {
    if (v < 0 || v >= nPoints)
      throw std::invalid_argument(what + " index " + std::to_string(v) + " is out of range (" +
                                  std::to_string(nPoints) + " points)");
  };
  for (int v : mesh.faceVertices) checkVertex(v, "vertex");
  std::size_t start = 0;
  for (std::size_t f = 0; f < mesh.faceSizes.size(); ++f) {
    const int n = mesh.faceSizes[f];
    for (int i = 0; i < n; ++i)
      for (int j = i + 1; j < n; ++j)
        if (mesh.faceVertices[start + static_cast<std::size_t>(i)] == mesh.faceVertices[start + static_cast<std::size_t>(j)])
          throw std::invalid_argument("face " + std::to_string(f) + " uses vertex " +
                                      std::to_string(mesh.faceVertices[start + static_cast<std::size_t>(i)]) + " twice");
    if (mesh.scheme == SubdivScheme::Loop && n != 3)
      throw std::invalid_argument("face " + std::to_string(f) + " has " + std::to_string(n) +
                                  " vertices: a Loop cage is of triangles");
    start += static_cast<std::size_t>(n);
  }
  std::vector<Index> creasePairs;
  std::vector<float> creaseWeights;
  for (const SubdivMesh::Crease& c : mesh.creases)
    for (std::size_t k = 0; k + 1 < c.chain.size(); ++k) {
      checkVertex(c.chain[k], "crease vertex");
      checkVertex(c.chain[k + 1], "crease vertex");
      creasePairs.push_back(c.chain[k]);
      creasePairs.push_back(c.chain[k + 1]);
      creaseWeights.push_back(static_cast<float>(c.sharpness));
    }
  std::vector<Index> cornerVertices;
  std::vector<float> cornerWeights;
  for (const auto& [v, sharpness] : mesh.corners) {
    checkVertex(v, "corner vertex");
    cornerVertices.push_back(v);
    cornerWeights.push_back(static_cast<float>(sharpness));
  }
  for (int h : mesh.holes)
    if (h < 0 || h >= static_cast<int>(mesh.faceSizes.size()))
      throw std::invalid_argument("hole face " + std::to_string(h) + " is out of range (" +
                                  std::to_string(mesh.faceSizes.size()) + " faces)");

  // Step 2: the topology, with RenderMan's boundary rule.
  osd::Far::TopologyDescriptor desc;
  desc.numVertices = nPoints;
  desc.numFaces = static_cast<int>(mesh.faceSizes.size());
  desc.numVertsPerFace = mesh.faceSizes.data();
  desc.vertIndicesPerFace = mesh.faceVertices.data();
  desc.numCreases = static_cast<int>(creaseWeights.size());
  desc.creaseVertexIndexPairs = creasePairs.data();
  desc.creaseWeights = creaseWeights.data();
  desc.numCorners = static_cast<int>(cornerWeights.size());
  desc.cornerVertexIndices = cornerVertices.data();
  desc.cornerWeights = cornerWeights.data();
  desc.numHoles = static_cast<int>(mesh.holes.size());
  desc.holeIndices = mesh.holes.data();
  osd::Sdc::Options sdc;
  sdc.SetVtxBoundaryInterpolation(mesh.interpolateBoundary == 1   ? osd::Sdc::Options::VTX_BOUNDARY_EDGE_AND_CORNER
                                  : mesh.interpolateBoundary == 2 ? osd::Sdc::Options::VTX_BOUNDARY_EDGE_ONLY
                                                                  : osd::Sdc::Options::VTX_BOUNDARY_NONE);
  using RefinerFactory = osd::Far::TopologyRefinerFactory<osd::Far::TopologyDescriptor>;
  const osd::Sdc::SchemeType scheme = mesh.scheme == SubdivScheme::Loop       ? osd::Sdc::SCHEME_LOOP
                                      : mesh.scheme == SubdivScheme::Bilinear ? osd::Sdc::SCHEME_BILINEAR
                                                                              : osd::Sdc::SCHEME_CATMARK;
  std::unique_ptr<osd::Far::TopologyRefiner> refiner(RefinerFactory::Create(desc, RefinerFactory::Options(scheme, sdc)));
  if (!refiner) throw std::invalid_argument("OpenSubdiv cannot build the cage's topology");

  // Step 3: one Bfr surface per rendered face, its patch points prepared once.
  const osd::Bfr::RefinerSurfaceFactory<> factory(*refiner);
  const osd::Far::TopologyLevel& level = refiner->GetLevel(0);
  SubdivCounts c;
  c.faces = level.GetNumFaces();
  c.vertices = level.GetNumVertices();
  c.holes = static_cast<int>(mesh.holes.size());
  c.creaseEdges = static_cast<int>(creaseWeights.size());
  c.corners = static_cast<int>(cornerWeights.size());
  for (Index v = 0; v < level.GetNumVertices(); ++v)
    if (!level.IsVertexValenceRegular(v)) ++c.extraordinaryVertices;
  std::vector<double> meshPoints;
  meshPoints.reserve(mesh.points.size() * 3);
  for (const Vec3& p : mesh.points) meshPoints.insert(meshPoints.end(), {p.x(), p.y(), p.z()});
  const osd::Bfr::Surface<double>::PointDescriptor pointDesc(3);
  std::vector<SubdivFace> faces;
  const auto cage = std::make_shared<const SubdivMesh>(mesh);
  for (Index f = 0; f < level.GetNumFaces(); ++f) {
    auto prepared = std::make_shared<SubdivFace::Prepared>();
    prepared->cage = cage;
    prepared->face = f;
    if (!factory.InitVertexSurface(f, &prepared->surface)) continue;  // a hole, or a dropped boundary face
    if (!prepared->surface.IsRegular()) ++c.irregularFaces;
    prepared->patchPoints.resize(static_cast<std::size_t>(prepared->surface.GetNumPatchPoints()) * 3);
    prepared->surface.PreparePatchPoints(meshPoints.data(), pointDesc, prepared->patchPoints.data(), pointDesc);
    for (std::size_t k = 0; k + 2 < prepared->patchPoints.size(); k += 3)
      prepared->hull.emplace_back(prepared->patchPoints[k], prepared->patchPoints[k + 1], prepared->patchPoints[k + 2]);
    const int n = prepared->surface.GetFaceSize();
    std::shared_ptr<const SubdivFace::Prepared> shared = std::move(prepared);
    const osd::Bfr::Parameterization param = shared->surface.GetParameterization();
    if (param.HasSubFaces() || param.GetType() == osd::Bfr::Parameterization::TRI) {
      for (int k = 0; k < n; ++k) faces.emplace_back(shared, k);
    } else {
      faces.emplace_back(shared, -1);
    }
  }
  c.surfaces = static_cast<int>(faces.size());
  if (counts) *counts = c;
  return faces;
}

}  // namespace patchscan
