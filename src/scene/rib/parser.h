// The RIB reader's parser (rib_reader.h): the graphics state and one member per request,
// fed by the tokenizer (rib_lexer.h). Its requests are defined by job: structure and the
// request table in rib_reader.cpp, camera, transformations and appearance in rib_state.cpp,
// geometry in rib_geometry.cpp. Private to the reader.
#pragma once

#include <cmath>
#include <map>
#include <numbers>
#include <optional>
#include <initializer_list>
#include <set>
#include <string>
#include <string_view>
#include <unordered_map>
#include <variant>
#include <vector>

#include "patch/basis.h"
#include "scene/rib/lexer.h"
#include "scene/scene.h"
#include "patch/trim.h"

namespace patchscan::rib {

constexpr double kRadPerDeg = std::numbers::pi / 180.0;
// ReadArchive nesting deeper than this is taken as an archive that reads itself.
constexpr int kMaxArchiveDepth = 16;
// ObjectInstance replays at most this many requests in all: objects instancing objects
// multiply, and ten of ten of ... sixteen deep would never end.
constexpr long kMaxReplayedRequests = 1'000'000;
// The largest count or index a polygon request may give: far beyond any scene, and small
// enough that sums of counts cannot overflow.
constexpr long kMaxPolygonCount = 1'000'000'000;
// RenderMan's default field of view (RenderMan Interface 3.2, "Projection").
constexpr double kRibDefaultFovDeg = 90.0;
// The light and shader parameter defaults of the standard shaders (RenderMan Interface
// 3.2, appendix A): a spotlight's cone half-angle 30 degrees and its soft edge 5 degrees.
constexpr double kSpotConeDeg = 30.0, kSpotDeltaDeg = 5.0;

// Column-vector matrices throughout: RIB writes row-vector matrices (p' = p M, the
// translation in elements 12..14), which are transposed on reading.
struct Attributes {
  Mat4 transform = Mat4::Identity();  // before WorldBegin: camera from current; after: world from object
  Appearance appearance;
  Basis uBasis = BezierBasis(), vBasis = BezierBasis();
  bool insideOrientation = false;  // Orientation "inside" / ReverseOrientation
  std::shared_ptr<const TrimLoops> trim;  // the current TrimCurve (null: none)
  bool trimKeepsInside = true;            // Attribute "trimcurve" "sense": "inside" keeps the loops' inside
};

struct Block {
  enum class Kind { Attribute, Transform, World, Frame };
  Kind kind;
  int line;
  std::string file;
  Attributes saved;
};

const char* BlockName(Block::Kind k);

// Requests read and skipped: the rest of the RenderMan Interface that does not change
// what a parametric surface looks like here.
const std::set<std::string, std::less<>>& SkippedRequests();
Mat4 Translation(double x, double y, double z);

// A whole number within [lo, hi], or nullopt.
inline std::optional<int> WholeIn(double x, int lo, int hi) {
  if (!(x == std::floor(x)) || x < lo || x > hi) return std::nullopt;
  return static_cast<int>(x);
}

// The storage class an inline declaration names ("constant", "uniform", "varying",
// "vertex", "facevarying" or "facevertex": its last such word), or "" when it names none.
inline std::string_view DeclaredClass(std::string_view declared) {
  std::string_view found;
  std::size_t at = 0;
  while (at < declared.size()) {
    const std::size_t end = std::min(declared.find_first_of(" \t\n\r", at), declared.size());
    const std::string_view word = declared.substr(at, end - at);
    for (const std::string_view c : {"constant", "uniform", "varying", "vertex", "facevarying", "facevertex"})
      if (word == c) found = word;
    at = end + 1;
  }
  return found;
}

class RibParser {
 public:
  RibParser(const LoadOptions& options) : options_(options) {}

  std::variant<Scene, SourceError> Run(std::string_view text, const std::string& name);

 private:
  // ---- errors and warnings ----
  bool Fail(int line, std::string message);
  void Warn(int line, const std::string& kind, const std::string& what);

  // ---- reading ----
  bool ReadText(std::string_view text, const std::string& name, int depth);

  // One request: frames, world and object blocks first (they decide what is read), then
  // the request table; skipped and unknown requests warn once per kind.
  bool Handle(const Request& r, int depth);
  using Handler = bool (RibParser::*)(const Request&);
  static const std::unordered_map<std::string_view, Handler>& RequestTable();

  // ---- argument checks ----
  bool Args(const Request& r, size_t count);
  // Exactly `count` leading numbers, given loose or as one array, into num_.
  bool Numbers(const Request& r, size_t count, size_t* used = nullptr);
  bool StringArg(const Request& r, size_t k, std::string* out);
  template <class F>
  bool MatrixArg(const Request& r, F&& then) {
    if (!Numbers(r, 16)) return false;
    Mat4 m;
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 4; ++j) m(j, i) = num_[4 * i + j];  // transposed: row vectors in RIB
    if (m.row(3) != Vec4(0, 0, 0, 1).transpose())
      return Fail(r.line, r.name + ": projective matrices are not supported (the last column must be 0 0 0 1)");
    return then(m);
  }
  bool ColourArg(const Request& r, Vec3* out);

