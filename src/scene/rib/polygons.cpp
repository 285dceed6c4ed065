// The RIB polygon requests (RenderMan Interface 3.2, "Polygons"): Polygon, GeneralPolygon,
// PointsPolygons and PointsGeneralPolygons, with their primitive variables "N", "Cs" and
// "st" in any storage class, triangulated into the scene's polygon meshes.
#include <cmath>
#include <string>

#include "patch/polygon.h"
#include "scene/rib/parser.h"
#include "scene/text_file.h"

namespace patchscan::rib {
namespace {

// How a primitive variable is stored (RenderMan Interface 3.2, "Primitive Variables"): one
// value for the request, one per face, one per point ("vertex" and "varying": the same on
// polygons), or one per corner of a face ("facevarying", and prman's "facevertex").
enum class Storage { Constant, Uniform, Vertex, FaceVarying };

// The storage class an inline declaration names, if any.
std::optional<Storage> DeclaredStorage(std::string_view declared) {
  const std::string_view c = DeclaredClass(declared);
  if (c == "constant") return Storage::Constant;
  if (c == "uniform") return Storage::Uniform;
  if (c == "vertex" || c == "varying") return Storage::Vertex;
  if (c == "facevarying" || c == "facevertex") return Storage::FaceVarying;
  return std::nullopt;
}

// A primitive variable of `width` numbers per value, once its storage is known.
struct Primvar {
  const double* data = nullptr;
  Storage storage = Storage::Constant;
  int width = 0;
  const double* At(std::size_t face, std::size_t point, std::size_t corner) const {
    switch (storage) {
      case Storage::Constant: return data;
      case Storage::Uniform: return data + face * width;
      case Storage::Vertex: return data + point * width;
      case Storage::FaceVarying: return data + corner * width;
    }
    return data;
  }
};

}  // namespace

bool RibParser::Counts(const Request& r, std::size_t k, const char* what, long lo, long hi,
                       std::vector<std::size_t>* out) {
  if (k >= r.args.size() || !r.args[k].Numeric())
    return Fail(r.line, r.name + ": expected " + what + " (an array of whole numbers) as argument " + std::to_string(k + 1));
  out->clear();
  out->reserve(r.args[k].numbers.size());
  for (const double x : r.args[k].numbers) {
    if (!(x == std::floor(x) && x >= static_cast<double>(lo) && x <= static_cast<double>(hi)))
      return Fail(r.args[k].line, r.name + ": " + what + " are whole numbers from " + std::to_string(lo) + " to " +
                                      std::to_string(hi) + ", found " + Shown(std::to_string(x)));
    out->push_back(static_cast<std::size_t>(x));
  }
  return true;
}

bool RibParser::Polygon(const Request& r) {
  // Polygon paramlist: one face of one loop, its points in order.
  if (!InWorld(r)) return false;
  PolygonFaces faces;
  faces.loopsOfFace = {1};
  std::vector<Param> params;
  if (!Params(r, 0, &params)) return false;
  for (const Param& p : params)
    if ((p.name == "P" || p.name == "Pw") && p.value->Numeric())
      faces.pointsOfLoop = {p.value->numbers.size() / (p.name == "P" ? 3 : 4)};
  if (faces.pointsOfLoop.empty()) return Fail(r.line, r.name + ": no \"P\"");
  if (faces.pointsOfLoop[0] < 3) return Fail(r.line, r.name + ": a polygon has at least 3 points");
  return AddPolygons(r, 0, faces);
}

bool RibParser::GeneralPolygon(const Request& r) {
  // GeneralPolygon nvertices paramlist: one face whose loops have nvertices[i] points.
  if (!InWorld(r)) return false;
  PolygonFaces faces;
  if (!Counts(r, 0, "loop sizes", 3, kMaxPolygonCount, &faces.pointsOfLoop)) return false;
  if (faces.pointsOfLoop.empty()) return Fail(r.line, r.name + ": no loop");
  faces.loopsOfFace = {faces.pointsOfLoop.size()};
  return AddPolygons(r, 1, faces);
}

bool RibParser::PointsPolygons(const Request& r) {
  // PointsPolygons nvertices vertices paramlist: face i has nvertices[i] corners, each an
  // index into "P" from the vertices array.
  if (!InWorld(r)) return false;
  PolygonFaces faces;
  std::vector<std::size_t> indices;
  if (!Counts(r, 0, "face sizes", 3, kMaxPolygonCount, &faces.pointsOfLoop) ||
      !Counts(r, 1, "vertex indices", 0, kMaxPolygonCount, &indices))
    return false;
  faces.loopsOfFace.assign(faces.pointsOfLoop.size(), 1);
  faces.indices.assign(indices.begin(), indices.end());
  return AddPolygons(r, 2, faces);
}

bool RibParser::PointsGeneralPolygons(const Request& r) {
  // PointsGeneralPolygons nloops nvertices vertices paramlist.
  if (!InWorld(r)) return false;
  PolygonFaces faces;
  std::vector<std::size_t> indices;
  if (!Counts(r, 0, "loop counts", 1, kMaxPolygonCount, &faces.loopsOfFace) ||
      !Counts(r, 1, "loop sizes", 3, kMaxPolygonCount, &faces.pointsOfLoop) ||
      !Counts(r, 2, "vertex indices", 0, kMaxPolygonCount, &indices))
    return false;
  faces.indices.assign(indices.begin(), indices.end());
  return AddPolygons(r, 3, faces);
}

bool RibParser::AddPolygons(const Request& r, std::size_t first, const PolygonFaces& faces) {
  // The corners the counts describe, checked against each other before anything is used.
  std::size_t loops = 0, corners = 0;
  for (const std::size_t n : faces.loopsOfFace) {
    loops += n;
    if (loops > faces.pointsOfLoop.size())
      return Fail(r.line, r.name + ": the loop counts add up to more than the " +
                              std::to_string(faces.pointsOfLoop.size()) + " loop sizes given");
  }
  if (loops != faces.pointsOfLoop.size())
    return Fail(r.line, r.name + ": the loop counts add up to " + std::to_string(loops) + ", but " +
                            std::to_string(faces.pointsOfLoop.size()) + " loop sizes are given");
  for (const std::size_t n : faces.pointsOfLoop) corners += n;
  if (!faces.indices.empty() || first >= 2) {
    if (corners != faces.indices.size())
      return Fail(r.line, r.name + ": the loop sizes add up to " + std::to_string(corners) + ", but " +
                              std::to_string(faces.indices.size()) + " vertex indices are given");
  }
  std::size_t nPoints = corners;
  if (!faces.indices.empty()) {
    nPoints = 0;
    for (const std::uint32_t k : faces.indices) nPoints = std::max<std::size_t>(nPoints, k + 1);
  }

  std::vector<Param> params;
  if (!Params(r, first, &params)) return false;
  const Value* p = nullptr;
  const Value* pw = nullptr;
  struct Wanted {
    const char* name;
    int width;
    Primvar var;
  } wanted[] = {{"N", 3, {}}, {"Cs", 3, {}}, {"st", 2, {}}};
  const std::size_t nFaces = faces.loopsOfFace.size();
  for (const Param& q : params) {
    if (q.name == "P") {
      p = q.value;
      continue;
    }
    if (q.name == "Pw") {
      pw = q.value;
      continue;
    }
    Wanted* w = nullptr;
    for (Wanted& c : wanted)
      if (q.name == c.name) w = &c;
    if (!w) {
      IgnoreParam(r, q);
      continue;
    }
    if (!q.value->Numeric()) return Fail(q.value->line, r.name + ": \"" + q.name + "\" expects numbers");
    const std::size_t size = q.value->numbers.size();
    const std::size_t width = static_cast<std::size_t>(w->width);
    // The declared class, else the first whose count fits: per point, per corner, per
    // face, one value.
    const std::pair<Storage, std::size_t> classes[] = {{Storage::Vertex, nPoints},
                                                       {Storage::FaceVarying, corners},
                                                       {Storage::Uniform, nFaces},
                                                       {Storage::Constant, 1}};
    const auto declared = DeclaredStorage(q.declared);
    bool fits = false;
    for (const auto& [storage, count] : classes) {
      if ((declared && storage != *declared) || size != width * count) continue;
      w->var = Primvar{q.value->numbers.data(), storage, w->width};
      fits = true;
      break;
    }
    if (!fits)
      return Fail(q.value->line, r.name + ": \"" + q.name + "\" expects " + std::to_string(width) + " numbers per point (" +
                                     std::to_string(width * nPoints) + "), per corner (" + std::to_string(width * corners) +
                                     "), per face (" + std::to_string(width * nFaces) + ") or " + std::to_string(width) +
                                     " in all, found " + std::to_string(size));
  }
  if (p && pw) return Fail(pw->line, r.name + ": both \"P\" and \"Pw\": give one");
  if (!p && !pw) return Fail(r.line, r.name + ": no \"P\"");
  const Value* given = p ? p : pw;
  const std::size_t dims = p ? 3 : 4;
  if (!given->Numeric() || given->numbers.size() != dims * nPoints)
    return Fail(given->line, r.name + (p ? ": \"P\" expects " : ": \"Pw\" expects ") + std::to_string(dims * nPoints) +
                                 " numbers (" + std::to_string(nPoints) + " points), found " + std::to_string(given->Size()));
  std::vector<Vec3> world(nPoints);
  for (std::size_t k = 0; k < nPoints; ++k) {
    const double* x = given->numbers.data() + dims * k;
    const double w = p ? 1.0 : x[3];
    if (!(w > 0.0)) return Fail(given->line, r.name + ": \"Pw\" weights must be positive");
    world[k] = (attr_.transform * Vec4(x[0] / w, x[1] / w, x[2] / w, 1.0)).head<3>();
  }
  // Normals transform by the inverse transpose.
  const Mat3 normalFromObject = attr_.transform.block<3, 3>(0, 0).inverse().transpose();

  ScenePolygons polygons;
  polygons.file = file_;
  polygons.line = r.line;
  PolygonMesh& mesh = polygons.mesh;
  mesh.vertices.reserve(corners);
  std::vector<Vec3> facePoints;
  std::vector<std::vector<std::uint32_t>> faceLoops;
  std::vector<std::array<std::uint32_t, 3>> triangles;
  std::size_t loop = 0, corner = 0;
  for (std::size_t f = 0; f < nFaces; ++f) {
    // The face's corners as points of their own, its loops indexing them.
    facePoints.clear();
    faceLoops.assign(faces.loopsOfFace[f], {});
    const std::size_t firstCorner = corner;
    for (auto& l : faceLoops) {
      for (std::size_t k = 0; k < faces.pointsOfLoop[loop]; ++k, ++corner) {
        l.push_back(static_cast<std::uint32_t>(facePoints.size()));
        facePoints.push_back(world[faces.indices.empty() ? corner : faces.indices[corner]]);
      }
      ++loop;
    }
    triangles.clear();
    TriangulatePolygon(facePoints, faceLoops, &triangles);
    if (triangles.empty()) continue;  // a face without area shows nothing
    const Vec3 faceNormal = NewellNormal(facePoints, faceLoops[0]).normalized();
    const auto base = static_cast<std::uint32_t>(mesh.vertices.size());
    for (std::size_t c = firstCorner; c < corner; ++c) {
      const std::size_t point = faces.indices.empty() ? c : faces.indices[c];
      PolygonVertex v;
      v.position = world[point];
      v.normal = faceNormal;
      if (wanted[0].var.data) {
        const double* n = wanted[0].var.At(f, point, c);
        const Vec3 given = (normalFromObject * Vec3(n[0], n[1], n[2])).normalized();
        if (given.allFinite()) v.normal = given;
      }
      if (wanted[1].var.data) {
        const double* cs = wanted[1].var.At(f, point, c);
        v.colour = Vec3(cs[0], cs[1], cs[2]);
      }
      if (wanted[2].var.data) {
        const double* st = wanted[2].var.At(f, point, c);
        v.st = Vec2(st[0], st[1]);
      }
      mesh.vertices.push_back(v);
    }
    for (const auto& t : triangles) mesh.triangles.push_back({base + t[0], base + t[1], base + t[2]});
  }
  if (mesh.triangles.empty()) return true;
  polygonAppearance_.push_back(AppearanceIndex());
  scene_.polygons.push_back(std::move(polygons));
  return true;
}

}  // namespace patchscan::rib
