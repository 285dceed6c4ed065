#include "patch/subdiv_topology.h"

#include <opensubdiv/far/error.h>
#include <opensubdiv/far/topologyDescriptor.h>
#include <opensubdiv/far/topologyRefinerFactory.h>

#include <algorithm>
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <unordered_map>
#include <vector>

namespace patchscan {

namespace osd = OpenSubdiv;

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

}  // namespace

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

// Checks `mesh` and builds its OpenSubdiv topology, with RenderMan's boundary rule and the
// texture coordinates' channel. Throws std::invalid_argument (PrepareSubdivFaces).
std::unique_ptr<osd::Far::TopologyRefiner> BuildRefiner(const SubdivMesh& mesh) {
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

  // The texture coordinates: as many as their class asks, every index in range.
  if (!mesh.st.empty()) {
    if (mesh.stClass != StClass::FaceVarying && mesh.st.size() != mesh.points.size())
      throw std::invalid_argument("\"st\" has " + std::to_string(mesh.st.size()) + " values, one per point expected (" +
                                  std::to_string(mesh.points.size()) + ")");
    if (mesh.stClass == StClass::FaceVarying) {
      if (mesh.stIndices.size() != mesh.faceVertices.size())
        throw std::invalid_argument("\"st\" has " + std::to_string(mesh.stIndices.size()) + " indices, one per face corner expected (" +
                                    std::to_string(mesh.faceVertices.size()) + ")");
      for (const int k : mesh.stIndices)
        if (k < 0 || k >= static_cast<int>(mesh.st.size()))
          throw std::invalid_argument("\"st\" index " + std::to_string(k) + " is out of range (" + std::to_string(mesh.st.size()) +
                                      " values)");
    }
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
  // Face-varying "st": one channel, its values indexed per face corner.
  osd::Far::TopologyDescriptor::FVarChannel stChannel;
  if (!mesh.st.empty() && mesh.stClass == StClass::FaceVarying) {
    stChannel.numValues = static_cast<int>(mesh.st.size());
    stChannel.valueIndices = mesh.stIndices.data();
    desc.numFVarChannels = 1;
    desc.fvarChannels = &stChannel;
  }
  osd::Sdc::Options sdc;
  // FaceVaryingRule lists OpenSubdiv's rules in OpenSubdiv's order.
  sdc.SetFVarLinearInterpolation(static_cast<osd::Sdc::Options::FVarLinearInterpolation>(mesh.faceVaryingRule));
  sdc.SetVtxBoundaryInterpolation(mesh.interpolateBoundary == 1   ? osd::Sdc::Options::VTX_BOUNDARY_EDGE_AND_CORNER
                                  : mesh.interpolateBoundary == 2 ? osd::Sdc::Options::VTX_BOUNDARY_EDGE_ONLY
                                                                  : osd::Sdc::Options::VTX_BOUNDARY_NONE);
  using RefinerFactory = osd::Far::TopologyRefinerFactory<osd::Far::TopologyDescriptor>;
  const osd::Sdc::SchemeType scheme = mesh.scheme == SubdivScheme::Loop       ? osd::Sdc::SCHEME_LOOP
                                      : mesh.scheme == SubdivScheme::Bilinear ? osd::Sdc::SCHEME_BILINEAR
                                                                              : osd::Sdc::SCHEME_CATMARK;
  std::unique_ptr<osd::Far::TopologyRefiner> refiner(RefinerFactory::Create(desc, RefinerFactory::Options(scheme, sdc)));
  if (!refiner) throw std::invalid_argument("OpenSubdiv cannot build the cage's topology");
  return refiner;
}

// The control points of a Catmull-Clark quadrilateral whose limit surface is the uniform
// bicubic B-spline patch of its 16 neighbouring points (every vertex interior, of valence
// 4, smooth, and every face around them a quadrilateral that is not a hole), or nothing.
// The B-spline basis is non-negative, so the patch lies in the hull of these points: the
// face's box without preparing it.
std::optional<std::vector<int>> RegularNeighbourhood(const osd::Far::TopologyLevel& level, int face) {
  const auto fv = level.GetFaceVertices(face);
  if (fv.size() != 4) return std::nullopt;
  std::vector<int> ring;
  for (const int v : fv) {
    if (level.IsVertexBoundary(v) || level.IsVertexNonManifold(v) || level.GetVertexFaces(v).size() != 4 ||
        level.GetVertexSharpness(v) > 0.0f)
      return std::nullopt;
    for (const int e : level.GetVertexEdges(v))
      if (level.GetEdgeSharpness(e) > 0.0f) return std::nullopt;
    for (const int f : level.GetVertexFaces(v)) {
      if (level.IsFaceHole(f) || level.GetFaceVertices(f).size() != 4) return std::nullopt;
      for (const int w : level.GetFaceVertices(f)) ring.push_back(w);
    }
  }
  std::sort(ring.begin(), ring.end());
  ring.erase(std::unique(ring.begin(), ring.end()), ring.end());
  return ring;
}

// Whether base vertex v is an extraordinary point of the Catmull-Clark limit surface:
// interior, manifold, smooth (no sharpness at it or along its edges), of valence other than
// 4. Bfr's patches at it are irregular.
bool SmoothExtraordinary(const osd::Far::TopologyLevel& level, int v) {
  if (level.IsVertexBoundary(v) || level.IsVertexNonManifold(v) || level.GetVertexSharpness(v) > 0.0f ||
      level.GetVertexFaces(v).size() == 4)
    return false;
  for (const int e : level.GetVertexEdges(v))
    if (level.GetEdgeSharpness(e) > 0.0f) return false;
  return true;
}

}  // namespace patchscan