  // The parameter list after the `first` positional arguments: "name" value pairs. The
  // name may carry an inline declaration ("uniform float Ka"): its last word counts.
  struct Param {
    std::string name;
    const Value* value;
    std::string declared;  // the name as written, with its inline declaration if any
  };
  bool Params(const Request& r, size_t first, std::vector<Param>* out);
  // A request of a name and a parameter list (Projection, Surface, Attribute).
  bool NameAndParams(const Request& r, std::string* name, std::vector<Param>* params) {
    return StringArg(r, 0, name) && Params(r, 1, params);
  }
  bool ParamNumbers(const Request& r, const Param& p, size_t count, double* out);
  bool ParamVec3(const Request& r, const Param& p, Vec3* out);
  bool ParamString(const Request& r, const Param& p, std::string* out);
  void IgnoreParam(const Request& r, const Param& p);

  // ---- structure ----
  bool FrameBegin(const Request& r);
  bool FrameEnd(const Request& r);
  bool ReadArchive(const Request& r, int depth);
  bool WorldBegin(const Request& r);
  bool Begin(const Request& r, Block::Kind kind);
  bool End(const Request& r, Block::Kind kind);
  // ObjectBegin handle ... ObjectEnd records the requests between (their file with them);
  // ObjectInstance handle replays them inside an attribute block of their own, under the
  // transformation and attributes current there (RenderMan Interface 3.2, "Retained
  // Geometry"). `depth` counts archives and instances within instances.
  bool ObjectBegin(const Request& r);
  bool ObjectEnd(const Request& r);
  bool Record(const Request& r, int depth);
  bool ObjectInstance(const Request& r, int depth);
  bool ObjectHandle(const Request& r, std::string* out);
  // body() in a scope of its own: the attributes restored after it, and the blocks it
  // opens closed by it (else an error naming `what`).
  template <class F>
  bool Scoped(const Request& r, const std::string& what, F&& body);
  bool Procedural(const Request& r, int depth);

  // ---- camera and image ----
  bool Format(const Request& r);
  bool Projection(const Request& r);
  bool ScreenWindow(const Request& r);
  bool CropWindow(const Request& r);
  bool Clipping(const Request& r);
  bool PixelSamples(const Request& r);
  bool Display(const Request& r);

  // ---- transformations ----
  bool SetTransform(const Request& r, const Mat4& m);
  bool Concat(const Request& r, const Mat4& m);
  bool CheckTransform(const Request& r);
  bool sawWorldOpen() const;
  bool Rotate(const Request& r);
  bool Orientation(const Request& r);
  bool Sides(const Request& r);
  bool Identity(const Request& r) { return Args(r, 0) && SetTransform(r, Mat4::Identity()); }
  bool TransformRequest(const Request& r) {
    return MatrixArg(r, [&](const Mat4& m) { return SetTransform(r, m); });
  }
  bool ConcatTransform(const Request& r) {
    return MatrixArg(r, [&](const Mat4& m) { return Concat(r, m); });
  }
  bool Translate(const Request& r) { return Numbers(r, 3) && Concat(r, Translation(num_[0], num_[1], num_[2])); }
  bool Scale(const Request& r) {
    return Numbers(r, 3) && Concat(r, Vec4(num_[0], num_[1], num_[2], 1).asDiagonal().toDenseMatrix());
  }
  bool ReverseOrientation(const Request& r) {
    if (!Args(r, 0)) return false;
    attr_.insideOrientation = !attr_.insideOrientation;
    return true;
  }
  bool Color(const Request& r) { return ColourArg(r, &attr_.appearance.colour); }
  bool Opacity(const Request& r) { return ColourArg(r, &attr_.appearance.opacity); }

  // ---- appearance ----
  bool SurfaceShader(const Request& r);
  bool DisplacementShader(const Request& r);
  bool LightSource(const Request& r);
  bool MakeTexture(const Request& r);  // MakeShadow, MakeLatLong- and MakeCubeFaceEnvironment
  // Hider "hidden" "depthfilter" and Option "shadow" "bias": how depth maps are written
  // and the bias of the shadow lights that give none.
  bool Hider(const Request& r);
  bool Option(const Request& r);

