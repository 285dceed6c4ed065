#include "scene/cad_reader.h"

// Open CASCADE's OCC_CATCH_SIGNALS turns a signal raised inside it into an exception (its
// libraries are built with this on Linux): its parsers crash on some malformed files.
#define OCC_CONVERT_SIGNALS
#include <csignal>

#include <BRepAdaptor_Surface.hxx>
#include <BRepBuilderAPI_NurbsConvert.hxx>
#include <BRepBuilderAPI_Sewing.hxx>
#include <BRepTools.hxx>
#include <BRepTools_Modifier.hxx>
#include <BRep_Builder.hxx>
#include <BRep_Tool.hxx>
#include <IGESCAFControl_Reader.hxx>
#include <Message.hxx>
#include <Message_Messenger.hxx>
#include <NCollection_DataMap.hxx>
#include <OSD.hxx>
#include <Quantity_Color.hxx>
#include <STEPCAFControl_Reader.hxx>
#include <ShapeCustom_ConvertToBSpline.hxx>
#include <Standard_ErrorHandler.hxx>
#include <Standard_Failure.hxx>
#include <TDF_Tool.hxx>
#include <TDataStd_Name.hxx>
#include <TDocStd_Document.hxx>
#include <TopExp.hxx>
#include <TopExp_Explorer.hxx>
#include <TopTools_IndexedMapOfShape.hxx>
#include <TopTools_ShapeMapHasher.hxx>
#include <TopoDS.hxx>
#include <XCAFApp_Application.hxx>
#include <XCAFDoc_ColorTool.hxx>
#include <XCAFDoc_DocumentTool.hxx>
#include <XCAFDoc_ShapeTool.hxx>

#include <algorithm>
#include <array>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <stdexcept>

#include "core/ascii.h"
#include "scene/cad_face.h"
#include "scene/occt_leaks.h"

namespace patchscan {
namespace {

// How many points along each shared edge the gap between its faces is measured at.
constexpr int kGapSamples = 9;
// Lines of the assembly tree kept for `info`; a larger tree ends with a count.
constexpr std::size_t kTreeLines = 200;
// Faces whose conversion failed named one by one in the warnings; the rest are counted.
constexpr int kNamedSkips = 5;
// The distance within which the sewing of an IGES part takes two faces' boundaries for one
// edge, in model units: Open CASCADE's default (BRepBuilderAPI_Sewing), which also sews
// boundaries lying apart within their own stated tolerances.
constexpr double kSewTolerance = 1e-6;

// Open CASCADE's default messenger prints to stdout: quiet while a file is read.
class QuietOcct {
 public:
  QuietOcct() : messenger_(Message::DefaultMessenger()), saved_(messenger_->Printers()) {
    messenger_->ChangePrinters().Clear();
  }
  ~QuietOcct() { messenger_->ChangePrinters() = saved_; }
  QuietOcct(const QuietOcct&) = delete;
  QuietOcct& operator=(const QuietOcct&) = delete;

 private:
  Handle(Message_Messenger) messenger_;
  Message_SequenceOfPrinters saved_;
};

// Open CASCADE's signal handlers for a scope (OSD::SetSignal), the process's own restored
// after it: a crash inside OCCT then unwinds to the nearest OCC_CATCH_SIGNALS as a
// Standard_Failure, and the program's handlers (an interrupt's, a sanitizer's) stay its own.
class OcctSignals {
 public:
  OcctSignals() {
    for (std::size_t k = 0; k < kSignals.size(); ++k) sigaction(kSignals[k], nullptr, &saved_[k]);
    OSD::SetSignal(OSD_SignalMode_Set, Standard_False);
  }
  ~OcctSignals() {
    for (std::size_t k = 0; k < kSignals.size(); ++k) sigaction(kSignals[k], &saved_[k], nullptr);
  }
  OcctSignals(const OcctSignals&) = delete;
  OcctSignals& operator=(const OcctSignals&) = delete;

 private:
  // The signals OSD::SetSignal sets on Linux.
  static constexpr std::array<int, 9> kSignals = {SIGHUP, SIGINT, SIGQUIT, SIGILL, SIGBUS, SIGSEGV, SIGSYS, SIGFPE, SIGTERM};
  std::array<struct sigaction, 9> saved_{};
};

// std::cout held back for a scope.
class HeldCout {
 public:
  HeldCout() : saved_(std::cout.rdbuf(held_.rdbuf())) {}
  ~HeldCout() { std::cout.rdbuf(saved_); }
  HeldCout(const HeldCout&) = delete;
  HeldCout& operator=(const HeldCout&) = delete;

