#include "patch/rib_reader.h"

#include <Eigen/Geometry>
#include <array>
#include <cmath>
#include <filesystem>
#include <numbers>
#include <optional>
#include <set>
#include <unordered_map>
#include <vector>

#include "patch/bpt_reader.h"
#include "patch/camera.h"
#include "patch/text_file.h"

namespace patchscan {
namespace {

constexpr double kRadPerDeg = std::numbers::pi / 180.0;
// ReadArchive nesting deeper than this is taken as an archive that reads itself.
constexpr int kMaxArchiveDepth = 16;
// RenderMan's default field of view (RenderMan Interface 3.2, "Projection").
constexpr double kRibDefaultFovDeg = 90.0;
// The light and shader parameter defaults of the standard shaders (RenderMan Interface
// 3.2, appendix A): a spotlight's cone half-angle 30 degrees and its soft edge 5 degrees.
constexpr double kSpotConeDeg = 30.0, kSpotDeltaDeg = 5.0;

// ---- lexing ----

// One argument of a request: a number, a string, or an array of either.
struct Value {
  enum class Kind { Number, String, Numbers, Strings };
  Kind kind = Kind::Number;
  std::vector<double> numbers;       // Number: one element
  std::vector<std::string> strings;  // String: one element
  int line = 0;

