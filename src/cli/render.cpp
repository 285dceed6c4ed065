#include "cli/render.h"

#include <Eigen/Geometry>
#include <sys/resource.h>
#include <unistd.h>

#include <csignal>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <map>
#include <ostream>

#include "cli/exit_codes.h"
#include "patch/tessellate.h"
#include "raster/image_writer.h"
#include "raster/scanline_renderer.h"
#include "raster/texture.h"
#include "xscan/exact_scan.h"
#include "xscan/overlay.h"
#include "xscan/tess_feed.h"

namespace patchscan::cli {
namespace {

// Peak resident memory of this process so far, in KiB.
long PeakResidentKiB() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return u.ru_maxrss;
}

// Set by SIGINT and SIGTERM during a render; the row sink below stops the render at the
// next row, and the unfinished image's temporary file is removed.
volatile std::sig_atomic_t gInterrupted = 0;
extern "C" void OnInterrupt(int) { gInterrupted = 1; }

void CatchInterrupts() {
  struct sigaction action {};
  action.sa_handler = OnInterrupt;
  sigemptyset(&action.sa_mask);
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
}

// Passes rows on (none once interrupted), timing how long the next sink (the image writer) takes, and when stderr
// is a terminal shows the percentage done, at most a few times a second.
class ProgressSink final : public raster::RowSink {
 public:
  ProgressSink(raster::RowSink& next, int height, std::ostream& err)
      : next_(next), height_(height), err_(err), show_(isatty(STDERR_FILENO) != 0) {}
  ~ProgressSink() override {
    if (shown_) err_ << "\r              \r" << std::flush;
  }
  bool WriteRow(int y, const float* pixels) override {
    if (gInterrupted) return false;
    if (show_) {
      const auto now = std::chrono::steady_clock::now();
      if (now - last_ > std::chrono::milliseconds(250)) {
        last_ = now;
        shown_ = true;
        err_ << "\rrender: " << (100 * (y + 1)) / height_ << "%" << std::flush;
      }
    }
    const auto t0 = std::chrono::steady_clock::now();
    const bool ok = next_.WriteRow(y, pixels);
    outputSeconds_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return ok;
  }
  double OutputSeconds() const { return outputSeconds_; }

 private:
  raster::RowSink& next_;
  int height_;
  std::ostream& err_;
  bool show_, shown_ = false;
  double outputSeconds_ = 0.0;
  std::chrono::steady_clock::time_point last_ = std::chrono::steady_clock::now();
};

// RenderMan light sources as the back end's lights: ambient lights sum into the rig's
// ambient light; the others keep their colour (intensity times lightcolor).
raster::LightRig SceneLights(const std::vector<SceneLight>& lights) {
  raster::LightRig rig;
  rig.ambient = raster::Rgb::Zero();
  for (const SceneLight& l : lights) {
    raster::Light out;
    out.intensity = l.colour;
    switch (l.kind) {
      case SceneLight::Kind::Ambient:
        rig.ambient += l.colour;
        continue;
      case SceneLight::Kind::Distant:
        out.kind = raster::Light::Kind::Directional;
        out.vector = (l.to - l.from).normalized();
        break;
      case SceneLight::Kind::Point:
        out.kind = raster::Light::Kind::Point;
        out.vector = l.from;
        out.inverseSquare = true;
        break;
      case SceneLight::Kind::Spot:
        out.kind = raster::Light::Kind::Spot;
        out.vector = l.from;
        out.inverseSquare = true;
        out.axis = (l.to - l.from).normalized();
        out.cosOutside = std::cos(l.coneAngle);
        out.cosInside = std::cos(std::max(0.0, l.coneAngle - l.coneDelta));
        out.beamDistribution = l.beamDistribution;
        break;
    }
    rig.lights.push_back(out);
  }
  return rig;
}

// A scene file's appearance as a back-end material. The default shader keeps the
// renderer's material, tinted by the colour.
raster::Material SceneMaterial(const Appearance& a, const raster::Material& fallback) {
  using S = Appearance::Shader;
  using M = raster::Material::Model;
  raster::Material m = fallback;
  m.opacity = a.opacity.mean();
  m.twoSided = a.twoSided;
  m.reversed = a.reversed;
  if (a.shader == S::Default) {
    m.colour = fallback.colour.cwiseProduct(a.colour);
    return m;
  }
  m.model = a.shader == S::Constant ? M::Constant
            : a.shader == S::Matte  ? M::Matte
            : a.shader == S::Metal  ? M::Metal
                                    : M::Plastic;
  m.colour = a.colour;
  m.emission = raster::Rgb::Zero();
  m.ka = a.ka;
  m.kd = a.kd;
  m.ks = a.ks;
  m.roughness = a.roughness;
  m.specularColour = a.specularColour;
  return m;
}

}  // namespace

