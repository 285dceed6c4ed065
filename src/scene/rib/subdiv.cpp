// RenderMan's SubdivisionMesh (RenderMan Interface 3.2, "Subdivision Surfaces"): the cage, its tags
// (creases, corners, holes, interpolateboundary, facevaryinginterpolateboundary) and its "st".
#include <climits>
#include <cmath>
#include <string>
#include <vector>

#include "scene/rib/parser.h"
#include "scene/text_file.h"

namespace patchscan::rib {

bool RibParser::SubdivTags(const Value& tags, const Value& nargs, const Value& ints,
                           const Value& floats, SubdivMesh* mesh) {
  const std::size_t nTags = tags.Textual() ? tags.strings.size() : 0;
  if (!tags.Textual() && tags.Size() != 0) return Fail(tags.line, "SubdivisionMesh: the tags are an array of strings");
  if (!nargs.Numeric() || nargs.numbers.size() != 2 * nTags)
    return Fail(nargs.line, "SubdivisionMesh: nargs expects 2 numbers per tag (" + std::to_string(2 * nTags) + "), found " +
                                std::to_string(nargs.Size()));
  if (!ints.Numeric() && ints.Size() != 0) return Fail(ints.line, "SubdivisionMesh: intargs are numbers");
  if (!floats.Numeric() && floats.Size() != 0) return Fail(floats.line, "SubdivisionMesh: floatargs are numbers");
  std::size_t ni = 0, nf = 0;
  for (std::size_t t = 0; t < nTags; ++t) {
    const auto nInt = WholeIn(nargs.numbers[2 * t], 0, 100'000'000), nFloat = WholeIn(nargs.numbers[2 * t + 1], 0, 100'000'000);
    if (!nInt || !nFloat) return Fail(nargs.line, "SubdivisionMesh: nargs are whole numbers");
    if (ni + static_cast<std::size_t>(*nInt) > ints.Size() || nf + static_cast<std::size_t>(*nFloat) > floats.Size())
      return Fail(nargs.line, "SubdivisionMesh: tag " + Shown(tags.strings[t]) + " asks for more arguments than intargs and floatargs hold");
    std::vector<int> iv;
    for (int k = 0; k < *nInt; ++k) {
      const auto i = WholeIn(ints.numbers[ni + static_cast<std::size_t>(k)], INT_MIN, INT_MAX);
      if (!i) return Fail(ints.line, "SubdivisionMesh: intargs are whole numbers");
      iv.push_back(*i);
    }
    const std::vector<double> fv(floats.numbers.begin() + static_cast<std::ptrdiff_t>(nf),
                                 floats.numbers.begin() + static_cast<std::ptrdiff_t>(nf + static_cast<std::size_t>(*nFloat)));
    ni += static_cast<std::size_t>(*nInt);
    nf += static_cast<std::size_t>(*nFloat);
    const std::string& tag = tags.strings[t];
    if (tag == "crease") {
      if (iv.size() < 2 || fv.size() != 1) return Fail(tags.line, "SubdivisionMesh: \"crease\" takes a chain of 2 or more vertices and one sharpness");
      mesh->creases.push_back({iv, fv[0]});
    } else if (tag == "corner") {
      if (iv.empty() || (fv.size() != 1 && fv.size() != iv.size()))
        return Fail(tags.line, "SubdivisionMesh: \"corner\" takes vertices and one sharpness, or one per vertex");
      for (std::size_t k = 0; k < iv.size(); ++k) mesh->corners.emplace_back(iv[k], fv.size() == 1 ? fv[0] : fv[k]);
    } else if (tag == "hole") {
      mesh->holes.insert(mesh->holes.end(), iv.begin(), iv.end());
    } else if (tag == "interpolateboundary") {
      // No argument: on (edges and corners), as RenderMan 3.2 first defined it.
      if (iv.size() > 1 || (iv.size() == 1 && (iv[0] < 0 || iv[0] > 2)))
        return Fail(tags.line, "SubdivisionMesh: \"interpolateboundary\" takes nothing, or 0, 1 or 2");
      mesh->interpolateBoundary = iv.empty() ? 1 : iv[0];
    } else if (tag == "facevaryinginterpolateboundary") {
      // RenderMan's numbers: 0 bilinear on each face (the old rule), 1 smooth with the
      // corners of the texture map kept (the default), 2 smooth, 3 the map's boundaries linear.
      constexpr FaceVaryingRule kRule[] = {FaceVaryingRule::All, FaceVaryingRule::CornersOnly, FaceVaryingRule::Smooth,
                                           FaceVaryingRule::Boundaries};
      if (iv.size() > 1 || (iv.size() == 1 && (iv[0] < 0 || iv[0] > 3)))
        return Fail(tags.line, "SubdivisionMesh: \"facevaryinginterpolateboundary\" takes nothing, or 0, 1, 2 or 3");
      const bool propagate = mesh->faceVaryingRule == FaceVaryingRule::CornersPlus1;
      mesh->faceVaryingRule = kRule[iv.empty() ? 1 : iv[0]];
      if (propagate && mesh->faceVaryingRule == FaceVaryingRule::CornersOnly) mesh->faceVaryingRule = FaceVaryingRule::CornersPlus1;
    } else if (tag == "facevaryingpropagatecorners") {
      // 1: the corners kept where three or more regions of the map meet, too.
      if (iv.size() != 1 || (iv[0] != 0 && iv[0] != 1))
        return Fail(tags.line, "SubdivisionMesh: \"facevaryingpropagatecorners\" takes 0 or 1");
      if (iv[0] == 1 && mesh->faceVaryingRule == FaceVaryingRule::CornersOnly) mesh->faceVaryingRule = FaceVaryingRule::CornersPlus1;
    } else {
      Warn(tags.line, "SubdivisionMesh tag " + tag, "SubdivisionMesh: tag " + Shown(tag) + " is not supported here: ignored");
    }
  }
  return true;
}

bool RibParser::SubdivTextureCoords(const Request& r, std::size_t first, SubdivMesh* mesh) {
  std::vector<Param> params;
  if (!Params(r, first, &params)) return false;
  for (const Param& q : params) {
    if (q.name != "st") continue;
    if (!q.value->Numeric()) return Fail(q.value->line, "SubdivisionMesh: \"st\" expects numbers");
    mesh->st.clear();  // given twice: the last counts, as for any parameter
    mesh->stIndices.clear();
    const std::size_t size = q.value->numbers.size(), points = mesh->points.size(), corners = mesh->faceVertices.size();
    // The declared class, else by count: per point as RenderMan predeclares "st" (varying),
    // per corner face-varying.
    const std::string_view declared = DeclaredClass(q.declared);
    if (declared == "vertex" || declared == "varying" || (declared.empty() && size == 2 * points && size != 2 * corners)) {
      if (size != 2 * points)
        return Fail(q.value->line, "SubdivisionMesh: \"st\" expects 2 numbers per point (" + std::to_string(2 * points) +
                                       "), found " + std::to_string(size));
      mesh->stClass = declared == "vertex" ? StClass::Vertex : StClass::Varying;
      for (std::size_t k = 0; k < points; ++k) mesh->st.emplace_back(q.value->numbers[2 * k], q.value->numbers[2 * k + 1]);
    } else if (declared == "facevarying" || declared == "facevertex" || declared.empty()) {
      if (size != 2 * corners)
        return Fail(q.value->line, "SubdivisionMesh: \"st\" expects 2 numbers per face corner (" + std::to_string(2 * corners) +
                                       ")" + (declared.empty() ? " or per point (" + std::to_string(2 * points) + ")" : "") +
                                       ", found " + std::to_string(size));
      // The corners of one vertex with equal values share one (RenderMan gives no indices:
      // the texture map is cut only where the values differ).
      mesh->stClass = StClass::FaceVarying;
      std::map<std::tuple<int, double, double>, int> index;
      for (std::size_t k = 0; k < corners; ++k) {
        const Vec2 t(q.value->numbers[2 * k], q.value->numbers[2 * k + 1]);
        const auto [it, inserted] = index.try_emplace({mesh->faceVertices[k], t.x(), t.y()}, static_cast<int>(mesh->st.size()));
        if (inserted) mesh->st.push_back(t);
        mesh->stIndices.push_back(it->second);
      }
    } else {
      return Fail(q.value->line, "SubdivisionMesh: \"st\" is vertex, varying, facevarying or facevertex, not " + std::string(declared));
    }
    for (const Vec2& t : mesh->st)
      if (!t.allFinite()) return Fail(q.value->line, "SubdivisionMesh: \"st\" values must be finite");
  }
  return true;
}

bool RibParser::SubdivisionMesh(const Request& r) {
  // SubdivisionMesh scheme nvertices vertices [tags nargs intargs floatargs] parameterlist
  if (!InWorld(r)) return false;
  std::string scheme;
  if (!StringArg(r, 0, &scheme)) return false;
  SubdivMesh mesh;
  if (scheme == "catmull-clark") {
    mesh.scheme = SubdivScheme::CatmullClark;
  } else if (scheme == "loop") {
    mesh.scheme = SubdivScheme::Loop;
  } else if (scheme == "bilinear") {
    mesh.scheme = SubdivScheme::Bilinear;
  } else {
    Warn(r.line, "SubdivisionMesh " + scheme,
         "SubdivisionMesh: scheme " + Shown(scheme) +
             " is not supported here (\"catmull-clark\", \"loop\" and \"bilinear\" are): skipped");
    return true;
  }
  if (r.args.size() < 3 || !r.args[1].Numeric() || !r.args[2].Numeric())
    return Fail(r.line, "SubdivisionMesh expects scheme, nvertices and vertices (arrays of numbers)");
  for (const double n : r.args[1].numbers) {
    const auto k = WholeIn(n, 0, 1'000'000);
    if (!k) return Fail(r.args[1].line, "SubdivisionMesh: nvertices are whole numbers");
    mesh.faceSizes.push_back(*k);
  }
  int maxIndex = -1;
  for (const double v : r.args[2].numbers) {
    const auto k = WholeIn(v, 0, 100'000'000);
    if (!k) return Fail(r.args[2].line, "SubdivisionMesh: vertices are whole numbers from 0");
    mesh.faceVertices.push_back(*k);
    maxIndex = std::max(maxIndex, *k);
  }
  // The tags are there if an array (not a parameter name) follows.
  std::size_t first = 3;
  if (r.args.size() >= 7 && r.args[3].kind != Value::Kind::String) {
    if (!SubdivTags(r.args[3], r.args[4], r.args[5], r.args[6], &mesh)) return false;
    first = 7;
  }
  if (!Points(r, first, static_cast<std::size_t>(maxIndex + 1), false, 0, 0, {"st"})) return false;
  mesh.points = pts_;
  if (!SubdivTextureCoords(r, first, &mesh)) return false;
  std::vector<SubdivFace> faces;
  SceneCage cage{file_, r.line, mesh.scheme, {}};
  try {
    faces = PrepareSubdivFaces(mesh, &cage.counts);
  } catch (const std::invalid_argument& e) {
    return Fail(r.line, std::string("SubdivisionMesh: ") + e.what());
  }
  scene_.cages.push_back(cage);
  scene_.ReserveSurfaces(faces.size(), true);
  for (SubdivFace& f : faces) AddSurface(r, std::move(f));
  return true;
}

}  // namespace patchscan::rib