  bool Numeric() const { return kind == Kind::Number || kind == Kind::Numbers; }
  bool Textual() const { return kind == Kind::String || kind == Kind::Strings; }
  size_t Size() const { return Numeric() ? numbers.size() : strings.size(); }
};

struct Request {
  std::string name;
  int line = 0;
  std::vector<Value> args;
};

bool IsSpace(char c) {
  return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\f' || c == '\v';
}
bool IsLetter(char c) { return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z'); }
bool IsNumberChar(char c) {
  return (c >= '0' && c <= '9') || c == '-' || c == '+' || c == '.' || c == 'e' || c == 'E';
}

// Splits RIB text into requests, one at a time. On malformed text Next returns false and
// Error() says why.
class Lexer {
 public:
  Lexer(std::string_view text, const std::string& file) : text_(text), file_(file) {}

  // The next request; false at the end of the text or on an error (then Error() is set).
  bool Next(Request* r) {
    r->args.clear();
    SkipSpace();
    if (i_ >= text_.size()) return false;
    if (!IsLetter(text_[i_])) return Fail(line_, "expected a request name, found " + Shown(Word()));
    r->line = line_;
    r->name = std::string(Identifier());
    for (;;) {
      SkipSpace();
      if (i_ >= text_.size() || IsLetter(text_[i_])) return true;
      Value v;
      if (!ReadValue(&v)) return false;
      r->args.push_back(std::move(v));
    }
  }
  const std::optional<SourceError>& Error() const { return error_; }

 private:
  bool Fail(int line, std::string message) {
    error_ = SourceError{file_, line, std::move(message)};
    return false;
  }
  void SkipSpace() {
    while (i_ < text_.size()) {
      const char c = text_[i_];
      if (c == '\n') {
        ++line_;
        ++i_;
      } else if (IsSpace(c)) {
        ++i_;
      } else if (c == '#') {
        while (i_ < text_.size() && text_[i_] != '\n') ++i_;
      } else {
        return;
      }
    }
  }
  // The run of non-space characters at i_, for messages.
  std::string_view Word() const {
    size_t j = i_;
    while (j < text_.size() && !IsSpace(text_[j])) ++j;
    return text_.substr(i_, j - i_);
  }
  std::string_view Identifier() {
    const size_t start = i_;
    while (i_ < text_.size() && (IsLetter(text_[i_]) || (text_[i_] >= '0' && text_[i_] <= '9') ||
                                 text_[i_] == '_'))
      ++i_;
    return text_.substr(start, i_ - start);
  }
  bool ReadNumber(double* out) {
    const size_t start = i_;
    while (i_ < text_.size() && IsNumberChar(text_[i_])) ++i_;
    const std::string_view t = text_.substr(start, i_ - start);
    const auto n = ParseNumber(t);
    // A number ends at a delimiter: space, a bracket, a quote or a comment.
    const bool delimited = i_ >= text_.size() || IsSpace(text_[i_]) || text_[i_] == '[' ||
                           text_[i_] == ']' || text_[i_] == '"' || text_[i_] == '#';
    if (!n || !delimited) {
      i_ = start;
      return Fail(line_, "expected a number, found " + Shown(Word()));
    }
    if (!n->finite) return Fail(line_, "number " + Shown(t) + " is not finite");
    *out = n->value;
    return true;
  }
  bool ReadString(std::string* out) {
    const int opened = line_;
    ++i_;  // the opening quote
    out->clear();
    while (i_ < text_.size() && text_[i_] != '"') {
      char c = text_[i_++];
      if (c == '\n') ++line_;
      if (c == '\\' && i_ < text_.size()) {
        c = text_[i_++];
        c = c == 'n' ? '\n' : c == 't' ? '\t' : c == 'r' ? '\r' : c;
      }
      out->push_back(c);
    }
    if (i_ >= text_.size()) return Fail(opened, "the string opened here is not closed");
    ++i_;  // the closing quote
    return true;
  }
  // One scalar (number or string) at i_ into v, which must be of `kind` if set.
  bool ReadScalar(Value* v, bool inArray) {
    const char c = text_[i_];
    if (static_cast<unsigned char>(c) >= 0x80)
      return Fail(line_, "binary RIB is not supported (a byte above 0x7f)");
    if (c == '"') {
      if (inArray && v->kind == Value::Kind::Numbers && !v->numbers.empty())
        return Fail(line_, "an array mixes numbers and strings");
      std::string s;
      if (!ReadString(&s)) return false;
      v->strings.push_back(std::move(s));
      if (inArray) v->kind = Value::Kind::Strings;
      return true;
    }
    if (IsNumberChar(c)) {
      if (inArray && v->kind == Value::Kind::Strings && !v->strings.empty())
        return Fail(line_, "an array mixes numbers and strings");
      double x = 0;
      if (!ReadNumber(&x)) return false;
      v->numbers.push_back(x);
      return true;
    }
    if (c == '[') return Fail(line_, "arrays do not nest");
    return Fail(line_, "unexpected " + Shown(Word()));
  }
  bool ReadValue(Value* v) {
    v->line = line_;
    if (text_[i_] == ']') return Fail(line_, "']' without '['");
    if (text_[i_] != '[') {
      if (!ReadScalar(v, false)) return false;
      v->kind = v->strings.empty() ? Value::Kind::Number : Value::Kind::String;
      return true;
    }
    const int opened = line_;
    ++i_;
    v->kind = Value::Kind::Numbers;
    for (;;) {
      SkipSpace();
      if (i_ >= text_.size()) return Fail(opened, "the array opened here is not closed");
      if (text_[i_] == ']') {
        ++i_;
        return true;
      }
      if (IsLetter(text_[i_])) return Fail(opened, "the array opened here is not closed before " + Shown(Word()));
      if (!ReadScalar(v, true)) return false;
    }
  }

  std::string_view text_;
  std::string file_;
  size_t i_ = 0;
  int line_ = 1;
  std::optional<SourceError> error_;
};

// ---- the graphics state ----

// Column-vector matrices throughout: RIB writes row-vector matrices (p' = p M, the
// translation in elements 12..14), which are transposed on reading.
struct Attributes {
  Mat4 transform = Mat4::Identity();  // before WorldBegin: camera from current; after: world from object
  Appearance appearance;
  Basis uBasis = BezierBasis(), vBasis = BezierBasis();
  bool insideOrientation = false;  // Orientation "inside" / ReverseOrientation
};

struct Block {
  enum class Kind { Attribute, Transform, World, Frame };
  Kind kind;
  int line;
  std::string file;
  Attributes saved;
};

const char* BlockName(Block::Kind k) {
  switch (k) {
    case Block::Kind::Attribute: return "AttributeBegin";
    case Block::Kind::Transform: return "TransformBegin";
    case Block::Kind::World: return "WorldBegin";
    case Block::Kind::Frame: return "FrameBegin";
  }
  return "";
}

// Requests read and skipped: the rest of the RenderMan Interface that does not change
// what a parametric surface looks like here.
const std::set<std::string, std::less<>>& SkippedRequests() {
  static const std::set<std::string, std::less<>> k = {
      "Option", "Attribute", "Hider", "Declare", "Displacement", "Atmosphere", "Interior",
      "Exterior", "Imager", "Exposure", "Quantize", "PixelFilter", "PixelVariance",
      "ShadingRate", "ShadingInterpolation", "Matte", "Bound", "Detail", "DetailRange",
      "GeometricApproximation", "MakeTexture", "MakeShadow", "MakeLatLongEnvironment",
      "MakeCubeFaceEnvironment", "MakeBump", "FrameAspectRatio", "CropWindow", "DepthOfField",
      "Shutter", "ColorSamples", "RelativeDetail", "TextureCoordinates", "Illuminate",
      "AreaLightSource", "CoordinateSystem", "CoordSysTransform", "ScopedCoordinateSystem",
      "Perspective", "Skew", "Deformation", "SolidBegin", "SolidEnd", "MotionBegin",
      "MotionEnd", "ObjectInstance", "Polygon", "GeneralPolygon", "PointsPolygons",
      "PointsGeneralPolygons", "NuPatch", "TrimCurve", "SubdivisionMesh",
      "HierarchicalSubdivisionMesh", "Points", "Curves", "Blobby", "Procedural", "Version",
      "ErrorHandler", "System", "IfBegin", "IfEnd", "Else", "ElseIf", "Resource",
      "ResourceBegin", "ResourceEnd", "Camera", "DisplayChannel", "ArchiveBegin", "ArchiveEnd",
      "Sphere2", "Attribute2", "Shader", "Pattern", "Bxdf", "Light", "Integrator",
      "Projection2", "VolumePixelSamples", "Volume", "PatchMesh2", "ClippingPlane"};
  return k;
}

Mat4 Translation(double x, double y, double z) {
  Mat4 m = Mat4::Identity();
  m.block<3, 1>(0, 3) = Vec3(x, y, z);
  return m;
}

class RibParser {
 public:
  RibParser(const LoadOptions& options) : options_(options) {}

  std::variant<Scene, SourceError> Run(std::string_view text, const std::string& name) {
    scene_.source = name;
    if (!ReadText(text, name, 0)) return *error_;
    if (!done_) {
      for (auto b = blocks_.rbegin(); b != blocks_.rend(); ++b)
        return SourceError{b->file, b->line, std::string(BlockName(b->kind)) + " is never closed"};
      if (options_.frame >= 0)
        return SourceError{name, 0, "no FrameBegin " + std::to_string(options_.frame) + " in the file"};
    }
    if (!sawWorld_) return SourceError{name, 0, "no WorldBegin: a RIB scene needs a world block"};
    return std::move(scene_);
  }

 private:
  // ---- errors and warnings ----
  bool Fail(int line, std::string message) {
    error_ = SourceError{file_, line, std::move(message)};
    return false;
  }
  void Warn(int line, const std::string& kind, const std::string& what) {
    if (!warned_.insert(kind).second) return;
    scene_.warnings.push_back(SourceError{file_, line, what}.What());
  }

  // ---- reading ----
  bool ReadText(std::string_view text, const std::string& name, int depth) {
    const std::string outerFile = file_;
    file_ = name;
    Lexer lexer(text, name);
    Request r;
    while (!done_ && lexer.Next(&r)) {
      if (!Handle(r, depth)) return false;
    }
    if (lexer.Error()) {
      error_ = lexer.Error();
      return false;
    }
    file_ = outerFile;
    return true;
  }

  bool Handle(const Request& r, int depth) {
    const std::string& n = r.name;
    // Frames: only the chosen one is read; requests outside frames apply to every frame.
    if (n == "FrameBegin") return FrameBegin(r);
    if (n == "FrameEnd") return FrameEnd(r);
    if (skippingFrame_) return true;
    if (n == "ReadArchive") return ReadArchive(r, depth);
    if (n == "WorldBegin") return WorldBegin(r);
    if (n == "WorldEnd") return End(r, Block::Kind::World);
    if (skippingWorld_) return true;
    if (n == "AttributeBegin") return Begin(r, Block::Kind::Attribute);
    if (n == "AttributeEnd") return End(r, Block::Kind::Attribute);
    if (n == "TransformBegin") return Begin(r, Block::Kind::Transform);
    if (n == "TransformEnd") return End(r, Block::Kind::Transform);
    if (n == "ObjectBegin") return Begin(r, Block::Kind::Attribute) && SkipObject(r);
    if (n == "ObjectEnd") return EndObject(r);
    if (objectDepth_ > 0) return true;
    // Camera and image.
    if (n == "Format") return Format(r);
    if (n == "Projection") return Projection(r);
    if (n == "ScreenWindow") return ScreenWindow(r);
    if (n == "Clipping") return Clipping(r);
    if (n == "PixelSamples") return PixelSamples(r);
    if (n == "Display") return Display(r);
    // Transformations.
    if (n == "Identity") return Args(r, 0) && SetTransform(r, Mat4::Identity());
    if (n == "Transform") return MatrixArg(r, [&](const Mat4& m) { return SetTransform(r, m); });
    if (n == "ConcatTransform") return MatrixArg(r, [&](const Mat4& m) { return Concat(r, m); });
    if (n == "Translate") return Numbers(r, 3) && Concat(r, Translation(num_[0], num_[1], num_[2]));
    if (n == "Scale") return Numbers(r, 3) && Concat(r, Vec4(num_[0], num_[1], num_[2], 1).asDiagonal().toDenseMatrix());
    if (n == "Rotate") return Rotate(r);
    if (n == "Orientation") return Orientation(r);
    if (n == "ReverseOrientation") {
      if (!Args(r, 0)) return false;
      attr_.insideOrientation = !attr_.insideOrientation;
      return true;
    }
    if (n == "Sides") return Sides(r);
    // Appearance.
    if (n == "Color") return ColourArg(r, &attr_.appearance.colour);
    if (n == "Opacity") return ColourArg(r, &attr_.appearance.opacity);
    if (n == "Surface") return SurfaceShader(r);
    if (n == "LightSource") return LightSource(r);
    // Geometry.
    if (n == "Basis") return BasisRequest(r);
    if (n == "Patch") return Patch(r);
    if (n == "PatchMesh") return PatchMesh(r);
    if (n == "Sphere" || n == "Cylinder" || n == "Cone" || n == "Paraboloid" ||
        n == "Hyperboloid" || n == "Disk" || n == "Torus")
      return Quadric(r);
    if (n == "Geometry") return Geometry(r);
    if (SkippedRequests().count(n) != 0) {
      Warn(r.line, n, n + " is not supported here: skipped");
      return true;
    }
    Warn(r.line, n, "unknown request " + Shown(n) + ": skipped");
    return true;
  }

  // ---- argument checks ----
  bool Args(const Request& r, size_t count) {
    if (r.args.size() < count)
      return Fail(r.line, r.name + " expects " + std::to_string(count) + " arguments, found " +
                              std::to_string(r.args.size()));
    return true;
  }
  // Exactly `count` leading numbers, given loose or as one array, into num_.
  bool Numbers(const Request& r, size_t count, size_t* used = nullptr) {
    num_.clear();
    size_t k = 0;
    if (!r.args.empty() && r.args[0].kind == Value::Kind::Numbers) {
      num_ = r.args[0].numbers;
      k = 1;
    } else {
      while (k < r.args.size() && r.args[k].kind == Value::Kind::Number && num_.size() < count)
        num_.push_back(r.args[k++].numbers[0]);
    }
    if (num_.size() != count)
      return Fail(r.line, r.name + " expects " + std::to_string(count) + " numbers, found " +
                              std::to_string(num_.size()));
    if (used) *used = k;
    return true;
  }
  bool StringArg(const Request& r, size_t k, std::string* out) {
    if (k >= r.args.size() || !r.args[k].Textual() || r.args[k].strings.size() != 1)
      return Fail(k < r.args.size() ? r.args[k].line : r.line,
                  r.name + " expects a string as argument " + std::to_string(k + 1));
    *out = r.args[k].strings[0];
    return true;
  }
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
  bool ColourArg(const Request& r, Vec3* out) {
    if (!Numbers(r, 3)) return false;
    *out = Vec3(num_[0], num_[1], num_[2]);
    return true;
  }

  // The parameter list after the `first` positional arguments: "name" value pairs. The
  // name may carry an inline declaration ("uniform float Ka"): its last word counts.
  struct Param {
    std::string name;
    const Value* value;
  };
  bool Params(const Request& r, size_t first, std::vector<Param>* out) {
    out->clear();
    if ((r.args.size() - std::min(first, r.args.size())) % 2 != 0)
      return Fail(r.line, r.name + ": the parameter list must be name-value pairs");
    for (size_t k = first; k + 1 < r.args.size(); k += 2) {
      const Value& name = r.args[k];
      if (name.kind != Value::Kind::String)
        return Fail(name.line, r.name + ": expected a parameter name (a string)");
      std::string_view word = name.strings[0];
      while (!word.empty() && IsSpace(word.back())) word.remove_suffix(1);
      const size_t space = word.find_last_of(" \t");
      if (space != std::string_view::npos) word.remove_prefix(space + 1);
      out->push_back({std::string(word), &r.args[k + 1]});
    }
    return true;
  }
  bool ParamNumbers(const Request& r, const Param& p, size_t count, double* out) {
    if (!p.value->Numeric() || p.value->numbers.size() != count)
      return Fail(p.value->line, r.name + ": parameter \"" + p.name + "\" expects " +
                                     std::to_string(count) + (count == 1 ? " number" : " numbers"));
    std::copy(p.value->numbers.begin(), p.value->numbers.end(), out);
    return true;
  }
  bool ParamVec3(const Request& r, const Param& p, Vec3* out) {
    double v[3];
    if (!ParamNumbers(r, p, 3, v)) return false;
    *out = Vec3(v[0], v[1], v[2]);
    return true;
  }
  bool ParamString(const Request& r, const Param& p, std::string* out) {
    if (!p.value->Textual() || p.value->strings.size() != 1)
      return Fail(p.value->line, r.name + ": parameter \"" + p.name + "\" expects one string");
    *out = p.value->strings[0];
    return true;
  }
  void IgnoreParam(const Request& r, const Param& p) {
    Warn(p.value->line, r.name + "/" + p.name,
         r.name + ": parameter \"" + p.name + "\" is not supported here: ignored");
  }

  // ---- structure ----
  bool FrameBegin(const Request& r) {
    if (!Numbers(r, 1)) return false;
    if (!blocks_.empty()) return Fail(r.line, "FrameBegin inside " + std::string(BlockName(blocks_.back().kind)));
    // Frame numbers are whole numbers within int (a larger one cannot be chosen anyway).
    if (num_[0] != std::floor(num_[0]) || std::abs(num_[0]) > 2e9)
      return Fail(r.line, "FrameBegin: the frame number must be a whole number");
    const int number = static_cast<int>(num_[0]);
    const bool chosen = options_.frame < 0 || options_.frame == number;
    blocks_.push_back({Block::Kind::Frame, r.line, file_, attr_});
    skippingFrame_ = !chosen;
    return true;
  }
  bool FrameEnd(const Request& r) {
    if (blocks_.empty() || blocks_.back().kind != Block::Kind::Frame) {
      if (skippingFrame_) return Fail(r.line, "FrameEnd inside a block of the skipped frame");
      return Fail(r.line, blocks_.empty() ? "FrameEnd without FrameBegin"
                                          : "FrameEnd closes " + std::string(BlockName(blocks_.back().kind)) +
                                                " at line " + std::to_string(blocks_.back().line));
    }
    attr_ = blocks_.back().saved;
    blocks_.pop_back();
    if (skippingFrame_) {
      skippingFrame_ = false;
      return true;
    }
    done_ = true;  // the chosen frame is complete
    return true;
  }
  bool ReadArchive(const Request& r, int depth) {
    std::string name;
    if (!StringArg(r, 0, &name)) return false;
    if (depth + 1 > kMaxArchiveDepth)
      return Fail(r.line, "ReadArchive nested more than " + std::to_string(kMaxArchiveDepth) +
                              " deep (an archive that reads itself?)");
    std::filesystem::path path(name);
    if (path.is_relative()) path = std::filesystem::path(file_).parent_path() / path;
    auto text = ReadTextFile(path.string());
    if (auto* e = std::get_if<SourceError>(&text))
      return Fail(r.line, "ReadArchive: " + e->What());
    return ReadText(std::get<std::string>(text), path.string(), depth + 1);
  }
  bool WorldBegin(const Request& r) {
    if (!Args(r, 0)) return false;
    for (const Block& b : blocks_)
      if (b.kind != Block::Kind::Frame)
        return Fail(r.line, "WorldBegin inside " + std::string(BlockName(b.kind)) + " at line " +
                                std::to_string(b.line));
    blocks_.push_back({Block::Kind::World, r.line, file_, attr_});
    if (sawWorld_) {
      Warn(r.line, "WorldBegin again", "a second world block: only the first is rendered");
      skippingWorld_ = true;
      return true;
    }
    sawWorld_ = true;
    // The transformation so far is the camera's: world to camera space.
    cameraFromWorld_ = attr_.transform;
    scene_.image.cameraFromWorld = cameraFromWorld_;
    // Lights declared in camera space before the world: into world space.
    const Mat4 worldFromCamera = cameraFromWorld_.inverse();
    for (SceneLight& l : scene_.lights) {
      l.from = (worldFromCamera * l.from.homogeneous()).head<3>();
      l.to = (worldFromCamera * l.to.homogeneous()).head<3>();
    }
    attr_.transform = Mat4::Identity();
    return true;
  }
  bool Begin(const Request& r, Block::Kind kind) {
    if (!Args(r, 0)) return false;
    blocks_.push_back({kind, r.line, file_, attr_});
    return true;
  }
  bool End(const Request& r, Block::Kind kind) {
    if (!Args(r, 0)) return false;
    const std::string name = r.name;
    if (blocks_.empty())
      return Fail(r.line, name + " without " + BlockName(kind));
    const Block& b = blocks_.back();
    if (b.kind != kind)
      return Fail(r.line, name + " closes " + BlockName(b.kind) + " at " +
                              (b.file == file_ ? "line " + std::to_string(b.line) : b.file + ":" + std::to_string(b.line)));
    if (kind == Block::Kind::Transform) {
      attr_.transform = b.saved.transform;
    } else {
      attr_ = b.saved;
    }
    blocks_.pop_back();
    if (kind == Block::Kind::World) skippingWorld_ = false;
    return true;
  }
  bool SkipObject(const Request& r) {
    Warn(r.line, "ObjectBegin", "ObjectBegin/ObjectInstance are not supported here: the object is skipped");
    ++objectDepth_;
    return true;
  }
  bool EndObject(const Request& r) {
    if (objectDepth_ == 0) return Fail(r.line, "ObjectEnd without ObjectBegin");
    --objectDepth_;
    return End(r, Block::Kind::Attribute);
  }

  // ---- camera and image ----
  bool Format(const Request& r) {
    if (!Numbers(r, 3)) return false;
    const double w = num_[0], h = num_[1];
    if (!(w >= 1 && h >= 1 && w <= kMaxImageSide && h <= kMaxImageSide && w == std::floor(w) && h == std::floor(h)))
      return Fail(r.line, "Format: the image size must be whole numbers from 1 to " + std::to_string(kMaxImageSide));
    if (!(num_[2] > 0)) return Fail(r.line, "Format: the pixel aspect ratio must be positive");
    if (num_[2] != 1.0) Warn(r.line, "pixelaspect", "Format: pixel aspect ratios other than 1 are not supported: square pixels");
    scene_.image.size = std::make_pair(static_cast<int>(w), static_cast<int>(h));
    return true;
  }
  bool Projection(const Request& r) {
    std::string name;
    if (!StringArg(r, 0, &name)) return false;
    std::vector<Param> params;
    if (!Params(r, 1, &params)) return false;
    if (name != "perspective" && name != "orthographic")
      return Fail(r.line, "Projection: unknown projection " + Shown(name) + " (known: \"perspective\", \"orthographic\")");
    scene_.image.orthographic = name == "orthographic";
    double& fov = scene_.image.fovDeg;
    fov = kRibDefaultFovDeg;
    for (const Param& p : params) {
      if (p.name == "fov" && !scene_.image.orthographic) {
        if (!ParamNumbers(r, p, 1, &fov)) return false;
        if (!(fov >= kMinFovDeg && fov <= kMaxFovDeg))
          return Fail(p.value->line, "Projection: fov must be from " + std::to_string(kMinFovDeg) + " to " + std::to_string(kMaxFovDeg) + " degrees");
      } else {
        IgnoreParam(r, p);
      }
    }
    // The projection resets the camera transformation (RenderMan Interface 3.2: it
    // defines camera space).
    attr_.transform = Mat4::Identity();
    return true;
  }
  bool ScreenWindow(const Request& r) {
    if (!Numbers(r, 4)) return false;
    if (num_[0] == num_[1] || num_[2] == num_[3]) return Fail(r.line, "ScreenWindow: the window is empty");
    scene_.image.screenWindow = Vec4(num_[0], num_[1], num_[2], num_[3]);
    return true;
  }
  bool Clipping(const Request& r) {
    if (!Numbers(r, 2)) return false;
    if (!(num_[0] > 0 && num_[1] > num_[0])) return Fail(r.line, "Clipping: expected 0 < near < far");
    scene_.image.hither = num_[0];
    return true;
  }
  bool PixelSamples(const Request& r) {
    if (!Numbers(r, 2)) return false;
    if (!(num_[0] >= 1 && num_[1] >= 1)) return Fail(r.line, "PixelSamples: expected at least 1 sample each way");
    const double side = std::round(std::sqrt(num_[0] * num_[1]));
    if (num_[0] != num_[1] || side > 8)
      Warn(r.line, "PixelSamples", "PixelSamples: a square grid of 1 to 8 samples a side is used");
    scene_.image.pixelSamples = static_cast<int>(std::clamp(side, 1.0, 8.0));
    return true;
  }
  bool Display(const Request& r) {
    std::string name, type;
    if (!StringArg(r, 0, &name) || !StringArg(r, 1, &type)) return false;
    // A name starting with '+' adds a further display: only the first is written.
    if (type != "framebuffer" && !name.empty() && name[0] != '+') scene_.image.displayName = name;
    return true;
  }

  // ---- transformations ----
  bool SetTransform(const Request& r, const Mat4& m) {
    attr_.transform = m;
    return CheckTransform(r);
  }
  bool Concat(const Request& r, const Mat4& m) {
    attr_.transform = attr_.transform * m;
    return CheckTransform(r);
  }
  bool CheckTransform(const Request& r) {
    if (!attr_.transform.allFinite()) return Fail(r.line, r.name + ": the transformation is no longer finite");
    return true;
  }
  bool sawWorldOpen() const {
    for (const Block& b : blocks_)
      if (b.kind == Block::Kind::World) return true;
    return false;
  }
  bool Rotate(const Request& r) {
    if (!Numbers(r, 4)) return false;
    const Vec3 axis(num_[1], num_[2], num_[3]);
    if (axis.norm() == 0.0) return Fail(r.line, "Rotate: the axis is zero");
    Mat4 m = Mat4::Identity();
    m.block<3, 3>(0, 0) = Eigen::AngleAxisd(num_[0] * kRadPerDeg, axis.normalized()).toRotationMatrix();
    return Concat(r, m);
  }
  bool Orientation(const Request& r) {
    std::string o;
    if (!StringArg(r, 0, &o)) return false;
    if (o == "outside" || o == "lh") {
      attr_.insideOrientation = false;
    } else if (o == "inside" || o == "rh") {
      attr_.insideOrientation = true;
    } else {
      return Fail(r.line, "Orientation: expected \"outside\", \"inside\", \"lh\" or \"rh\", found " + Shown(o));
    }
    return true;
  }
  bool Sides(const Request& r) {
    if (!Numbers(r, 1)) return false;
    if (num_[0] != 1 && num_[0] != 2) return Fail(r.line, "Sides: expected 1 or 2");
    attr_.appearance.twoSided = num_[0] == 2;
    return true;
  }

  // ---- appearance ----
  bool SurfaceShader(const Request& r) {
    std::string name;
    if (!StringArg(r, 0, &name)) return false;
    std::vector<Param> params;
    if (!Params(r, 1, &params)) return false;
    Appearance& a = attr_.appearance;
    using S = Appearance::Shader;
    // The standard shaders' defaults (RenderMan Interface 3.2, appendix A).
    if (name == "constant") {
      a.shader = S::Constant;
    } else if (name == "matte") {
      a.shader = S::Matte;
      a.ka = 1.0;
      a.kd = 1.0;
    } else if (name == "metal") {
      a.shader = S::Metal;
      a.ka = 1.0;
      a.ks = 1.0;
      a.roughness = 0.1;
    } else if (name == "plastic" || name == "paintedplastic") {
      a.shader = name == "plastic" ? S::Plastic : S::PaintedPlastic;
      a.ka = 1.0;
      a.kd = 0.5;
      a.ks = 0.5;
      a.roughness = 0.1;
      a.specularColour = Vec3(1, 1, 1);
    } else {
      Warn(r.line, "shader " + name, "Surface: unknown shader " + Shown(name) + ": the default material is used");
      a.shader = S::Default;
      return true;
    }
    a.textureName.clear();
    for (const Param& p : params) {
      bool ok = true;
      if (p.name == "Ka" && a.shader != S::Constant) ok = ParamNumbers(r, p, 1, &a.ka);
      else if (p.name == "Kd" && a.shader != S::Constant && a.shader != S::Metal) ok = ParamNumbers(r, p, 1, &a.kd);
      else if (p.name == "Ks" && (a.shader == S::Metal || a.shader == S::Plastic || a.shader == S::PaintedPlastic)) ok = ParamNumbers(r, p, 1, &a.ks);
      else if (p.name == "roughness" && (a.shader == S::Metal || a.shader == S::Plastic || a.shader == S::PaintedPlastic)) {
        ok = ParamNumbers(r, p, 1, &a.roughness);
        if (ok && !(a.roughness > 0)) return Fail(p.value->line, "Surface: roughness must be positive");
      } else if (p.name == "specularcolor" && (a.shader == S::Plastic || a.shader == S::PaintedPlastic)) {
        ok = ParamVec3(r, p, &a.specularColour);
      } else if (p.name == "texturename" && a.shader == S::PaintedPlastic) {
        ok = ParamString(r, p, &a.textureName);
        if (ok && !a.textureName.empty()) {
          std::filesystem::path path(a.textureName);
          if (path.is_relative()) a.textureName = (std::filesystem::path(file_).parent_path() / path).string();
        }
      } else {
        IgnoreParam(r, p);
      }
      if (!ok) return false;
    }
    return true;
  }
  bool LightSource(const Request& r) {
    std::string name;
    if (!StringArg(r, 0, &name)) return false;
    if (r.args.size() < 2) return Fail(r.line, "LightSource expects a shader name and a light handle");
    std::vector<Param> params;
    if (!Params(r, 2, &params)) return false;
    SceneLight l;
    l.line = r.line;
    using K = SceneLight::Kind;
    if (name == "ambientlight") l.kind = K::Ambient;
    else if (name == "distantlight") l.kind = K::Distant;
    else if (name == "pointlight") l.kind = K::Point;
    else if (name == "spotlight") l.kind = K::Spot;
    else {
      Warn(r.line, "light " + name, "LightSource: unknown light shader " + Shown(name) + ": skipped");
      return true;
    }
    double intensity = 1.0;
    Vec3 colour(1, 1, 1);
    l.coneAngle = kSpotConeDeg * kRadPerDeg;
    l.coneDelta = kSpotDeltaDeg * kRadPerDeg;
    for (const Param& p : params) {
      bool ok = true;
      if (p.name == "intensity") ok = ParamNumbers(r, p, 1, &intensity);
      else if (p.name == "lightcolor") ok = ParamVec3(r, p, &colour);
      else if (p.name == "from" && l.kind != K::Ambient) ok = ParamVec3(r, p, &l.from);
      else if (p.name == "to" && (l.kind == K::Distant || l.kind == K::Spot)) ok = ParamVec3(r, p, &l.to);
      else if (p.name == "coneangle" && l.kind == K::Spot) ok = ParamNumbers(r, p, 1, &l.coneAngle);
      else if (p.name == "conedeltaangle" && l.kind == K::Spot) ok = ParamNumbers(r, p, 1, &l.coneDelta);
      else if (p.name == "beamdistribution" && l.kind == K::Spot) ok = ParamNumbers(r, p, 1, &l.beamDistribution);
      else IgnoreParam(r, p);
      if (!ok) return false;
    }
    if ((l.kind == K::Distant || l.kind == K::Spot) && l.from == l.to)
      return Fail(r.line, "LightSource: \"from\" and \"to\" are the same point");
    l.colour = intensity * colour;
    // From the current space into world space (camera space before WorldBegin: moved to
    // world space there).
    l.from = (attr_.transform * l.from.homogeneous()).head<3>();
    l.to = (attr_.transform * l.to.homogeneous()).head<3>();
    scene_.lights.push_back(l);
    return true;
  }

  // ---- geometry ----
  bool InWorld(const Request& r) {
    if (!sawWorldOpen()) return Fail(r.line, r.name + " outside WorldBegin/WorldEnd");
    return true;
  }
  void AddSurface(const Request& r, Shape shape) {
    Surface s{std::move(shape), Affine3(attr_.transform)};
    scene_.surfaces.push_back(std::move(s));
    scene_.sourceLines.push_back(r.line);
    scene_.sourceFiles.push_back(file_);
    Appearance a = attr_.appearance;
    // RenderMan Interface 3.2, "Orientation": the normal is flipped where the orientation
    // differs from the handedness of the current coordinate system (left-handed unless
    // the camera and object transformations together mirror it).
    const bool mirrored = (cameraFromWorld_ * attr_.transform).block<3, 3>(0, 0).determinant() < 0.0;
    a.reversed = attr_.insideOrientation != mirrored;
    // Distinct appearances, found by hash: a scene may give each of its surfaces its own.
    std::vector<std::uint32_t>& same = appearanceIndex_[HashOf(a)];
    std::uint32_t index = 0;
    for (const std::uint32_t k : same)
      if (scene_.appearances[k] == a) index = k + 1;
    if (index == 0) {
      same.push_back(static_cast<std::uint32_t>(scene_.appearances.size()));
      scene_.appearances.push_back(a);
      index = static_cast<std::uint32_t>(scene_.appearances.size());
    }
    scene_.appearanceOf.push_back(index - 1);
  }
  static std::size_t HashOf(const Appearance& a) {
    std::size_t h = std::hash<std::string>()(a.textureName) ^ (static_cast<std::size_t>(a.shader) << 1) ^
                    (static_cast<std::size_t>(a.twoSided) << 5) ^ (static_cast<std::size_t>(a.reversed) << 6);
    for (const double x : {a.colour.x(), a.colour.y(), a.colour.z(), a.opacity.x(), a.opacity.y(), a.opacity.z(), a.ka,
                           a.kd, a.ks, a.roughness, a.specularColour.x(), a.specularColour.y(), a.specularColour.z()})
      h = h * 1000003u ^ std::hash<double>()(x);
    return h;
  }
  bool BasisRequest(const Request& r) {
    // Basis ubasis ustep vbasis vstep: each basis a name or 16 numbers.
    if (r.args.size() != 4) return Fail(r.line, "Basis expects 4 arguments (ubasis ustep vbasis vstep), found " + std::to_string(r.args.size()));
    Basis b[2];
    for (int k = 0; k < 2; ++k) {
      const Value& basis = r.args[2 * k];
      const Value& step = r.args[2 * k + 1];
      if (basis.Textual()) {
        const auto named = basis.strings.size() == 1 ? BasisByName(basis.strings[0]) : std::nullopt;
        if (!named)
          return Fail(basis.line, "Basis: unknown basis " + Shown(basis.strings.empty() ? "" : basis.strings[0]) +
                                      " (known: bezier, b-spline, catmull-rom, hermite, power)");
        b[k] = *named;
      } else {
        if (basis.numbers.size() != 16) return Fail(basis.line, "Basis: a basis matrix has 16 numbers, found " + std::to_string(basis.numbers.size()));
        for (int i = 0; i < 4; ++i)
          for (int j = 0; j < 4; ++j) b[k].m(i, j) = basis.numbers[4 * i + j];
        b[k].name = "matrix";
      }
      if (step.kind != Value::Kind::Number || step.numbers[0] != std::floor(step.numbers[0]) ||
          step.numbers[0] < 1 || step.numbers[0] > 4)
        return Fail(step.line, "Basis: a step is a whole number from 1 to 4");
      b[k].step = static_cast<int>(step.numbers[0]);
    }
    attr_.uBasis = b[0];
    attr_.vBasis = b[1];
    return true;
  }
  // The "P" of a patch's parameter list: exactly `count` points into pts_.
  bool Points(const Request& r, size_t first, size_t count) {
    std::vector<Param> params;
    if (!Params(r, first, &params)) return false;
    const Value* p = nullptr;
    for (const Param& q : params) {
      if (q.name == "P") p = q.value;
      else if (q.name == "Pw") return Fail(q.value->line, r.name + ": \"Pw\" (rational patches) is not supported; give \"P\"");
      else if (q.name == "Pz") return Fail(q.value->line, r.name + ": \"Pz\" (height fields) is not supported; give \"P\"");
      else IgnoreParam(r, q);
    }
    if (!p) return Fail(r.line, r.name + ": no \"P\"");
    if (!p->Numeric() || p->numbers.size() != 3 * count)
      return Fail(p->line, r.name + ": \"P\" expects " + std::to_string(3 * count) + " numbers (" +
                               std::to_string(count) + " points), found " + std::to_string(p->Size()));
    pts_.resize(count);
    for (size_t k = 0; k < count; ++k) pts_[k] = Vec3(p->numbers[3 * k], p->numbers[3 * k + 1], p->numbers[3 * k + 2]);
    return true;
  }
  bool PatchType(const Request& r, bool* bicubic) {
    std::string type;
    if (!StringArg(r, 0, &type)) return false;
    if (type != "bilinear" && type != "bicubic")
      return Fail(r.line, r.name + ": unknown type " + Shown(type) + " (known: \"bilinear\", \"bicubic\")");
    *bicubic = type == "bicubic";
    return true;
  }
  bool Patch(const Request& r) {
    bool bicubic = false;
    if (!InWorld(r) || !PatchType(r, &bicubic) || !Points(r, 1, bicubic ? 16 : 4)) return false;
    if (bicubic) {
      std::array<Vec3, 16> cv;
      std::copy(pts_.begin(), pts_.end(), cv.begin());
      AddSurface(r, BicubicPatch(cv, attr_.uBasis, attr_.vBasis));
    } else {
      AddSurface(r, BilinearPatch({pts_[0], pts_[1], pts_[2], pts_[3]}));
    }
    return true;
  }
  // Patches along one direction of a mesh of n points: RenderMan Interface 3.2,
  // "PatchMesh": bicubic nonperiodic (n - 4) / step + 1, periodic n / step; bilinear
  // nonperiodic n - 1, periodic n.
  bool MeshCount(const Request& r, int n, bool periodic, bool bicubic, int step, const char* dir, int* count) {
    if (!bicubic) {
      if (n < (periodic ? 1 : 2)) return Fail(r.line, std::string("PatchMesh: too few points in ") + dir);
      *count = periodic ? n : n - 1;
      return true;
    }
    if (periodic) {
      if (n < 4 || n % step != 0) return Fail(r.line, std::string("PatchMesh: a periodic bicubic mesh needs a multiple of the ") + dir + " step (" + std::to_string(step) + ") of at least 4 points in " + dir + ", found " + std::to_string(n));
      *count = n / step;
    } else {
      if (n < 4 || (n - 4) % step != 0) return Fail(r.line, std::string("PatchMesh: a nonperiodic bicubic mesh needs 4 + k * ") + std::to_string(step) + " points in " + dir + ", found " + std::to_string(n));
      *count = (n - 4) / step + 1;
    }
    return true;
  }
  bool PatchMesh(const Request& r) {
    bool bicubic = false;
    if (!InWorld(r) || !PatchType(r, &bicubic)) return false;
    if (r.args.size() < 5) return Fail(r.line, "PatchMesh expects type nu uwrap nv vwrap, then \"P\"");
    int n[2];
    bool periodic[2];
    for (int k = 0; k < 2; ++k) {
      const Value& count = r.args[1 + 2 * k];
      const Value& wrap = r.args[2 + 2 * k];
      if (count.kind != Value::Kind::Number || count.numbers[0] != std::floor(count.numbers[0]) || count.numbers[0] < 1 || count.numbers[0] > 1e7)
        return Fail(count.line, "PatchMesh: a point count is a whole number from 1 to 10000000");
      if (wrap.kind != Value::Kind::String || (wrap.strings[0] != "periodic" && wrap.strings[0] != "nonperiodic"))
        return Fail(wrap.line, "PatchMesh: wrap is \"periodic\" or \"nonperiodic\"");
      n[k] = static_cast<int>(count.numbers[0]);
      periodic[k] = wrap.strings[0] == "periodic";
    }
    const int nu = n[0], nv = n[1];
    if (static_cast<long long>(nu) * nv > 10'000'000LL) return Fail(r.line, "PatchMesh: more than 10000000 points");
    if (!Points(r, 5, static_cast<size_t>(nu) * nv)) return false;
    const int uStep = bicubic ? attr_.uBasis.step : 1, vStep = bicubic ? attr_.vBasis.step : 1;
    int nuPatches = 0, nvPatches = 0;
    if (!MeshCount(r, nu, periodic[0], bicubic, uStep, "u", &nuPatches) ||
        !MeshCount(r, nv, periodic[1], bicubic, vStep, "v", &nvPatches))
      return false;
    const int order = bicubic ? 4 : 2;
    for (int pv = 0; pv < nvPatches; ++pv)
      for (int pu = 0; pu < nuPatches; ++pu) {
        std::array<Vec3, 16> cv;
        for (int j = 0; j < order; ++j)
          for (int i = 0; i < order; ++i) {
            const int iu = (pu * uStep + i) % nu, iv = (pv * vStep + j) % nv;
            cv[static_cast<size_t>(order * j + i)] = pts_[static_cast<size_t>(iv) * nu + iu];
          }
        if (bicubic) AddSurface(r, BicubicPatch(cv, attr_.uBasis, attr_.vBasis));
        else AddSurface(r, BilinearPatch({cv[0], cv[1], cv[2], cv[3]}));
      }
    return true;
  }
  bool Quadric(const Request& r) {
    if (!InWorld(r)) return false;
    const std::string& n = r.name;
    const size_t count = n == "Hyperboloid" ? 7 : n == "Torus" ? 5 : (n == "Cone" || n == "Disk") ? 3 : 4;
    size_t used = 0;
    if (!Numbers(r, count, &used)) return false;
    std::vector<Param> params;
    if (!Params(r, used, &params)) return false;
    for (const Param& p : params) IgnoreParam(r, p);
    const double* a = num_.data();
    const double thetaMax = a[count - 1];
    // Sweeps are angles of at most a turn either way (RenderMan Interface 3.2, "Quadrics").
    if (!(std::abs(thetaMax) <= 360.0)) return Fail(r.line, n + ": thetamax must be from -360 to 360 degrees");
    if (n == "Torus" && !(std::abs(a[2]) <= 360.0 && std::abs(a[3]) <= 360.0))
      return Fail(r.line, "Torus: phimin and phimax must be from -360 to 360 degrees");
    auto positive = [&](double x, const char* what) {
      return x > 0 ? true : Fail(r.line, n + ": " + what + " must be positive");
    };
    if (n == "Sphere") {
      if (!positive(a[0], "the radius")) return false;
      AddSurface(r, Sphere(a[0], a[1], a[2], thetaMax));
    } else if (n == "Cylinder") {
      if (!positive(a[0], "the radius")) return false;
      AddSurface(r, Cylinder(a[0], a[1], a[2], thetaMax));
    } else if (n == "Cone") {
      if (!positive(a[1], "the radius")) return false;
      AddSurface(r, Cone(a[0], a[1], thetaMax));
    } else if (n == "Paraboloid") {
      if (!positive(a[0], "rmax") || !positive(a[2] - a[1], "zmax - zmin")) return false;
      AddSurface(r, Paraboloid(a[0], a[1], a[2], thetaMax));
    } else if (n == "Hyperboloid") {
      AddSurface(r, Hyperboloid(Vec3(a[0], a[1], a[2]), Vec3(a[3], a[4], a[5]), thetaMax));
    } else if (n == "Disk") {
      if (!positive(a[1], "the radius")) return false;
      AddSurface(r, Disk(a[0], a[1], thetaMax));
    } else {
      if (!positive(a[0], "the major radius") || !positive(a[1], "the minor radius")) return false;
      AddSurface(r, Torus(a[0], a[1], a[2], a[3], thetaMax));
    }
    return true;
  }
  bool Geometry(const Request& r) {
    std::string name;
    if (!InWorld(r) || !StringArg(r, 0, &name)) return false;
    if (name != "teapot") {
      Warn(r.line, "geometry " + name, "Geometry: unknown geometry " + Shown(name) + ": skipped");
      return true;
    }
    // Parsed once per program: a scene may hold a thousand teapots.
    static const auto teapot = ParseBpt(TeapotBptText(), "teapot");
    if (auto* e = std::get_if<SourceError>(&teapot)) return Fail(r.line, "Geometry \"teapot\": " + e->What());
    for (const BptPatch& p : std::get<BptFile>(teapot).patches) AddSurface(r, BicubicPatch(p.cv));
    return true;
  }

  LoadOptions options_;
  Scene scene_;
  std::optional<SourceError> error_;
  std::string file_;
  Attributes attr_;
  std::vector<Block> blocks_;
  std::set<std::string, std::less<>> warned_;
  std::vector<double> num_;
  std::vector<Vec3> pts_;
  std::unordered_map<std::size_t, std::vector<std::uint32_t>> appearanceIndex_;
  Mat4 cameraFromWorld_ = Mat4::Identity();
  bool sawWorld_ = false, skippingWorld_ = false, skippingFrame_ = false, done_ = false;
  int objectDepth_ = 0;
};

}  // namespace

std::variant<Scene, SourceError> ParseRib(std::string_view text, const std::string& name,
                                          const LoadOptions& options) {
  RibParser parser(options);
  return parser.Run(text, name);
}

std::variant<Scene, SourceError> ReadRib(const std::string& path, const LoadOptions& options) {
  auto text = ReadTextFile(path);
  if (auto* e = std::get_if<SourceError>(&text)) return *e;
  return ParseRib(std::get<std::string>(text), path, options);
}

}  // namespace patchscan