 private:
  std::ostringstream held_;
  std::streambuf* saved_;
};

// A part as read, prepared once however many times it is placed.
struct Prototype {
  TopoDS_Shape shape;
  std::vector<std::pair<TopoDS_Shape, Vec3>> colouredParts;  // its faces and solids XDE colours
};

struct Instance {
  int prototype = 0;
  gp_Trsf placement;
  std::optional<Vec3> colour;  // the part's, else its instance's or assembly's
};

struct Model {
  std::vector<Prototype> prototypes;
  std::vector<Instance> instances;
  std::vector<std::string> tree;
  std::set<std::array<double, 3>> colours;
};

// The XDE document's assembly walked into prototypes and their placed instances.
class XdeWalk {
 public:
  XdeWalk(const Handle(TDocStd_Document)& doc, Model* model)
      : shapes_(XCAFDoc_DocumentTool::ShapeTool(doc->Main())), colours_(XCAFDoc_DocumentTool::ColorTool(doc->Main())),
        model_(model) {}

  void Run() {
    TDF_LabelSequence roots;
    shapes_->GetFreeShapes(roots);
    for (const TDF_Label& root : roots) Walk(root, gp_Trsf(), std::nullopt, 0);
  }

 private:
  std::optional<Vec3> ColourOf(const TDF_Label& label) {
    Quantity_Color c;
    if (!colours_->GetColor(label, XCAFDoc_ColorSurf, c) && !colours_->GetColor(label, XCAFDoc_ColorGen, c)) return std::nullopt;
    model_->colours.insert({c.Red(), c.Green(), c.Blue()});
    return Vec3(c.Red(), c.Green(), c.Blue());
  }

  static std::string NameOf(const TDF_Label& label) {
    Handle(TDataStd_Name) name;
    if (label.FindAttribute(TDataStd_Name::GetID(), name)) return TCollection_AsciiString(name->Get()).ToCString();
    TCollection_AsciiString entry;
    TDF_Tool::Entry(label, entry);
    return entry.ToCString();
  }

  void Line(int depth, const std::string& text) {
    if (model_->tree.size() < kTreeLines) model_->tree.push_back(std::string(static_cast<std::size_t>(2 * depth), ' ') + text);
    else ++treeLeftOut_;
  }

  void Walk(const TDF_Label& label, const gp_Trsf& placement, std::optional<Vec3> colour, int depth) {
    if (auto c = ColourOf(label)) colour = c;
    if (XCAFDoc_ShapeTool::IsReference(label)) {
      TDF_Label referred;
      if (!XCAFDoc_ShapeTool::GetReferredShape(label, referred)) return;
      Walk(referred, placement * XCAFDoc_ShapeTool::GetLocation(label).Transformation(), colour, depth);
      return;
    }
    if (XCAFDoc_ShapeTool::IsAssembly(label)) {
      Line(depth, NameOf(label) + " (assembly)");
      TDF_LabelSequence components;
      XCAFDoc_ShapeTool::GetComponents(label, components);
      for (const TDF_Label& c : components) Walk(c, placement, colour, depth + 1);
      return;
    }
    const TopoDS_Shape shape = XCAFDoc_ShapeTool::GetShape(label);
    if (shape.IsNull()) return;
    TCollection_AsciiString entry;
    TDF_Tool::Entry(label, entry);
    auto [at, fresh] = prototypeOf_.try_emplace(entry.ToCString(), static_cast<int>(model_->prototypes.size()));
    if (fresh) {
      Prototype p{shape, {}};
      TDF_LabelSequence subs;
      XCAFDoc_ShapeTool::GetSubShapes(label, subs);
      for (const TDF_Label& s : subs)
        if (auto c = ColourOf(s)) p.colouredParts.emplace_back(XCAFDoc_ShapeTool::GetShape(s), *c);
      model_->prototypes.push_back(std::move(p));
    }
    int faces = 0;
    for (TopExp_Explorer f(shape, TopAbs_FACE); f.More(); f.Next()) ++faces;
    Line(depth, NameOf(label) + " (part, " + std::to_string(faces) + " faces)");
    model_->instances.push_back(Instance{at->second, placement, colour});
  }

