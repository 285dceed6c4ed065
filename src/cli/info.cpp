#include "cli/info.h"

#include <algorithm>
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

}  // namespace

CLI::App* AddInfoCommand(CLI::App* app, InfoOptions* o) {
  CLI::App* cmd = app->add_subcommand(
      "info",
      "Describe a scene file: surface count, control points, world bounds, collapsed "
      "(degenerate) patch edges, the camera, and one line per surface with its bounds in "
      "world and screen space.");
  cmd->add_option("FILE", o->file, "scene file: .bpt, .rib or .obj")->required();
  AddCameraOptions(cmd, &o->camera);
  return cmd;
}

int RunInfo(const InfoOptions& o, std::ostream& out, std::ostream& err) {
  auto loaded = render::LoadSceneAndCamera(o.file, o.camera, err);
  if (const auto* failed = std::get_if<render::Failure>(&loaded)) return Fail(*failed, err);
  const Scene& scene = std::get<render::LoadedScene>(loaded).scene;
  const Camera& camera = std::get<render::LoadedScene>(loaded).view.camera;
  const bool framed = std::get<render::LoadedScene>(loaded).view.framed;

  // Step 1: scene totals.
  size_t nPatches = 0, nCollapsed = 0;
  std::set<std::tuple<double, double, double>> distinct;
  for (const Surface& s : scene.surfaces)
    if (const auto* b = std::get_if<BicubicPatch>(&s.shape)) {
      ++nPatches;
      nCollapsed += std::popcount(CollapsedEdges(*b));
      for (const Vec3& p : b->BezierPoints()) distinct.insert({p.x(), p.y(), p.z()});
    }
  out << "scene: " << scene.source << '\n'
      << "surfaces: " << scene.surfaces.size() << " (" << nPatches << (nPatches == 1 ? " bicubic patch)\n" : " bicubic patches)\n");
  if (nPatches > 0)
    out << "control points: " << 16 * nPatches << " (" << distinct.size() << " distinct)\n"
        << "collapsed edges: " << nCollapsed << '\n';
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
        << camera.fovDeg << ", hither " << camera.hither << (framed ? " (framed automatically)" : "")
        << '\n';
  }
  if (!scene.lights.empty() || !scene.appearances.empty())
    out << "lights: " << scene.lights.size() << ", materials: " << scene.appearances.size() << '\n';

  for (const SceneCage& c : scene.cages) {
    const SubdivCounts& n = c.counts;
    const char* scheme = c.scheme == SubdivScheme::Loop       ? "loop"
                         : c.scheme == SubdivScheme::Bilinear ? "bilinear"
                                                              : "catmull-clark";
    out << "subdivision cage: " << c.file << ':' << c.line << ", " << scheme << ", " << n.faces << " faces, "
        << n.vertices << " vertices, " << n.irregularFaces << " irregular faces, " << n.extraordinaryVertices
        << " extraordinary vertices; tags: " << n.creaseEdges << " crease edges, " << n.corners << " corners, "
        << n.holes << " holes; " << n.surfaces << " surfaces" << (n.textureCoords ? ", texture coordinates \"st\"" : "")
        << "; prepared on demand (" << n.boundedAtLoad << " faces bounded by Bfr at load)\n";
  }

  // Curves: their segments, each a ribbon facing the camera.
  if (const auto ribbons = std::count_if(scene.surfaces.begin(), scene.surfaces.end(),
                                         [](const Surface& s) { return std::holds_alternative<CurveRibbon>(s.shape); }))
    out << "curve segments: " << ribbons << " (ribbons facing the camera)\n";

  // Polygons: the requests, their corners and the triangles they became.
  if (!scene.polygons.empty()) {
    std::size_t corners = 0, triangles = 0;
    for (const ScenePolygons& p : scene.polygons) {
      corners += p.mesh.vertices.size();
      triangles += p.mesh.triangles.size();
    }
    out << "polygons: " << scene.polygons.size() << (scene.polygons.size() == 1 ? " request, " : " requests, ")
        << corners << " corners, " << triangles << " triangles (surface ids " << scene.surfaces.size() + 1 << " to "
        << scene.Ids() << ")\n";
  }

  // Trimmed NURBS pieces, with their trim loops and segments (one set per TrimCurve).
  std::set<const TrimLoops*> trims;
  std::size_t trimmed = 0;
  for (const Surface& s : scene.surfaces)
    if (const PieceTrim* t = TrimOf(s)) {
      ++trimmed;
      trims.insert(t->loops.get());
    }
  if (trimmed > 0) {
    std::size_t loops = 0, segments = 0;
    for (const TrimLoops* t : trims) {
      loops += static_cast<std::size_t>(t->Loops());
      segments += t->Segments().size();
    }
    out << "trimmed NURBS pieces: " << trimmed << ", by " << trims.size() << " trim curve sets of " << loops
        << " loops, " << segments << " Bézier segments\n";
  }

  // Step 2: one line per surface.
  out << "surface  line  kind             collapsed  world bounds | screen bounds (x, y px)\n";
  Bounds3 screenAll;
  bool behindEye = false;
  for (size_t i = 0; i < scene.surfaces.size(); ++i) {
    const Surface& s = scene.surfaces[i];
    const auto* b = std::get_if<BicubicPatch>(&s.shape);
    const auto screen = ScreenBounds(s, ScreenMap(camera, s.worldFromObject));
    std::string where = "reaches behind the eye";
    if (screen) {
      screenAll.Extend(*screen);
      where = "x " + Range(screen->lo.x(), screen->hi.x()) + "  y " +
              Range(screen->lo.y(), screen->hi.y());
    } else {
      behindEye = true;
    }
    out << std::setw(7) << i + 1 << std::setw(6) << scene.sourceLines[i] << "  " << std::left
        << std::setw(17) << Describe(s).substr(0, 16) << std::setw(11)
        << (b ? EdgeList(CollapsedEdges(*b)) : "-") << std::right << Box3(WorldBounds(s))
        << " | " << where << '\n';
  }
  if (!screenAll.Empty())
    out << "screen bounds: x " << Range(screenAll.lo.x(), screenAll.hi.x()) << "  y "
        << Range(screenAll.lo.y(), screenAll.hi.y())
        << (behindEye ? " (of the surfaces in front of the eye)" : "") << '\n';
  return kExitOk;
}

}  // namespace patchscan::cli
