#include "cli/info.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>
#include <bit>
#include <iomanip>
#include <ostream>
#include <set>
#include <sstream>
#include <tuple>

#include "cli/exit_codes.h"
#include "patch/screen.h"
#include "render/load.h"

namespace patchscan::cli {
namespace {

std::string Range(double lo, double hi) {
  std::ostringstream s;
  s << '[' << lo << ", " << hi << ']';
  return s.str();
}

std::string Box3(const Bounds3& b) {
  std::ostringstream s;
  for (int k = 0; k < 3; ++k) s << (k ? "  " : "") << "xyz"[k] << ' ' << Range(b.lo[k], b.hi[k]);
  return s.str();
}

std::string Point(const Vec3& p) {
  std::ostringstream s;
  s << p.x() << ',' << p.y() << ',' << p.z();
  return s.str();
}

std::string EdgeList(unsigned mask) {
  std::string s;
  for (PatchEdge e : {PatchEdge::U0, PatchEdge::U1, PatchEdge::V0, PatchEdge::V1})
    if (mask & (1u << static_cast<int>(e))) s += (s.empty() ? "" : " ") + std::string(EdgeName(e));
  return s.empty() ? "-" : s;
}

// What info reports of one surface.
struct SurfaceFacts {
  std::string file;  // the file that defines it
  int line = 0;
  std::string kind;  // the shape's whole description
  unsigned collapsed = 0;  // a bicubic patch's collapsed edges (PatchEdge bits)
  Bounds3 world;
  std::optional<Bounds3> screen;  // none: it reaches behind the eye
};

std::vector<SurfaceFacts> Facts(const Scene& scene, const Camera& camera) {
  std::vector<SurfaceFacts> facts;
  for (std::size_t i = 0; i < scene.surfaces.size(); ++i) {
    const Surface& s = scene.surfaces[i];
    SurfaceFacts f;
    f.file = i < scene.sourceFiles.size() ? scene.sourceFiles[i] : scene.source;
    f.line = scene.sourceLines[i];
    f.kind = Describe(s);
    if (const auto* b = std::get_if<BicubicPatch>(&s.shape)) f.collapsed = CollapsedEdges(*b);
    f.world = WorldBounds(s);
    f.screen = ScreenBounds(s, ScreenMap(camera, s.worldFromObject));
    facts.push_back(std::move(f));
  }
  return facts;
}

// The surfaces' screen bounds together (of those in front of the eye), and whether any
// reaches behind it.
std::pair<Bounds3, bool> ScreenTotal(const std::vector<SurfaceFacts>& facts) {
  Bounds3 all;
  bool behind = false;
  for (const SurfaceFacts& f : facts) {
    if (f.screen) all.Extend(*f.screen);
    behind = behind || !f.screen;
  }
  return {all, behind};
}

// JSON: a string quoted, a number (null where not finite), a vector and a box.
std::string Quoted(const std::string& text) {
  std::string q = "\"";
  for (const char ch : text) {
    if (ch == '"' || ch == '\\') q += '\\';
    if (static_cast<unsigned char>(ch) < 0x20) {
      char code[8];
      std::snprintf(code, sizeof code, "\\u%04x", ch);
      q += code;
    } else {
      q += ch;
    }
  }
  return q + '"';
}
std::string Num(double v) {
  if (!std::isfinite(v)) return "null";
  std::ostringstream s;
  s << std::setprecision(10) << v;
  return s.str();
}
std::string Vec(const Vec3& v) { return "[" + Num(v.x()) + ", " + Num(v.y()) + ", " + Num(v.z()) + "]"; }
std::string Box(const Bounds3& b) { return b.Empty() ? "null" : "{\"lo\": " + Vec(b.lo) + ", \"hi\": " + Vec(b.hi) + "}"; }
std::string Box2(const Bounds3& b) {
  return b.Empty() ? "null"
                   : "{\"x\": [" + Num(b.lo.x()) + ", " + Num(b.hi.x()) + "], \"y\": [" + Num(b.lo.y()) + ", " +
                         Num(b.hi.y()) + "]}";
}
std::string EdgeArray(unsigned mask) {
  std::string s;
  for (PatchEdge e : {PatchEdge::U0, PatchEdge::U1, PatchEdge::V0, PatchEdge::V1})
    if (mask & (1u << static_cast<int>(e))) s += (s.empty() ? "" : ", ") + Quoted(EdgeName(e));
  return "[" + s + "]";
}

const char* SchemeName(SubdivScheme scheme) {
  return scheme == SubdivScheme::Loop ? "loop" : scheme == SubdivScheme::Bilinear ? "bilinear" : "catmull-clark";
}

// The scene's totals: bicubic patches, their control points (distinct ones too) and
// collapsed edges; polygon corners and triangles; trimmed pieces, trim sets, loops, segments.
struct Totals {
  std::size_t patches = 0, controlPoints = 0, distinctPoints = 0, collapsed = 0, curves = 0;
  std::size_t corners = 0, triangles = 0;
  std::size_t trimmed = 0, trimSets = 0, loops = 0, segments = 0;
};

Totals Count(const Scene& scene) {
  Totals t;
  std::set<std::tuple<double, double, double>> distinct;
  std::set<const TrimLoops*> trims;
  for (const Surface& s : scene.surfaces) {
    if (const auto* b = std::get_if<BicubicPatch>(&s.shape)) {
      ++t.patches;
      t.collapsed += static_cast<std::size_t>(std::popcount(CollapsedEdges(*b)));
      for (const Vec3& p : b->BezierPoints()) distinct.insert({p.x(), p.y(), p.z()});
    }
    if (std::holds_alternative<CurveRibbon>(s.shape)) ++t.curves;
    if (const PieceTrim* trim = TrimOf(s)) {
      ++t.trimmed;
      trims.insert(trim->loops.get());
    }
  }
  t.controlPoints = 16 * t.patches;
  t.distinctPoints = distinct.size();
  for (const ScenePolygons& p : scene.polygons) {
    t.corners += p.mesh.vertices.size();
    t.triangles += p.mesh.triangles.size();
  }
  t.trimSets = trims.size();
  for (const TrimLoops* loops : trims) {
    t.loops += static_cast<std::size_t>(loops->Loops());
    t.segments += loops->Segments().size();
  }
  return t;
}

// A CAD file's facts (scene/cad_reader.h): its B-rep and how closely its faces meet.
void PrintCad(const SceneCad& c, std::ostream& out) {
  out << "CAD model: " << c.faces << " faces (";
  for (std::size_t k = 0; k < c.faceKinds.size(); ++k) out << (k ? ", " : "") << c.faceKinds[k].first << ' ' << c.faceKinds[k].second;
  out << "), " << c.edges << " edges, " << c.wires << " wires, " << c.instances << " placed parts, " << c.colours
      << " colours; " << c.skipped << " faces skipped\n"
      << "CAD tolerances (model units): largest edge tolerance " << c.largestTolerance << ", widest gap between faces "
      << "along an edge " << c.largestGap << ", widest joint in a wire " << c.largestJoint << '\n';
  out << "assembly:\n";
  for (const std::string& line : c.tree) out << "  " << line << '\n';
}

void PrintCadJson(const SceneCad& c, std::ostream& out) {
  out << ", \"cad\": {\"faces\": " << c.faces << ", \"face_kinds\": {";
  for (std::size_t k = 0; k < c.faceKinds.size(); ++k)
    out << (k ? ", " : "") << Quoted(c.faceKinds[k].first) << ": " << c.faceKinds[k].second;
  out << "}, \"edges\": " << c.edges << ", \"wires\": " << c.wires << ", \"instances\": " << c.instances
      << ", \"colours\": " << c.colours << ", \"skipped_faces\": " << c.skipped << ", \"largest_tolerance\": "
      << Num(c.largestTolerance) << ", \"largest_gap\": " << Num(c.largestGap) << ", \"largest_joint\": "
      << Num(c.largestJoint) << ", \"tree\": [";
  for (std::size_t k = 0; k < c.tree.size(); ++k) out << (k ? ", " : "") << Quoted(c.tree[k]);
  out << "]}";
}

void PrintJson(const Scene& scene, const render::LoadedScene& loaded, const std::vector<SurfaceFacts>& facts,
               std::ostream& out) {
  const Camera& camera = loaded.view.camera;
  const Totals t = Count(scene);
  out << "{\"scene\": " << Quoted(scene.source) << ", \"surfaces\": " << scene.surfaces.size()
      << ", \"bicubic_patches\": " << t.patches << ", \"control_points\": " << t.controlPoints
      << ", \"distinct_control_points\": " << t.distinctPoints << ", \"collapsed_edges\": " << t.collapsed
      << ", \"world_bounds\": " << Box(scene.WorldBounds());
  out << ", \"camera\": {\"width\": " << camera.width << ", \"height\": " << camera.height;
  if (camera.cameraFromWorld)
    out << ", \"from\": \"scene\", \"eye\": " << Vec(EyePoint(camera)) << ", \"forward\": " << Vec(ViewForward(camera))
        << ", \"right\": " << Vec(ViewRight(camera));
  else
    out << ", \"from\": " << (loaded.view.framed ? "\"framed\"" : "\"options\"") << ", \"eye\": " << Vec(camera.eye)
        << ", \"look_at\": " << Vec(camera.lookAt) << ", \"up\": " << Vec(camera.up);
  out << ", \"orthographic\": " << (camera.orthographic ? "true" : "false") << ", \"fov\": " << Num(camera.fovDeg)
      << ", \"hither\": " << Num(camera.hither) << "}";
  out << ", \"lights\": " << scene.lights.size() << ", \"materials\": " << scene.appearances.size() << ", \"cages\": [";
  for (std::size_t k = 0; k < scene.cages.size(); ++k) {
    const SceneCage& c = scene.cages[k];
    const SubdivCounts& n = c.counts;
    out << (k ? ", " : "") << "{\"file\": " << Quoted(c.file) << ", \"line\": " << c.line << ", \"scheme\": \""
        << SchemeName(c.scheme) << "\", \"faces\": " << n.faces << ", \"vertices\": " << n.vertices
        << ", \"irregular_faces\": " << n.irregularFaces << ", \"extraordinary_vertices\": " << n.extraordinaryVertices
        << ", \"crease_edges\": " << n.creaseEdges << ", \"corners\": " << n.corners << ", \"holes\": " << n.holes
        << ", \"surfaces\": " << n.surfaces << "}";
  }
  out << "], \"curve_segments\": " << t.curves << ", \"polygons\": {\"requests\": " << scene.polygons.size()
      << ", \"corners\": " << t.corners << ", \"triangles\": " << t.triangles << "}, \"trimmed_pieces\": " << t.trimmed
      << ", \"trim_sets\": " << t.trimSets << ", \"trim_loops\": " << t.loops << ", \"trim_segments\": " << t.segments;
  if (scene.cad) PrintCadJson(*scene.cad, out);
  out << ", \"surface_list\": [";
  for (std::size_t i = 0; i < facts.size(); ++i) {
    const SurfaceFacts& f = facts[i];
    out << (i ? ",\n  " : "\n  ") << "{\"surface\": " << i + 1 << ", \"file\": " << Quoted(f.file)
        << ", \"line\": " << f.line << ", \"kind\": " << Quoted(f.kind) << ", \"collapsed_edges\": " << EdgeArray(f.collapsed)
        << ", \"world_bounds\": " << Box(f.world) << ", \"screen_bounds\": " << (f.screen ? Box2(*f.screen) : "null")
        << "}";
  }
  const auto [all, behind] = ScreenTotal(facts);
  out << "],\n \"screen_bounds\": " << Box2(all) << ", \"behind_eye\": " << (behind ? "true" : "false") << "}\n";
}

}  // namespace

CLI::App* AddInfoCommand(CLI::App* app, InfoOptions* o) {
  CLI::App* cmd = app->add_subcommand(
      "info",
      "Describe a scene file: surface count, control points, world bounds, collapsed "
      "(degenerate) patch edges, the camera, and one line per surface with the file and line "
      "that define it (the archive's, for a surface read from one; a CAD file's face number), "
      "its bounds in world and screen space and its kind. A CAD file's faces by surface type, "
      "edges, wires, colours, assembly tree, largest edge tolerance and the widest gap "
      "measured between two faces along an edge.");
  cmd->add_option("FILE", o->file, "scene file: .bpt, .rib, .obj, .step, .stp, .iges, .igs or .brep")->type_name("FILE")->required();
  cmd->add_flag("--json", o->json,
                "print the same facts as one JSON object (each surface with its file, line, kind, collapsed "
                "edges and bounds; the camera; the cages, curves, polygons and trims) instead of text");
  AddCameraOptions(cmd, &o->camera);
  return cmd;
}

int RunInfo(const InfoOptions& o, std::ostream& out, std::ostream& err) {
  auto loaded = render::LoadSceneAndCamera(o.file, o.camera, err);
  if (const auto* failed = std::get_if<render::Failure>(&loaded)) return Fail(*failed, err);
  const render::LoadedScene& ls = std::get<render::LoadedScene>(loaded);
  const Scene& scene = ls.scene;
  const Camera& camera = ls.view.camera;
  const std::vector<SurfaceFacts> facts = Facts(scene, camera);
  if (o.json) {
    PrintJson(scene, ls, facts, out);
    return kExitOk;
  }

  // Step 1: scene totals.
  const Totals t = Count(scene);
  out << "scene: " << scene.source << '\n'
      << "surfaces: " << scene.surfaces.size() << " (" << t.patches << (t.patches == 1 ? " bicubic patch)\n" : " bicubic patches)\n");
  if (t.patches > 0)
    out << "control points: " << t.controlPoints << " (" << t.distinctPoints << " distinct)\n"
        << "collapsed edges: " << t.collapsed << '\n';
  out << "world bounds: " << Box3(scene.WorldBounds()) << '\n';
  if (camera.cameraFromWorld) {
    out << "camera: " << camera.width << 'x' << camera.height << ", eye " << Point(EyePoint(camera))
        << ", forward " << Point(ViewForward(camera)) << ", right " << Point(ViewRight(camera));
    if (camera.orthographic)
      out << ", orthographic";
    else
      out << ", fov " << camera.fovDeg;
    out << ", hither " << camera.hither << " (the scene's)\n";
  } else {
    out << "camera: " << camera.width << 'x' << camera.height << ", eye " << Point(camera.eye)
        << ", look-at " << Point(camera.lookAt) << ", up " << Point(camera.up) << ", fov "
        << camera.fovDeg << ", hither " << camera.hither << (ls.view.framed ? " (framed automatically)" : "")
        << '\n';
  }
  if (!scene.lights.empty() || !scene.appearances.empty())
    out << "lights: " << scene.lights.size() << ", materials: " << scene.appearances.size() << '\n';
  for (const SceneCage& c : scene.cages) {
    const SubdivCounts& n = c.counts;
    out << "subdivision cage: " << c.file << ':' << c.line << ", " << SchemeName(c.scheme) << ", " << n.faces << " faces, "
        << n.vertices << " vertices, " << n.irregularFaces << " irregular faces, " << n.extraordinaryVertices
        << " extraordinary vertices; tags: " << n.creaseEdges << " crease edges, " << n.corners << " corners, "
        << n.holes << " holes; " << n.surfaces << " surfaces" << (n.textureCoords ? ", texture coordinates \"st\"" : "")
        << "; prepared on demand (" << n.boundedAtLoad << " faces bounded by Bfr at load)\n";
  }
  // Curves: their segments, each a ribbon facing the camera.
  if (t.curves > 0) out << "curve segments: " << t.curves << " (ribbons facing the camera)\n";
  if (!scene.polygons.empty())
    out << "polygons: " << scene.polygons.size() << (scene.polygons.size() == 1 ? " request, " : " requests, ")
        << t.corners << " corners, " << t.triangles << " triangles (surface ids " << scene.surfaces.size() + 1 << " to "
        << scene.Ids() << ")\n";
  if (t.trimmed > 0)
    out << "trimmed surfaces: " << t.trimmed << ", by " << t.trimSets << " trim curve sets of " << t.loops
        << " loops, " << t.segments << " Bézier segments\n";
  if (scene.cad) PrintCad(*scene.cad, out);

  // Step 2: one line per surface: where it is defined (the line, with the file when it is
  // not the scene's own: an archive; a CAD file's face number), its bounds, and its kind,
  // whole, last.
  std::vector<std::string> where;
  std::size_t wide = 4;
  for (const SurfaceFacts& f : facts) {
    where.push_back((f.file == scene.source ? std::string() : f.file + ':') + std::to_string(f.line));
    wide = std::max(wide, where.back().size());
  }
  out << "surface  " << std::left << std::setw(static_cast<int>(wide)) << (scene.cad ? "face" : "line") << std::right
      << "  collapsed  world bounds | screen bounds (x, y px) | kind\n";
  for (std::size_t i = 0; i < facts.size(); ++i) {
    const SurfaceFacts& f = facts[i];
    const std::string screen =
        f.screen ? "x " + Range(f.screen->lo.x(), f.screen->hi.x()) + "  y " + Range(f.screen->lo.y(), f.screen->hi.y())
                 : "reaches behind the eye";
    out << std::setw(7) << i + 1 << "  " << std::left << std::setw(static_cast<int>(wide)) << where[i] << "  "
        << std::setw(11) << EdgeList(f.collapsed) << std::right << Box3(f.world) << " | " << screen << " | " << f.kind
        << '\n';
  }
  const auto [all, behind] = ScreenTotal(facts);
  if (!all.Empty())
    out << "screen bounds: x " << Range(all.lo.x(), all.hi.x()) << "  y " << Range(all.lo.y(), all.hi.y())
        << (behind ? " (of the surfaces in front of the eye)" : "") << '\n';
  return kExitOk;
}

}  // namespace patchscan::cli
