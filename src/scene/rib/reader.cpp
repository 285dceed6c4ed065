#include "scene/rib/reader.h"

#include <filesystem>

#include "scene/rib/parser.h"
#include "scene/text_file.h"

namespace patchscan::rib {

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
      "Declare", "Atmosphere", "Interior",
      "Exterior", "Imager", "Exposure", "Quantize", "PixelFilter", "PixelVariance",
      "ShadingRate", "ShadingInterpolation", "Matte", "Bound", "Detail", "DetailRange",
      "GeometricApproximation", "MakeTexture",
      "MakeBump", "FrameAspectRatio", "DepthOfField",
      "Shutter", "ColorSamples", "RelativeDetail", "TextureCoordinates", "Illuminate",
      "AreaLightSource", "CoordinateSystem", "CoordSysTransform", "ScopedCoordinateSystem",
      "Perspective", "Skew", "Deformation", "SolidBegin", "SolidEnd", "MotionBegin",
      "MotionEnd",
      "HierarchicalSubdivisionMesh", "Points", "Blobby", "Version",
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

std::variant<Scene, SourceError> RibParser::Run(std::string_view text, const std::string& name) {
  scene_.source = name;
  if (!ReadText(text, name, 0)) return *error_;
  if (recording_)
    return SourceError{recordingFile_, recordingLine_, "ObjectBegin is never closed"};
  if (!done_) {
    for (auto b = blocks_.rbegin(); b != blocks_.rend(); ++b)
      return SourceError{b->file, b->line, std::string(BlockName(b->kind)) + " is never closed"};
    if (options_.frame >= 0)
      return SourceError{name, 0, "no FrameBegin " + std::to_string(options_.frame) + " in the file"};
  }
  if (!sawWorld_) return SourceError{name, 0, "no WorldBegin: a RIB scene needs a world block"};
  // Polygons take the surface ids after the surfaces'.
  scene_.appearanceOf.insert(scene_.appearanceOf.end(), polygonAppearance_.begin(), polygonAppearance_.end());
  // Each kind is named once, at its first place, with how often it came.
  for (const auto& [kind, at] : warned_)
    if (at.second > 1) scene_.warnings[at.first] += " (" + std::to_string(at.second) + " times)";
  return std::move(scene_);
}

bool RibParser::Fail(int line, std::string message) {
  error_ = SourceError{file_, line, std::move(message)};
  return false;
}

void RibParser::Warn(int line, const std::string& kind, const std::string& what) {
  const auto [it, first] = warned_.try_emplace(kind, scene_.warnings.size(), 0);
  ++it->second.second;
  if (first) scene_.warnings.push_back(SourceError{file_, line, what}.What());
}

bool RibParser::ReadText(std::string_view text, const std::string& name, int depth) {
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

const std::unordered_map<std::string_view, RibParser::Handler>& RibParser::RequestTable() {
  static const std::unordered_map<std::string_view, Handler> k = {
      // Camera and image.
      {"Format", &RibParser::Format},
      {"Projection", &RibParser::Projection},
      {"ScreenWindow", &RibParser::ScreenWindow},
      {"CropWindow", &RibParser::CropWindow},
      {"Clipping", &RibParser::Clipping},
      {"PixelSamples", &RibParser::PixelSamples},
      {"Display", &RibParser::Display},
      // Transformations.
      {"Identity", &RibParser::Identity},
      {"Transform", &RibParser::TransformRequest},
      {"ConcatTransform", &RibParser::ConcatTransform},
      {"Translate", &RibParser::Translate},
      {"Scale", &RibParser::Scale},
      {"Rotate", &RibParser::Rotate},
      {"Orientation", &RibParser::Orientation},
      {"ReverseOrientation", &RibParser::ReverseOrientation},
      {"Sides", &RibParser::Sides},
      // Appearance.
      {"Color", &RibParser::Color},
      {"Opacity", &RibParser::Opacity},
      {"Surface", &RibParser::SurfaceShader},
      {"Displacement", &RibParser::DisplacementShader},
      {"LightSource", &RibParser::LightSource},
      {"MakeShadow", &RibParser::MakeTexture},
      {"MakeLatLongEnvironment", &RibParser::MakeTexture},
      {"MakeCubeFaceEnvironment", &RibParser::MakeTexture},
      {"Hider", &RibParser::Hider},
      {"Option", &RibParser::Option},
      // Geometry.
      {"Basis", &RibParser::BasisRequest},
      {"Patch", &RibParser::Patch},
      {"PatchMesh", &RibParser::PatchMesh},
      {"SubdivisionMesh", &RibParser::SubdivisionMesh},
      {"NuPatch", &RibParser::NuPatch},
      {"Polygon", &RibParser::Polygon},
      {"Curves", &RibParser::Curves},
      {"GeneralPolygon", &RibParser::GeneralPolygon},
      {"PointsPolygons", &RibParser::PointsPolygons},
      {"PointsGeneralPolygons", &RibParser::PointsGeneralPolygons},
      {"TrimCurve", &RibParser::TrimCurve},
      {"Attribute", &RibParser::AttributeRequest},
      {"Sphere", &RibParser::Quadric},
      {"Cylinder", &RibParser::Quadric},
      {"Cone", &RibParser::Quadric},
      {"Paraboloid", &RibParser::Quadric},
      {"Hyperboloid", &RibParser::Quadric},
      {"Disk", &RibParser::Quadric},
      {"Torus", &RibParser::Quadric},
      {"Geometry", &RibParser::Geometry},
  };
  return k;
}

bool RibParser::Handle(const Request& r, int depth) {
  const std::string& n = r.name;
  if (recording_) return Record(r, depth);
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
  if (n == "ObjectBegin") return ObjectBegin(r);
  if (n == "ObjectEnd") return Fail(r.line, "ObjectEnd without ObjectBegin");
  if (n == "ObjectInstance") return ObjectInstance(r, depth);
  if (n == "Procedural") return Procedural(r, depth);
  // Everything else, by the request table.
  if (const auto h = RequestTable().find(n); h != RequestTable().end()) return (this->*(h->second))(r);
  if (SkippedRequests().count(n) != 0) {
    Warn(r.line, n, n + " is not supported here: skipped");
    return true;
  }
  Warn(r.line, n, "unknown request " + Shown(n) + ": skipped");
  return true;
}

bool RibParser::Args(const Request& r, size_t count) {
  if (r.args.size() < count)
    return Fail(r.line, r.name + " expects " + std::to_string(count) + " arguments, found " +
                            std::to_string(r.args.size()));
  return true;
}

bool RibParser::Numbers(const Request& r, size_t count, size_t* used) {
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

bool RibParser::StringArg(const Request& r, size_t k, std::string* out) {
  if (k >= r.args.size() || !r.args[k].Textual() || r.args[k].strings.size() != 1)
    return Fail(k < r.args.size() ? r.args[k].line : r.line,
                r.name + " expects a string as argument " + std::to_string(k + 1));
  *out = r.args[k].strings[0];
  return true;
}

bool RibParser::ColourArg(const Request& r, Vec3* out) {
  if (!Numbers(r, 3)) return false;
  *out = Vec3(num_[0], num_[1], num_[2]);
  return true;
}

bool RibParser::Params(const Request& r, size_t first, std::vector<Param>* out) {
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
    out->push_back({std::string(word), &r.args[k + 1], name.strings[0]});
  }
  return true;
}

bool RibParser::ParamNumbers(const Request& r, const Param& p, size_t count, double* out) {
  if (!p.value->Numeric() || p.value->numbers.size() != count)
    return Fail(p.value->line, r.name + ": parameter \"" + p.name + "\" expects " +
                                   std::to_string(count) + (count == 1 ? " number" : " numbers"));
  std::copy(p.value->numbers.begin(), p.value->numbers.end(), out);
  return true;
}

bool RibParser::ParamVec3(const Request& r, const Param& p, Vec3* out) {
  double v[3];
  if (!ParamNumbers(r, p, 3, v)) return false;
  *out = Vec3(v[0], v[1], v[2]);
  return true;
}

bool RibParser::ParamString(const Request& r, const Param& p, std::string* out) {
  if (!p.value->Textual() || p.value->strings.size() != 1)
    return Fail(p.value->line, r.name + ": parameter \"" + p.name + "\" expects one string");
  *out = p.value->strings[0];
  return true;
}

void RibParser::IgnoreParam(const Request& r, const Param& p) {
  Warn(p.value->line, r.name + "/" + p.name,
       r.name + ": parameter \"" + p.name + "\" is not supported here: ignored");
}

bool RibParser::FrameBegin(const Request& r) {
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

bool RibParser::FrameEnd(const Request& r) {
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

bool RibParser::ReadArchive(const Request& r, int depth) {
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

bool RibParser::WorldBegin(const Request& r) {
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

bool RibParser::Begin(const Request& r, Block::Kind kind) {
  if (!Args(r, 0)) return false;
  blocks_.push_back({kind, r.line, file_, attr_});
  return true;
}

bool RibParser::End(const Request& r, Block::Kind kind) {
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

bool RibParser::ObjectHandle(const Request& r, std::string* out) {
  // A number (RenderMan 3.2) or a string (3.3 and prman).
  if (r.args.empty() || r.args[0].Size() != 1)
    return Fail(r.line, r.name + " expects an object handle (a number or a string)");
  *out = r.args[0].Numeric() ? ShortestNumber(r.args[0].numbers[0]) : r.args[0].strings[0];
  return true;
}

bool RibParser::ObjectBegin(const Request& r) {
  std::string handle;
  if (!ObjectHandle(r, &handle)) return false;
  recording_.emplace(handle, std::vector<Recorded>{});
  recordingLine_ = r.line;
  recordingFile_ = file_;
  return true;
}

bool RibParser::Record(const Request& r, int depth) {
  const std::string& n = r.name;
  if (n == "ObjectEnd") return ObjectEnd(r);
  if (n == "ReadArchive") return ReadArchive(r, depth);  // its requests are recorded
  if (n == "ObjectBegin" || n == "FrameBegin" || n == "FrameEnd" || n == "WorldBegin" || n == "WorldEnd")
    return Fail(r.line, n + " inside the object definition of ObjectBegin at " + recordingFile_ + ":" +
                            std::to_string(recordingLine_));
  recording_->second.push_back({file_, r});
  return true;
}

bool RibParser::ObjectEnd(const Request& r) {
  if (!Args(r, 0)) return false;
  objects_[recording_->first] = std::move(recording_->second);
  recording_.reset();
  return true;
}

template <class F>
bool RibParser::Scoped(const Request& r, const std::string& what, F&& body) {
  const Attributes saved = attr_;
  const std::size_t blocks = blocks_.size();
  if (!body()) return false;
  if (blocks_.size() < blocks) return Fail(r.line, r.name + ": " + what + " closes blocks it did not open");
  if (blocks_.size() > blocks)
    return Fail(r.line, r.name + ": " + what + " leaves " + std::string(BlockName(blocks_.back().kind)) + " at " +
                            blocks_.back().file + ":" + std::to_string(blocks_.back().line) + " open");
  attr_ = saved;
  return true;
}

bool RibParser::ObjectInstance(const Request& r, int depth) {
  std::string handle;
  if (!InWorld(r) || !ObjectHandle(r, &handle)) return false;
  const auto object = objects_.find(handle);
  if (object == objects_.end()) return Fail(r.line, "ObjectInstance: no object " + Shown(handle) + " was defined");
  if (depth + 1 > kMaxArchiveDepth)
    return Fail(r.line, "ObjectInstance nested more than " + std::to_string(kMaxArchiveDepth) +
                            " deep (an object that instances itself?)");
  replayed_ += static_cast<long>(object->second.size());
  if (replayed_ > kMaxReplayedRequests)
    return Fail(r.line, "ObjectInstance: more than " + std::to_string(kMaxReplayedRequests) +
                            " requests replayed in all (instances of instances of ...)");
  // A copy: an instance inside may define objects anew.
  const std::vector<Recorded> requests = object->second;
  return Scoped(r, "object " + Shown(handle), [&] {
    const std::string outerFile = file_;
    for (const Recorded& rec : requests) {
      file_ = rec.file;
      if (!Handle(rec.request, depth + 1)) return false;
      if (done_) break;
    }
    file_ = outerFile;
    return true;
  });
}

bool RibParser::Procedural(const Request& r, int depth) {
  // Procedural "DelayedReadArchive" ["file"] [bound]: the archive read here, in a block of
  // its own. Other procedurals run programs or load code: skipped.
  std::string kind;
  if (!StringArg(r, 0, &kind)) return false;
  if (kind != "DelayedReadArchive") {
    Warn(r.line, "Procedural " + kind, "Procedural " + Shown(kind) + " is not supported here: skipped");
    return true;
  }
  if (r.args.size() < 2 || !r.args[1].Textual() || r.args[1].strings.empty())
    return Fail(r.line, "Procedural \"DelayedReadArchive\" expects the archive's file name in a string array");
  Request read{"ReadArchive", r.line, {r.args[1]}};
  read.args[0].kind = Value::Kind::String;
  read.args[0].strings.resize(1);
  return Scoped(r, "archive " + Shown(read.args[0].strings[0]), [&] { return ReadArchive(read, depth); });
}

}  // namespace patchscan::rib

namespace patchscan {

std::variant<Scene, SourceError> ParseRib(std::string_view text, const std::string& name,
                                          const LoadOptions& options) {
  rib::RibParser parser(options);
  return parser.Run(text, name);
}

std::vector<RibFrame> RibFrames(const std::string& path) {
  std::vector<RibFrame> frames;
  auto text = ReadTextFile(path);
  if (!std::holds_alternative<std::string>(text)) return frames;
  rib::Lexer lexer(std::get<std::string>(text), path);
  rib::Request r;
  RibFrame outside;  // the Display given outside any frame
  bool inFrame = false;
  while (lexer.Next(&r)) {
    if (r.name == "FrameBegin" && !r.args.empty() && r.args[0].Numeric() && r.args[0].numbers.size() == 1) {
      const double n = r.args[0].numbers[0];
      inFrame = n == std::floor(n) && std::abs(n) <= 2e9;
      if (inFrame) frames.push_back({static_cast<int>(n), outside.depthMap, outside.display});
    } else if (r.name == "FrameEnd") {
      inFrame = false;
    } else if (r.name == "Display" && r.args.size() >= 2 && !r.args[0].Numeric() && r.args[0].Size() == 1 &&
               !r.args[1].Numeric() && r.args[1].Size() == 1) {
      // As the reader takes a Display: a framebuffer or a further display ('+') is not the file.
      const std::string& name = r.args[0].strings[0];
      if (r.args[1].strings[0] == "framebuffer" || name.empty() || name[0] == '+') continue;
      RibFrame& frame = inFrame ? frames.back() : outside;
      frame.depthMap = r.args[1].strings[0] == "zfile" || r.args[1].strings[0] == "shadow";
      frame.display = name;
    }
  }
  return frames;
}

std::variant<Scene, SourceError> ReadRib(const std::string& path, const LoadOptions& options) {
  auto text = ReadTextFile(path);
  if (auto* e = std::get_if<SourceError>(&text)) return *e;
  return ParseRib(std::get<std::string>(text), path, options);
}

}  // namespace patchscan