  // ---- geometry ----
  bool InWorld(const Request& r);
  void AddSurface(const Request& r, Shape shape, std::shared_ptr<const PieceTrim> trim = nullptr);
  // The index into the scene's appearances of the current appearance (added if new).
  std::uint32_t AppearanceIndex();
  static std::size_t HashOf(const Appearance& a);
  bool BasisRequest(const Request& r);
  // The "P" or "Pw" of a patch's parameter list: exactly `count` points into hpts_
  // (homogeneous, w = 1 for "P") and pts_ (divided by w); rational_ when a weight is not 1.
  // `rationalAllowed` false refuses "Pw". A patch or mesh of nu x nv points (nu > 0) may
  // give "Pz", a height field, instead.
  // "P" (or "Pw", "Pz") of `count` points into pts_ and hpts_; other parameters are ignored
  // with a warning, but for those named in readElsewhere.
  bool Points(const Request& r, size_t first, size_t count, bool rationalAllowed = true, int nu = 0, int nv = 0,
              std::initializer_list<std::string_view> readElsewhere = {});
  bool PatchType(const Request& r, bool* bicubic);
  bool Patch(const Request& r);
  // A patch given by "Pw" with a weight other than 1, as a rational Bézier NurbsPiece.
  void AddRationalPatch(const Request& r, std::vector<Vec4> cv, bool bicubic);
  // Patches along one direction of a mesh of n points: RenderMan Interface 3.2,
  // "PatchMesh": bicubic nonperiodic (n - 4) / step + 1, periodic n / step; bilinear
  // nonperiodic n - 1, periodic n.
  bool MeshCount(const Request& r, int n, bool periodic, bool bicubic, int step, const char* dir, int* count);
  bool PatchMesh(const Request& r);
  bool SubdivisionMesh(const Request& r);
  bool NuPatch(const Request& r);
  // TrimCurve ncurves order knot min max n u v w (RenderMan Interface 3.2): the loops that
  // trim the NuPatches that follow in the attribute block.
  bool TrimCurve(const Request& r);
  // Attribute "name" params: "trimcurve" "sense" is read, every other attribute skipped.
  bool AttributeRequest(const Request& r);
  // "st" of a SubdivisionMesh, by its class (declared, else by its count) into mesh.
  bool SubdivTextureCoords(const Request& r, std::size_t first, SubdivMesh* mesh);
  // SubdivisionMesh's tags (RenderMan Interface 3.2 and prman: crease, corner, hole,
  // interpolateboundary, facevaryinginterpolateboundary, facevaryingpropagatecorners) into
  // `mesh`; unknown tags are warned about and ignored.
  bool SubdivTags(const Value& tags, const Value& nargs, const Value& ints, const Value& floats,
                  SubdivMesh* mesh);
  // Polygon, GeneralPolygon, PointsPolygons, PointsGeneralPolygons (RenderMan Interface
  // 3.2, "Polygons"; rib_polygons.cpp): faces of loops of indices into "P", the first loop
  // the outline and the others holes, with "N", "Cs" and "st" of any storage class.
  bool Polygon(const Request& r);
  bool GeneralPolygon(const Request& r);
  bool PointsPolygons(const Request& r);
  bool PointsGeneralPolygons(const Request& r);
  struct PolygonFaces {
    std::vector<std::size_t> loopsOfFace;  // per face, its loops
    std::vector<std::size_t> pointsOfLoop;   // per loop, its points
    std::vector<std::uint32_t> indices;      // per corner, into "P"; empty: 0, 1, 2, ...
  };
  // The faces' parameter list from argument `first` on: points, primitive variables,
  // triangulation, appended to the scene as one ScenePolygons.
  bool AddPolygons(const Request& r, std::size_t first, const PolygonFaces& faces);
  // An array argument of whole numbers from `lo` to `hi`.
  bool Counts(const Request& r, std::size_t k, const char* what, long lo, long hi, std::vector<std::size_t>* out);
  // Curves type nvertices wrap (RenderMan Interface 3.2; rib_curves.cpp): each segment a
  // CurveRibbon in world space, in the current v basis and step.
  bool Curves(const Request& r);
  bool Quadric(const Request& r);
  bool Geometry(const Request& r);

  LoadOptions options_;
  Scene scene_;
  std::optional<SourceError> error_;
  std::string file_;
  Attributes attr_;
  std::vector<Block> blocks_;
  std::map<std::string, std::pair<std::size_t, long>, std::less<>> warned_;  // kind: its warning, how often
  std::vector<double> num_;
  std::vector<Vec3> pts_;
  std::vector<Vec4> hpts_;
  bool rational_ = false;
  std::unordered_map<std::size_t, std::vector<std::uint32_t>> appearanceIndex_;
  std::vector<std::uint32_t> polygonAppearance_;  // per ScenePolygons
  Mat4 cameraFromWorld_ = Mat4::Identity();
  double shadowBias_ = kDefaultShadowBias;  // Option "shadow" "bias"
  bool sawWorld_ = false, skippingWorld_ = false, skippingFrame_ = false, done_ = false;
  struct Recorded {
    std::string file;
    Request request;
  };
  std::unordered_map<std::string, std::vector<Recorded>> objects_;
  std::optional<std::pair<std::string, std::vector<Recorded>>> recording_;  // handle, requests so far
  int recordingLine_ = 0;
  long replayed_ = 0;  // requests replayed by ObjectInstance so far
  std::string recordingFile_;
};

}  // namespace patchscan::rib
