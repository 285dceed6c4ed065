#include "patch/subdiv.h"

#include <opensubdiv/bfr/refinerSurfaceFactory.h>
#include <opensubdiv/bfr/surface.h>
#include <opensubdiv/far/error.h>
#include <opensubdiv/far/topologyDescriptor.h>
#include <opensubdiv/far/topologyRefinerFactory.h>

#include <cstdint>
#include <stdexcept>
#include <unordered_map>

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

namespace {

// The cage's edges, each once, with the faces that use it. Refuses what OpenSubdiv's Bfr
// cannot be trusted with (a fuzzed cage crashed it inside IrregularPatchBuilder): an edge of
// three or more faces, two faces running an edge the same way (their orientations disagree),
// and a vertex where separate fans of faces meet (a bowtie).
void CheckManifold(const SubdivMesh& mesh, std::unordered_map<std::uint64_t, int>* edgeUses) {
  struct Use {
    int count = 0, face = -1;
    bool forward = false;  // the first face runs it from the smaller vertex
  };
  std::unordered_map<std::uint64_t, Use> edges;
  auto key = [](int a, int b) {
    return (static_cast<std::uint64_t>(std::min(a, b)) << 32) | static_cast<std::uint32_t>(std::max(a, b));
  };
  // The corners at each vertex: (face, the vertex before, the vertex after).
  struct Corner {
    int face, prev, next;
  };
  std::vector<std::vector<Corner>> corners(mesh.points.size());
  std::size_t start = 0;
  for (std::size_t f = 0; f < mesh.faceSizes.size(); ++f) {
    const int n = mesh.faceSizes[f];
    for (int k = 0; k < n; ++k) {
      const int a = mesh.faceVertices[start + static_cast<std::size_t>(k)];
      const int b = mesh.faceVertices[start + static_cast<std::size_t>((k + 1) % n)];
      const int before = mesh.faceVertices[start + static_cast<std::size_t>((k + n - 1) % n)];
      corners[static_cast<std::size_t>(a)].push_back({static_cast<int>(f), before, b});
      Use& u = edges[key(a, b)];
      const std::string edge = "the edge between vertices " + std::to_string(a) + " and " + std::to_string(b);
      if (u.count >= 2)
        throw std::invalid_argument(edge + " is used by 3 or more faces (a non-manifold edge)");
      if (u.count == 1 && u.forward == (a < b))
        throw std::invalid_argument("faces " + std::to_string(u.face) + " and " + std::to_string(f) + " both run " + edge +
                                    " the same way (their orientations disagree)");
      if (u.count == 0) {
        u.face = static_cast<int>(f);
        u.forward = a < b;
      }
      ++u.count;
    }
    start += static_cast<std::size_t>(n);
  }
  // A vertex's corners form one fan: linked where one face's edge out of it is the next
  // face's edge into it.
  std::vector<int> parent;
  for (std::size_t v = 0; v < corners.size(); ++v) {
    const auto& c = corners[v];
    parent.resize(c.size());
    for (std::size_t i = 0; i < c.size(); ++i) parent[i] = static_cast<int>(i);
    auto root = [&](int i) {
      while (parent[static_cast<std::size_t>(i)] != i) i = parent[static_cast<std::size_t>(i)];
      return i;
    };
    std::size_t fans = c.size();
    for (std::size_t i = 0; i < c.size(); ++i)
      for (std::size_t j = 0; j < c.size(); ++j)
        if (i != j && c[i].next == c[j].prev) {
          const int ri = root(static_cast<int>(i)), rj = root(static_cast<int>(j));
          if (ri != rj) {
            parent[static_cast<std::size_t>(ri)] = rj;
            --fans;
          }
        }
    if (fans > 1)
      throw std::invalid_argument("vertex " + std::to_string(v) + " joins " + std::to_string(fans) +
                                  " separate fans of faces (a non-manifold vertex)");
  }
  edgeUses->clear();
  for (const auto& [k, u] : edges) (*edgeUses)[k] = u.count;
}

// OpenSubdiv reports through printf by default; the cage is checked before it is given
// to OpenSubdiv, so what it would still say is not for the user's terminal.
void QuietOpenSubdiv() {
  static const bool once = [] {
    osd::Far::SetErrorCallback([](osd::Far::ErrorType, const char*) {});
    osd::Far::SetWarningCallback([](const char*) {});
    return true;
  }();
  (void)once;
}

}  // namespace

std::vector<SubdivFace> PrepareSubdivFaces(const SubdivMesh& mesh, SubdivCounts* counts) {
  QuietOpenSubdiv();
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
  std::unordered_map<std::uint64_t, int> edgeUses;
  CheckManifold(mesh, &edgeUses);
  for (std::size_t k = 0; k + 1 < creasePairs.size(); k += 2) {
    const int a = creasePairs[k], b = creasePairs[k + 1];
    const std::uint64_t key = (static_cast<std::uint64_t>(std::min(a, b)) << 32) | static_cast<std::uint32_t>(std::max(a, b));
    if (a == b || !edgeUses.contains(key))
      throw std::invalid_argument("crease: vertices " + std::to_string(a) + " and " + std::to_string(b) +
                                  " are not the ends of an edge of the cage");
  }
  // An interior vertex of valence 2 folds the control hull over on itself. OpenSubdiv 3.5's
  // Bfr builds the irregular patches around one from uninitialised indices when the cage also
  // has creases (valgrind and a fuzzed crash inside IrregularPatchBuilder agree; without
  // creases it is clean), so a cage is refused the combination rather than evaluated wrongly.
  if (!creasePairs.empty()) {
    std::vector<int> valence(mesh.points.size(), 0);
    std::vector<bool> boundary(mesh.points.size(), false);
    for (const auto& [k, uses] : edgeUses)
      for (const int v : {static_cast<int>(k >> 32), static_cast<int>(k & 0xffffffffu)}) {
        ++valence[static_cast<std::size_t>(v)];
        if (uses == 1) boundary[static_cast<std::size_t>(v)] = true;
      }
    for (std::size_t v = 0; v < valence.size(); ++v)
      if (valence[v] == 2 && !boundary[v])
        throw std::invalid_argument("vertex " + std::to_string(v) +
                                    " is an interior vertex of valence 2, and OpenSubdiv 3.5 cannot evaluate a cage "
                                    "that has one together with creases: remove the creases or the vertex");
  }

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