CLI::App* AddRenderCommand(CLI::App* app, RenderOptions* o) {
  CLI::App* cmd = app->add_subcommand(
      "render",
      "Render a scene file to an image. The format follows the output's extension: .png, "
      ".tif/.tiff, .jpg/.jpeg (no alpha) or .exr; alpha is coverage. The image is written to "
      "a temporary file and renamed into place, so a failed render leaves no file.");
  cmd->add_option("FILE", o->file, "scene file: .bpt (Bézier patches) or .rib (RenderMan scene)")->required();
  cmd->add_option("-o,--output", o->output,
                  "output image file (default: a RIB scene's Display file name; required otherwise)");
  cmd->add_option("--mode", o->mode,
                  "how surfaces become samples: exact = Blinn's scan-line algorithm, every "
                  "visible sample's (u,v) found by Newton iteration (shading always uses the "
                  "exact normal; --shading flat/gouraud and --hidden-line need triangles); "
                  "theta = the same Y scan, with each cross-section sampled at --theta-steps "
                  "angles of its normal per turn and the samples between interpolated along the "
                  "chords; tess = tessellated with OpenSubdiv's Bfr::Tessellation pattern")
      ->check(CLI::IsMember({"exact", "theta", "tess"}))
      ->capture_default_str();
  cmd->add_option("--theta-steps", o->thetaSteps,
                  "theta mode: tabulated normal angles per turn of a cross-section (chord error "
                  "R (1 - cos(pi/N)) pixels for a section of radius R pixels)")
      ->check(CLI::Range(1, 4096))
      ->capture_default_str();
  cmd->add_option("--y-step", o->yStep,
                  "theta mode: pixels between the scan lines whose cross-sections are sampled "
                  "(rounded to a whole number of sample rows, at least one); the surface between "
                  "two such lines goes to the back end as one slab of triangles, and where the "
                  "chains of two lines do not pair up (a curve born or gone, an event of the Y "
                  "scan) every sample row between them is sampled instead. Silhouettes between "
                  "the lines are chords: error about h^2 / (8 R) pixels for step h and a "
                  "silhouette curving with radius R pixels. 0: every sample row is sampled and "
                  "no triangles are made")
      ->check(CLI::Range(0.0, 64.0))
      ->capture_default_str();
  cmd->add_flag("--no-extrapolate", o->noExtrapolate,
                "exact mode: start each tracker's Newton iteration from its last position "
                "instead of extrapolating from its last two (to measure what extrapolation saves)");
  cmd->add_option("--overlay", o->overlay,
                  "exact mode: trackers = draw what the scan did over the image: each tracker's "
                  "path as dots (boundary-edge trackers blue, silhouette trackers red) and each "
                  "event as a ring (maximum passed yellow, saddle magenta, fold green, "
                  "silhouette tracker born pink, tracker died black, crossing repaired by the "
                  "x scan orange, walk or sample given up cyan)")
      ->check(CLI::IsMember({"none", "trackers"}))
      ->capture_default_str();
  cmd->add_option("--tess-rate", o->tessRate, "tessellation segments per patch edge (uniform)")
      ->check(CLI::Range(1, kMaxTessRate))
      ->capture_default_str();
  cmd->add_option("--tess-pixels", o->tessPixels,
                  "screen-adaptive tessellation: per-edge rates making edges about this many "
                  "pixels long (equal on shared edges), instead of --tess-rate")
      ->check(CLI::Range(0.01, 1e6));
  cmd->add_option("--aa", o->aa,
                  "supersampling: an l x l grid of samples per pixel whose edge samples are "
                  "shared with the neighbours (1: one sample at the pixel centre; default: a RIB "
                  "scene's PixelSamples, else 3)")
      ->check(CLI::Range(1, raster::kMaxAa));
  cmd->add_option("--shading", o->shading, "flat, gouraud or phong")
      ->check(CLI::IsMember({"flat", "gouraud", "phong"}))
      ->capture_default_str();
  cmd->add_option("--texture", o->texture,
                  "none; checker, a procedural 8x8 uv checker; or an image file read through "
                  "OpenImageIO's TextureSystem (mipmapped, opened only when a visible sample "
                  "needs it; 'maketx' makes mipmapped files)")
      ->capture_default_str();
  cmd->add_flag("--cull-backfaces", o->cullBackFaces,
                "drop triangles facing away from the eye (default: two-sided)");
  cmd->add_option("--opacity", o->opacity,
                  "opacity of every surface; below 1, linear transparency: each sample blends "
                  "its 4 nearest surfaces front to back")
      ->check(CLI::Range(1e-3, 1.0))
      ->capture_default_str();
  cmd->add_flag("--hidden-line", o->hiddenLine,
                "hidden-line mode: visible surfaces in white with their triangle edges in black, "
                "unshaded");
  cmd->add_flag("--aov", o->aov,
                "also write the channels Z (eye distance), N.x N.y N.z (world normal), u v and id "
                "(surface index) of the surface covering most of each pixel; .exr only");
  cmd->add_option("--seed", o->seed,
                  "seed of the stochastic extra shading calls (same seed, same image)")
      ->capture_default_str();
  cmd->add_flag("--stats", o->stats, "print counts, times and peak memory to stderr");
  cmd->add_option("--stats-json", o->statsJson, "write counts and times as JSON to this file");
  AddCameraOptions(cmd, &o->camera);
  return cmd;
}