 public:
  std::size_t treeLeftOut_ = 0;

 private:
  Handle(XCAFDoc_ShapeTool) shapes_;
  Handle(XCAFDoc_ColorTool) colours_;
  Model* model_;
  std::map<std::string, int> prototypeOf_;
};

// IGES written face by face has no shared edges: each face comes with its own boundary.
// Sewing makes the boundaries two faces meet along one edge, as a STEP file's are, so that
// the scans end both faces at that edge's crossings (docs/cad.md). The part's coloured
// faces and solids are followed into the sewn shape. A part with shells (IGES written as
// B-rep solids) shares its edges already and is left as read.
void Sew(Prototype* p) {
  if (TopExp_Explorer(p->shape, TopAbs_SHELL).More()) return;
  BRepBuilderAPI_Sewing sewing(kSewTolerance);
  sewing.Add(p->shape);
  sewing.Perform();
  const TopoDS_Shape sewn = sewing.SewedShape();
  if (sewn.IsNull()) return;
  for (auto& [part, colour] : p->colouredParts)
    if (sewing.IsModifiedSubShape(part)) part = sewing.ModifiedSubShape(part);
  p->shape = sewn;
}

// The file read into a model; throws std::runtime_error saying why it cannot be.
Model ReadModel(const std::string& path, const std::string& ext) {
  Model model;
  if (ext == ".brep") {
    TopoDS_Shape shape;
    BRep_Builder builder;
    bool read = false;
    {
      HeldCout held;  // BRepTools::Read writes its complaints to std::cout itself
      // OCCT's .brep parser does not check its stream: a count past the end of a truncated
      // or damaged file loops on a failed stream (for hours, with a count of 10^9). A stream
      // that throws on its first failed read ends that; valid files never fail a read.
      std::ifstream in(path, std::ios::binary);
      in.exceptions(std::ios::failbit | std::ios::badbit);
      try {
        BRepTools::Read(shape, in, builder);
        read = true;
      } catch (const std::ios_base::failure&) {
        throw std::runtime_error("not a B-rep file Open CASCADE can read (a value is missing or malformed)");
      }
    }
    if (!read || shape.IsNull())
      throw std::runtime_error("not a B-rep file Open CASCADE can read");
    model.prototypes.push_back(Prototype{shape, {}});
    model.instances.push_back(Instance{0, gp_Trsf(), std::nullopt});
    model.tree.push_back(std::filesystem::path(path).filename().string() + " (part)");
    return model;
  }
  Handle(TDocStd_Document) doc;
  Handle(XCAFApp_Application) app = XCAFApp_Application::GetApplication();
  app->NewDocument("MDTV-XCAF", doc);
  const bool step = ext == ".step" || ext == ".stp";
  bool read = false;
  if (step) {
    STEPCAFControl_Reader reader;
    reader.SetColorMode(true), reader.SetNameMode(true), reader.SetLayerMode(false);
    if (reader.ReadFile(path.c_str()) != IFSelect_RetDone) throw std::runtime_error("not a STEP file Open CASCADE can read");
    read = reader.Transfer(doc);
  } else {
    IGESCAFControl_Reader reader;
    reader.SetColorMode(true), reader.SetNameMode(true), reader.SetLayerMode(false);
    if (reader.ReadFile(path.c_str()) != IFSelect_RetDone) throw std::runtime_error("not an IGES file Open CASCADE can read");
    read = reader.Transfer(doc);
  }
  if (!read) throw std::runtime_error("Open CASCADE could not translate its entities into shapes");
  XdeWalk walk(doc, &model);
  walk.Run();
  if (walk.treeLeftOut_) model.tree.push_back("... " + std::to_string(walk.treeLeftOut_) + " more");
  app->Close(doc);
  if (model.instances.empty())
    throw std::runtime_error(std::string("it holds no B-rep shape") + (step ? " (a tessellated-only STEP file?)" : ""));
  if (!step)
    for (Prototype& p : model.prototypes) Sew(&p);
  return model;
}

std::string KindName(GeomAbs_SurfaceType t) {
  switch (t) {
    case GeomAbs_Plane: return "plane";
    case GeomAbs_Cylinder: return "cylinder";
    case GeomAbs_Cone: return "cone";
    case GeomAbs_Sphere: return "sphere";
    case GeomAbs_Torus: return "torus";
    case GeomAbs_BezierSurface: return "Bezier";
    case GeomAbs_BSplineSurface: return "B-spline";
    case GeomAbs_SurfaceOfRevolution: return "revolution";
    case GeomAbs_SurfaceOfExtrusion: return "extrusion";
    case GeomAbs_OffsetSurface: return "offset";
    default: return "other";
  }
}

// One prototype's faces converted, each with its colour (none: the instance's) and number.
struct PreparedFace {
  CadFace face;
  std::optional<Vec3> colour;
  int number = 0;         // in the part's TopExp::MapShapes order, from 1
  bool original = false;  // number is the face's as read (NurbsConvert says which it was)
};

std::vector<PreparedFace> Prepare(const Prototype& p, bool asNurbs, SceneCad* cad, std::map<std::string, int>* kinds,
                                  std::vector<std::string>* warnings, const std::string& path) {
  TopTools_IndexedMapOfShape faces, edges, wires;
  TopExp::MapShapes(p.shape, TopAbs_FACE, faces);
  TopExp::MapShapes(p.shape, TopAbs_EDGE, edges);
  TopExp::MapShapes(p.shape, TopAbs_WIRE, wires);
  cad->faces += faces.Extent(), cad->edges += edges.Extent(), cad->wires += wires.Extent();
  for (int i = 1; i <= edges.Extent(); ++i)
    cad->largestTolerance = std::max(cad->largestTolerance, BRep_Tool::Tolerance(TopoDS::Edge(edges(i))));
  std::vector<std::optional<Vec3>> colour(static_cast<std::size_t>(faces.Extent()) + 1);
  auto coloured = p.colouredParts;  // solids first, so that a face's own colour wins
  std::stable_sort(coloured.begin(), coloured.end(), [](const auto& a, const auto& b) { return a.first.ShapeType() < b.first.ShapeType(); });
  for (const auto& [shape, c] : coloured)
    for (TopExp_Explorer f(shape, TopAbs_FACE); f.More(); f.Next())
      if (const int i = faces.FindIndex(f.Current()); i > 0) colour[static_cast<std::size_t>(i)] = c;
  for (int i = 1; i <= faces.Extent(); ++i) ++(*kinds)[KindName(BRepAdaptor_Surface(TopoDS::Face(faces(i)), false).GetType())];

  // Swept (extrusion, revolution) and offset surfaces made B-splines in their own parameters,
  // so that the pcurves stay as they are; the elementary and B-spline surfaces kept as read.
  // As NURBS: every surface a B-spline, its pcurves with it (BRepBuilderAPI_NurbsConvert).
  std::optional<BRepBuilderAPI_NurbsConvert> nurbs;
  std::optional<BRepTools_Modifier> swept;
  if (asNurbs) {
    nurbs.emplace(p.shape, Standard_True);
  } else {
    Handle(ShapeCustom_ConvertToBSpline) toBSpline = new ShapeCustom_ConvertToBSpline();
    toBSpline->SetExtrusionMode(Standard_True);
    toBSpline->SetRevolutionMode(Standard_True);
    toBSpline->SetOffsetMode(Standard_True);
    toBSpline->SetPlaneMode(Standard_False);
    swept.emplace(p.shape, toBSpline);
    if (!swept->IsDone()) throw std::runtime_error("Open CASCADE could not make its swept surfaces B-splines");
  }
  const auto modified = [&](const TopoDS_Shape& s) { return nurbs ? nurbs->ModifiedShape(s) : swept->ModifiedShape(s); };
  const TopoDS_Shape converted = modified(p.shape);
  NCollection_DataMap<TopoDS_Shape, int, TopTools_ShapeMapHasher> original;
  for (int i = 1; i <= faces.Extent(); ++i) original.Bind(modified(faces(i)), i);
  cad->largestGap = std::max(cad->largestGap, LargestEdgeGap(converted, kGapSamples));

  std::vector<PreparedFace> out;
  TopTools_IndexedMapOfShape seen;
  for (TopExp_Explorer f(converted, TopAbs_FACE); f.More(); f.Next()) {
    if (seen.Add(f.Current()) != seen.Extent()) continue;  // a face shared by two shells: once
    const int* number = original.Seek(f.Current());
    const int n = number ? *number : seen.Extent();
    try {
      PreparedFace pf{ConvertFace(TopoDS::Face(f.Current())), number ? colour[static_cast<std::size_t>(*number)] : std::nullopt, n,
                      number != nullptr};
      cad->largestJoint = std::max(cad->largestJoint, pf.face.largestGap);
      out.push_back(std::move(pf));
    } catch (const std::exception& e) {
      if (++cad->skipped <= kNamedSkips) warnings->push_back(path + ": face " + std::to_string(n) + " skipped: " + e.what());
    } catch (const Standard_Failure& e) {
      if (++cad->skipped <= kNamedSkips)
        warnings->push_back(path + ": face " + std::to_string(n) + " skipped: Open CASCADE: " + e.GetMessageString());
    }
  }
  return out;
}

// The model's instances as the scene's surfaces, one appearance per colour and side.
Scene Build(const Model& model, const std::string& path, bool asNurbs) {
  Scene scene;
  scene.source = path;
  SceneCad cad;
  std::map<std::string, int> kinds;
  std::vector<std::vector<PreparedFace>> prepared;
  for (const Prototype& p : model.prototypes) prepared.push_back(Prepare(p, asNurbs, &cad, &kinds, &scene.warnings, path));
  if (cad.skipped > kNamedSkips)
    scene.warnings.push_back(path + ": " + std::to_string(cad.skipped - kNamedSkips) + " more faces skipped");
  std::map<std::pair<std::array<double, 3>, bool>, std::uint32_t> appearanceOf;
  auto parts = std::make_shared<std::vector<TopoDS_Shape>>();
  for (const Prototype& p : model.prototypes) parts->push_back(p.shape);
  auto placed = std::make_shared<std::vector<CadPlacedPart>>();
  for (const Instance& inst : model.instances) {
    const Affine3 placement = AffineOf(inst.placement);
    const bool mirrored = inst.placement.IsNegative();
    placed->push_back(CadPlacedPart{static_cast<std::size_t>(inst.prototype), placement, {}});
    for (const PreparedFace& pf : prepared[static_cast<std::size_t>(inst.prototype)]) {
      if (pf.original && !pf.face.pieces.empty())
        placed->back().faces.emplace_back(pf.number, static_cast<std::uint32_t>(scene.surfaces.size()));
      Appearance a;
      if (const auto c = pf.colour ? pf.colour : inst.colour) a.colour = *c;
      a.reversed = pf.face.reversed != mirrored;
      const auto key = std::make_pair(std::array<double, 3>{a.colour.x(), a.colour.y(), a.colour.z()}, a.reversed);
      const auto [at, fresh] = appearanceOf.try_emplace(key, static_cast<std::uint32_t>(scene.appearances.size()));
      if (fresh) scene.appearances.push_back(a);
      scene.ReserveSurfaces(pf.face.pieces.size(), true);
      for (const Surface& piece : pf.face.pieces) {
        scene.surfaces.push_back(piece);
        scene.surfaces.back().worldFromObject = placement * pf.face.location * piece.worldFromObject;
        scene.sourceLines.push_back(pf.number);
        scene.sourceFiles.push_back(path);
        scene.appearanceOf.push_back(at->second);
      }
    }
  }
  cad.faceKinds.assign(kinds.begin(), kinds.end());
  cad.instances = static_cast<int>(model.instances.size());
  cad.colours = static_cast<int>(model.colours.size());
  cad.tree = model.tree;
  cad.mesh = [parts, placed](double deflection) { return MeshCad(*parts, *placed, deflection); };
  scene.cad = std::move(cad);
  return scene;
}

}  // namespace

std::variant<Scene, SourceError> ReadCad(const std::string& path, bool asNurbs) {
  if (!std::ifstream(path)) return SourceError{path, 0, "cannot open the file"};
  const std::string ext = AsciiLower(std::filesystem::path(path).extension().string());
  QuietOcct quiet;
  OcctSignals signals;
  try {
    OCC_CATCH_SIGNALS
    Scene scene = Build(ReadModel(path, ext), path, asNurbs);
    if (scene.surfaces.empty()) return SourceError{path, 0, "no face of the model could be converted"};
    return scene;
  } catch (const std::runtime_error& e) {
    return SourceError{path, 0, e.what()};
  } catch (const Standard_Failure& e) {
    return SourceError{path, 0, std::string("Open CASCADE failed reading it: ") + e.DynamicType()->Name() + ": " +
                                    e.GetMessageString()};
  }
}

}  // namespace patchscan