int RunRender(const RenderOptions& o, std::ostream& err) {
  using Clock = std::chrono::steady_clock;
  const auto t0 = Clock::now();
  CatchInterrupts();
  auto loaded = LoadSceneAndCamera(o.file, o.camera, err);
  if (const int* code = std::get_if<int>(&loaded)) return *code;
  const Scene& scene = std::get<LoadedScene>(loaded).scene;
  const Camera& camera = std::get<LoadedScene>(loaded).view.camera;
  const auto tLoaded = Clock::now();
  const std::string output = !o.output.empty() ? o.output : scene.image.displayName;
  if (output.empty()) {
    err << "patchscan: no output image: give -o IMAGE" << (scene.image.cameraFromWorld ? " (the scene has no Display file)" : "") << '\n';
    return kExitUsage;
  }
  const int aa = o.aa.value_or(scene.image.pixelSamples.value_or(kDefaultAa));

  // Both direct modes run Blinn's Y scan; they differ in the X scan.
  const bool exact = o.mode == "exact" || o.mode == "theta";
  if (exact && (o.shading != "phong" || o.hiddenLine)) {
    err << "patchscan: --mode " << o.mode << " shades every sample with its own normal: --shading "
           "flat/gouraud and --hidden-line need a triangle mode (--mode tess)\n";
    return kExitUsage;
  }
  if (!exact && o.overlay != "none") {
    err << "patchscan: --overlay trackers draws the Y scan's trackers: it needs --mode exact or theta\n";
    return kExitUsage;
  }

  // Step 1: tessellate and feed the back end, or set up the exact scan.
  TessMesh tess;
  raster::TriangleMesh mesh;
  std::unique_ptr<ExactScan> scan;
  if (exact) {
    ExactScanOptions xo;
    xo.extrapolate = !o.noExtrapolate;
    if (o.mode == "theta") {
      xo.thetaSteps = o.thetaSteps;
      // Sample rows are 1 / (aa - 1) pixels apart (aa 1: one per pixel).
      const double spacing = aa == 1 ? 1.0 : 1.0 / (aa - 1);
      xo.slabRows = o.yStep > 0.0 ? std::max(1, static_cast<int>(std::lround(o.yStep / spacing))) : 0;
    }
    scan = std::make_unique<ExactScan>(scene.surfaces, camera, xo);
  } else {
    for (size_t k = 0; k < scene.surfaces.size(); ++k) {
      if (gInterrupted) {
        err << "patchscan: interrupted; no image written\n";
        return kExitInterrupted;
      }
      if (o.tessPixels > 0)
        TessellateToScreen(scene.surfaces[k], camera, o.tessPixels, static_cast<std::uint32_t>(k), &tess);
      else
        TessellateUniform(scene.surfaces[k], o.tessRate, static_cast<std::uint32_t>(k), &tess);
    }
    WeldBoundaryVertices(&tess, kWeldRelTol * scene.WorldBounds().Diagonal().norm());
    mesh = ToRasterMesh(tess, camera);
  }
  const auto t1 = Clock::now();

  // Step 2: render, streaming rows to the image.
  raster::RenderSettings s;
  s.width = camera.width;
  s.height = camera.height;
  s.aa = aa;
  s.shading = o.shading == "flat"      ? raster::ShadingMode::Flat
              : o.shading == "gouraud" ? raster::ShadingMode::Gouraud
                                       : raster::ShadingMode::Phong;
  s.cullBackFaces = o.cullBackFaces;
  s.hiddenLine = o.hiddenLine;
  s.opacity = o.opacity;
  s.seed = o.seed;
  s.hither = camera.hither;
  s.eye = EyePoint(camera);
  s.orthographic = camera.orthographic;
  s.forward = ViewForward(camera);
  std::unique_ptr<raster::ImageTexture> texture;
  if (o.texture == "checker") {
    s.material.checkerSquares = 8;
  } else if (o.texture != "none") {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(o.texture, ec)) {
      err << "patchscan: --texture: no such file '" << o.texture << "'\n";
      return kExitUsage;
    }
    texture = std::make_unique<raster::ImageTexture>(o.texture);
    s.material.texture = texture.get();
  }
  const Vec3 forward = ViewForward(camera), right = ViewRight(camera);
  s.lights = scene.lights.empty() ? raster::DefaultLightRig(forward, right.cross(forward), right)
                                  : SceneLights(scene.lights);
  // The scene's own materials, each texture opened only when a visible sample needs it.
  std::map<std::string, std::unique_ptr<raster::ImageTexture>> sceneTextures;
  for (const Appearance& a : scene.appearances) {
    raster::Material m = SceneMaterial(a, s.material);
    if (!a.textureName.empty()) {
      std::error_code ec;
      if (!std::filesystem::is_regular_file(a.textureName, ec)) {
        err << "patchscan: " << scene.source << ": paintedplastic texture '" << a.textureName << "' not found\n";
        return kExitInputError;
      }
      auto& t = sceneTextures[a.textureName];
      if (!t) t = std::make_unique<raster::ImageTexture>(a.textureName);
      m.texture = t.get();
    }
    s.materials.push_back(m);
  }
  s.materialOf = scene.appearanceOf;

  auto opened = raster::ImageWriter::Open(output, camera.width, camera.height, o.aov);
  if (auto* why = std::get_if<std::string>(&opened)) {
    err << "patchscan: " << *why << '\n';
    return kExitUsage;
  }
  auto& writer = *std::get<std::unique_ptr<raster::ImageWriter>>(opened);
  std::unique_ptr<TrackerOverlay> overlay;
  raster::RowSink* out = &writer;
  if (o.overlay == "trackers") {
    overlay = std::make_unique<TrackerOverlay>(writer, camera.width, camera.height);
    scan->SetTrace(overlay.get());
    out = overlay.get();
  }
  ProgressSink progress(*out, camera.height, err);
  auto stats = exact ? raster::RenderFragments(*scan, s, progress) : raster::RenderMesh(mesh, s, progress);
  if (stats && overlay && !overlay->Finish()) stats.reset();
  if (!stats) {
    if (gInterrupted) {
      err << "\npatchscan: interrupted; no image written\n";
      return kExitInterrupted;
    }
    if (texture && !texture->Error().empty()) {
      err << "patchscan: " << texture->Error() << '\n';
      return kExitInputError;
    }
    for (const auto& [name, t] : sceneTextures)
      if (!t->Error().empty()) {
        err << "patchscan: " << t->Error() << '\n';
        return kExitInputError;
      }
    err << "patchscan: " << output << ": writing the image failed\n";
    return kExitOutputError;
  }
  const auto tCommit = Clock::now();
  if (auto committed = writer.Commit(); auto* why = std::get_if<std::string>(&committed)) {
    err << "patchscan: " << *why << '\n';
    return kExitOutputError;
  }
  const auto t2 = Clock::now();
  // Encoding and writing the image, inside the render's time.
  const double outputSec = progress.OutputSeconds() + std::chrono::duration<double>(t2 - tCommit).count();

  // Step 3: statistics.
  const double loadSec = std::chrono::duration<double>(tLoaded - t0).count();
  const double tessSec = std::chrono::duration<double>(t1 - tLoaded).count();
  const double renderSec = std::chrono::duration<double>(t2 - t1).count();
  const long peakKiB = PeakResidentKiB();
  const ExactScanStats xs = exact ? scan->Stats() : ExactScanStats{};
  // Newton iterations per tracker per scan line (paper 001 §3.5 reports ~2.5 without
  // extrapolation, under 1 with): edge and silhouette trackers together.
  const double itersPerTracker =
      xs.nTrackerSteps > 0 ? static_cast<double>(xs.edges.nNewtonIterations + xs.silhouettes.nNewtonIterations) /
                                   static_cast<double>(xs.nTrackerSteps)
                             : 0.0;
  if (o.stats) {
    if (exact)
      err << "surfaces: " << xs.nSurfaces << " (set up " << xs.nSurfacesActivated
          << ", most active at once " << xs.maxActiveSurfaces << "), maxima and saddles "
          << xs.nStationary << "\nsample rows: " << xs.nRows << ", fragments " << xs.nFragments
          << "\ntrackers: " << xs.nTrackerSteps << " tracker-rows, Newton iterations per tracker "
          << "per row " << itersPerTracker << " (edges " << xs.edges.nNewtonIterations
          << ", silhouettes " << xs.silhouettes.nNewtonIterations << ")\nevents: edge trackers "
          << xs.edges.nCreated << " born, " << xs.edges.nDeleted << " died, " << xs.edges.nFolds
          << " folds; silhouette trackers born at maxima " << xs.silhouettes.nCreatedAtMaxima
          << ", folds " << xs.silhouettes.nCreatedAtFolds << ", saddles "
          << xs.silhouettes.nCreatedAtSaddles << ", died " << xs.silhouettes.nDeletedFailed
          << ", left " << xs.silhouettes.nDeletedLeft << "\nx scan: " << xs.walk.nWalks
          << " walks (" << xs.walk.nClosedWalks << " closed), " << xs.walk.nColumnSteps
          << " column steps, " << xs.walk.nArcSteps << " arc steps, " << xs.walk.nSilhouettes
          << " silhouette points, Newton " << xs.walk.nNewtonCalls << " calls / "
          << xs.walk.nNewtonIterations << " iterations\nrepairs: " << xs.edges.nRepairs
          << " edge-tracker bisections, " << xs.walk.nUntrackedSilhouettes
          << " silhouettes and " << xs.walk.nUntrackedExits
          << " boundary exits found by the x scan without a tracker; " << xs.silhouettes.nRepairSearches
          << " subdivision searches after unexplained events, finding " << xs.silhouettes.nRepaired
          << " lost crossings; failures "
          << xs.walk.nFailures << '\n';
    if (o.mode == "theta")
      err << "theta chains: " << xs.theta.nChains << ", vertices " << xs.theta.nVertices << ", crawl steps "
          << xs.theta.nSteps << ", turn points " << xs.theta.nTurnPoints << ", tilt vertices " << xs.theta.nTilts
          << "\ntheta trackers: " << xs.theta.nTrackers << " advanced from the line before, Newton iterations per tracker "
          << (xs.theta.nTrackers ? static_cast<double>(xs.theta.nTrackerIterations) / static_cast<double>(xs.theta.nTrackers) : 0.0)
          << ", " << xs.theta.nTrackerFailures << " lost; " << xs.theta.nTurnTrackers << " turn points advanced, "
          << "Newton iterations per turn point "
          << (xs.theta.nTurnTrackers ? static_cast<double>(xs.theta.nTurnIterations) / static_cast<double>(xs.theta.nTurnTrackers) : 0.0)
          << ", " << xs.theta.nTurnFailures << " lost; " << xs.theta.nLinkRepairs << " links repaired sideways, "
          << xs.theta.nLineRepairs << " lines crawled afresh\nslabs: " << xs.nSlabIntervals
          << " intervals as slabs (" << xs.nSlabTriangles << " triangles, " << stats->nTrianglesSetUp
          << " set up), " << xs.nRowIntervals << " row by row\n";
    else
      err << "triangles n: " << stats->nTriangles << " (set up " << stats->nTrianglesSetUp
          << ")\nmost active on one sample row m: " << stats->maxActive << '\n';
    err << "samples tested: " << stats->nSamplesTested << "\nsamples covered: "
        << stats->nSamplesCovered << "\nshading calls: " << stats->nShadingCalls << " (+"
        << stats->nExtraShadingCalls << " adaptive-stochastic, " << stats->nSuperSampledPixels
        << " pixels super-sampled)\ntime: load " << loadSec << " s, " << (exact ? "set up " : "tessellate ")
        << tessSec << " s, render " << renderSec << " s (of which writing the image " << outputSec
        << " s)\npeak memory: " << peakKiB << " KiB\n"
        << "texture: " << (texture ? (texture->Opened() ? "opened" : "never needed") : "none")
        << (texture ? ", " + std::to_string(texture->Lookups()) + " lookups" : std::string()) << '\n';
  }
  if (!o.statsJson.empty()) {
    std::ofstream js(o.statsJson);
    js << "{\"mode\": \"" << o.mode << "\", \"triangles\": " << stats->nTriangles << ", \"triangles_set_up\": "
       << stats->nTrianglesSetUp << ", \"max_active\": " << stats->maxActive
       << ", \"samples_tested\": " << stats->nSamplesTested << ", \"samples_covered\": "
       << stats->nSamplesCovered << ", \"shading_calls\": " << stats->nShadingCalls
       << ", \"extra_shading_calls\": " << stats->nExtraShadingCalls
       << ", \"super_sampled_pixels\": " << stats->nSuperSampledPixels
       << ", \"exact\": {\"surfaces_set_up\": " << xs.nSurfacesActivated
       << ", \"max_active_surfaces\": " << xs.maxActiveSurfaces << ", \"stationary_points\": " << xs.nStationary
       << ", \"sample_rows\": " << xs.nRows << ", \"fragments\": " << xs.nFragments
       << ", \"tracker_rows\": " << xs.nTrackerSteps << ", \"newton_iterations_per_tracker_row\": " << itersPerTracker
       << ", \"edge_newton_iterations\": " << xs.edges.nNewtonIterations
       << ", \"silhouette_newton_iterations\": " << xs.silhouettes.nNewtonIterations
       << ", \"edge_repairs\": " << xs.edges.nRepairs << ", \"folds\": " << xs.edges.nFolds
       << ", \"silhouettes_born_at_maxima\": " << xs.silhouettes.nCreatedAtMaxima
       << ", \"silhouettes_born_at_folds\": " << xs.silhouettes.nCreatedAtFolds
       << ", \"silhouettes_born_at_saddles\": " << xs.silhouettes.nCreatedAtSaddles
       << ", \"walks\": " << xs.walk.nWalks << ", \"closed_walks\": " << xs.walk.nClosedWalks
       << ", \"column_steps\": " << xs.walk.nColumnSteps << ", \"arc_steps\": " << xs.walk.nArcSteps
       << ", \"xscan_newton_calls\": " << xs.walk.nNewtonCalls
       << ", \"xscan_newton_iterations\": " << xs.walk.nNewtonIterations
       << ", \"silhouette_points\": " << xs.walk.nSilhouettes
       << ", \"untracked_silhouettes\": " << xs.walk.nUntrackedSilhouettes
       << ", \"untracked_exits\": " << xs.walk.nUntrackedExits
       << ", \"repair_searches\": " << xs.silhouettes.nRepairSearches
       << ", \"repaired_by_search\": " << xs.silhouettes.nRepaired << ", \"failures\": " << xs.walk.nFailures
       << ", \"theta_chains\": " << xs.theta.nChains << ", \"theta_vertices\": " << xs.theta.nVertices
       << ", \"theta_steps\": " << xs.theta.nSteps << ", \"theta_turn_points\": " << xs.theta.nTurnPoints
       << ", \"theta_tilts\": " << xs.theta.nTilts << ", \"theta_trackers\": " << xs.theta.nTrackers
       << ", \"theta_tracker_iterations\": " << xs.theta.nTrackerIterations
       << ", \"theta_trackers_lost\": " << xs.theta.nTrackerFailures << ", \"theta_turn_trackers\": " << xs.theta.nTurnTrackers
       << ", \"theta_turn_iterations\": " << xs.theta.nTurnIterations << ", \"theta_turns_lost\": " << xs.theta.nTurnFailures
       << ", \"theta_link_repairs\": " << xs.theta.nLinkRepairs
       << ", \"theta_line_repairs\": " << xs.theta.nLineRepairs
       << ", \"slab_intervals\": " << xs.nSlabIntervals << ", \"row_intervals\": " << xs.nRowIntervals
       << ", \"slab_triangles\": " << xs.nSlabTriangles << "}, \"seconds_load\": " << loadSec << ", \"seconds_tessellate\": " << tessSec
       << ", \"seconds_render\": " << renderSec << ", \"seconds_output\": " << outputSec << ", \"peak_rss_kib\": " << peakKiB << "}\n";
    if (!js) {
      err << "patchscan: " << o.statsJson << ": cannot write statistics\n";
      return kExitOutputError;
    }
  }
  return kExitOk;
}

}  // namespace patchscan::cli
