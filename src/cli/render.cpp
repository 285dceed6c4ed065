#include "cli/render.h"

#include <cstdio>
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <ostream>
#include <set>
#include <thread>

#include "cli/exit_codes.h"
#include "cli/file_output.h"
#include "cli/render_setup.h"
#include "cli/stats_report.h"
#include "patch/rib_reader.h"
#include "patch/tessellate.h"
#include "raster/async_row_sink.h"
#include "raster/image_io.h"
#include "raster/image_writer.h"
#include "xscan/exact_scan.h"
#include "xscan/partitioned_scan.h"
#include "xscan/polygon_feed.h"
#include "xscan/overlay.h"
#include "xscan/tess_feed.h"

namespace patchscan::cli {
namespace {

using Clock = std::chrono::steady_clock;
double Seconds(Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double>(b - a).count(); }

// Peak resident memory of this process so far, in KiB.
long PeakResidentKiB() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return u.ru_maxrss;
}

// The options that do not fit the mode: the message for the user, or empty.
std::string ModeConflict(const RenderOptions& o) {
  const std::string mode = NameOf(kRenderModeNames, o.mode);
  if (Direct(o.mode) && (o.shading != raster::ShadingMode::Phong || o.hiddenLine))
    return "--mode " + mode + " shades every sample with its own normal: --shading flat/gouraud and --hidden-line "
           "need a triangle mode (--mode tess)";
  if (!Direct(o.mode) && o.overlay != Overlay::None)
    return "--overlay trackers draws the Y scan's trackers: it needs --mode exact or theta";
  return {};
}

// The direct modes' front end: Blinn's Y scan with the exact or the θ-sampled X scan, its
// surfaces dealt out to `threads` workers (one when tracing: the overlay is not shared).
std::unique_ptr<DirectScanSource> DirectScan(const RenderOptions& o, const Scene& scene, const Camera& camera, int aa,
                                             int threads) {
  const ExactScanOptions xo = ScanOptionsFor(o, aa);
  if (o.makeDirectScan) return o.makeDirectScan(o, scene, camera, xo, aa, threads);
  const int workers = o.overlay == Overlay::None ? threads : 1;
  return std::make_unique<PartitionedScan>(scene.surfaces, camera, xo, workers, threads);
}

// The tessellated mode's mesh, tessellated on `threads` threads (nullopt: interrupted).
std::optional<raster::TriangleMesh> TessellatedMesh(const RenderOptions& o, const Scene& scene, const Camera& camera,
                                                    int threads) {
  auto tess = TessellateScene(scene.surfaces, camera, TessSettings{o.tessRate, o.tessPixels, o.tessError}, threads,
                              [] { return gInterrupted != 0; });
  if (!tess) return std::nullopt;
  WeldBoundaryVertices(&*tess, kWeldRelTol * scene.WorldBounds().Diagonal().norm());
  raster::TriangleMesh mesh = ToRasterMesh(*tess, camera);
  AppendPolygonTriangles(scene.polygons, camera, static_cast<std::uint32_t>(scene.surfaces.size()), &mesh);
  return mesh;
}

}  // namespace

ExactScanOptions ScanOptionsFor(const RenderOptions& o, int aa) {
  ExactScanOptions xo;
  xo.extrapolate = !o.noExtrapolate;
  if (o.mode == RenderMode::Theta) {
    xo.thetaSteps = o.thetaSteps;
    // Sample rows are 1 / (aa - 1) pixels apart (aa 1: one per pixel). A slab one sample
    // row high would cost two lines' trackers and a zip for the one row of samples its own
    // chains give exactly: such a step takes chains on every row instead.
    const double spacing = aa == 1 ? 1.0 : 1.0 / (aa - 1);
    const int rows = o.yStep > 0.0 ? static_cast<int>(std::lround(o.yStep / spacing)) : 0;
    xo.slabRows = rows >= 2 ? rows : 0;
  }
  return xo;
}

CLI::App* AddRenderCommand(CLI::App* app, RenderOptions* o) {
  CLI::App* cmd = app->add_subcommand(
      "render",
      "Render a scene file to an image. The format follows the output's extension: .png, "
      ".tif/.tiff, .jpg/.jpeg (no alpha) or .exr; alpha is coverage. 8-bit PNG and JPEG hold "
      "sRGB-encoded colour (PNG with straight alpha); 16-bit TIFF and half-float EXR the linear, "
      "premultiplied values. The image is written to a temporary file and renamed into place, "
      "so a failed render leaves no file.");
  cmd->add_option("FILE", o->file, "scene file: .bpt (Bézier patches), .rib (RenderMan scene) or .obj (a subdivision cage)")->required();
  cmd->add_option("-o,--output", o->output,
                  "output image file (default: a RIB scene's Display file name; required otherwise)");
  AddChoiceOption(cmd, "--mode", &o->mode, kRenderModeNames,
                  "how surfaces become samples: exact = Blinn's scan-line algorithm, every "
                  "visible sample's (u,v) found by Newton iteration (shading always uses the "
                  "exact normal; --shading flat/gouraud and --hidden-line need triangles); "
                  "theta = the same Y scan, with each cross-section sampled at --theta-steps "
                  "angles of its normal per turn and the samples between interpolated along the "
                  "chords; tess = tessellated with OpenSubdiv's Bfr::Tessellation pattern");
  cmd->add_option("--theta-steps", o->thetaSteps,
                  "theta mode: tabulated normal angles per turn of a cross-section (chord error "
                  "R (1 - cos(pi/N)) pixels for a section of radius R pixels); with chains on "
                  "every row, a surface whose normal turns through more than 0.1 of a step per "
                  "pixel of its extent on the screen, or whose chains come to hold more vertices "
                  "per sample than exact samples cost, takes the exact scan instead (cheaper there; "
                  "--stats: theta_exact_surfaces)")
      ->check(CLI::Range(1, 4096))
      ->capture_default_str();
  cmd->add_option("--y-step", o->yStep,
                  "theta mode: 0 (the default), or a step of less than two sample rows: every "
                  "sample row is sampled, its chains advanced from the row before (coverage exact "
                  "on every row), and no triangles are made. Else pixels between the scan lines "
                  "whose cross-sections are sampled (rounded to a whole number of sample rows); "
                  "each surface between two such lines goes to the back end as one slab of "
                  "triangles, and where a surface's chains of two lines do not pair up (a curve "
                  "born or gone, an event of its Y scan) its every sample row between them is "
                  "sampled instead, its ends on a boundary placed where a slab across it has its "
                  "edge. Silhouettes between the lines are chords: error about h^2 / (8 R) "
                  "pixels for step h and a silhouette curving with radius R pixels")
      ->check(CLI::Range(0.0, 64.0))
      ->capture_default_str();
  cmd->add_flag("--no-extrapolate", o->noExtrapolate,
                "exact mode: start each tracker's Newton iteration from its last position "
                "instead of extrapolating from its last two (to measure what extrapolation saves)");
  AddChoiceOption(cmd, "--overlay", &o->overlay, ChoiceNames<Overlay>{{"none", Overlay::None}, {"trackers", Overlay::Trackers}},
                  "exact mode: trackers = draw what the scan did over the image: each tracker's "
                  "path as dots (boundary-edge trackers blue, silhouette trackers red) and each "
                  "event as a ring (maximum passed yellow, saddle magenta, fold green, "
                  "silhouette tracker born pink, tracker died black, crossing repaired by the "
                  "x scan orange, walk or sample given up cyan)");
  auto* tessError = cmd->add_option("--tess-error", o->tessError,
                                    "tess mode (the default tessellation): rates chosen per surface from the "
                                    "screen so that no triangle lies more than about this many pixels from "
                                    "the surface (chord error; equal rates on shared edges)")
                         ->check(CLI::Range(0.01, 1e6))
                         ->capture_default_str();
  auto* tessRate = cmd->add_option("--tess-rate", o->tessRate,
                                   "tess mode: uniform tessellation instead, this many segments per patch edge")
                       ->check(CLI::Range(1, kMaxTessRate));
  auto* tessPixels = cmd->add_option("--tess-pixels", o->tessPixels,
                                     "tess mode: screen-adaptive tessellation instead, per-edge rates making "
                                     "edges about this many pixels long (equal on shared edges)")
                         ->check(CLI::Range(0.01, 1e6));
  tessError->excludes(tessRate)->excludes(tessPixels);
  tessRate->excludes(tessPixels);
  cmd->add_option("--aa", o->aa,
                  "supersampling: an l x l grid of samples per pixel whose edge samples are "
                  "shared with the neighbours (1: one sample at the pixel centre; default: a RIB "
                  "scene's PixelSamples, else 3)")
      ->check(CLI::Range(1, raster::kMaxAa));
  AddChoiceOption(cmd, "--shading", &o->shading,
                  ChoiceNames<raster::ShadingMode>{{"flat", raster::ShadingMode::Flat},
                                                   {"gouraud", raster::ShadingMode::Gouraud},
                                                   {"phong", raster::ShadingMode::Phong}},
                  "flat, gouraud or phong");
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
  cmd->add_option("--compression", o->compression, raster::ImageWriter::kCompressionHelp);
  cmd->add_option("--crop", o->crop,
                  "render a window of the image: XMIN,XMAX,YMIN,YMAX as fractions of the width and "
                  "height from the top left (RenderMan's CropWindow, which a RIB scene may give); "
                  "the pixels whose centres lie in it, the same as the full render's there, in an "
                  "image of the window's size (EXR and TIFF record where it lies in the frame)");
  cmd->add_option("--seed", o->seed,
                  "seed of the stochastic extra shading calls (same seed, same image)")
      ->capture_default_str();
  cmd->add_option("--threads", o->threads,
                  "worker threads (default: one per core). The scene's surfaces are dealt out to "
                  "them and each scans its share row by row (paper 002's object partition); their "
                  "rows are composited by depth in a fixed order, so the image is the same for any "
                  "number. 1: one thread. --overlay uses one worker")
      ->check(CLI::Range(1, 1024));
  cmd->add_flag("--stats", o->stats, "print counts, times and peak memory to stderr");
  auto* progress = cmd->add_flag("--progress", o->progress,
                                 "show progress on stderr (rows finished, elapsed time, time left) even when "
                                 "stderr is not a terminal (default: only on a terminal)");
  cmd->add_flag("--quiet", o->quiet, "no progress line (errors and warnings are still printed)")->excludes(progress);
  cmd->add_option("--stats-json", o->statsJson, "write counts and times as JSON to this file");
  AddCameraOptions(cmd, &o->camera);
  return cmd;
}

namespace {

// The pixels [x0, x1) x [y0, y1) of a width x height frame that a crop window in NDC
// covers: RenderMan's rule, the pixels from ceil(W xmin) to ceil(W xmax) - 1, so windows
// that share a side share no pixel and tile the frame.
struct PixelWindow {
  int x0, y0, x1, y1;
};
PixelWindow CropPixels(const Vec4& ndc, int width, int height) {
  auto at = [](double f, int n) { return std::clamp(static_cast<int>(std::ceil(f * n)), 0, n); };
  return {at(ndc[0], width), at(ndc[2], height), at(ndc[1], width), at(ndc[3], height)};
}

// "xmin,xmax,ymin,ymax" with 0 <= xmin < xmax <= 1 and the same for y.
std::optional<Vec4> ParseCrop(const std::string& text) {
  Vec4 w;
  char tail = 0;
  if (std::sscanf(text.c_str(), "%lf,%lf,%lf,%lf%c", &w[0], &w[1], &w[2], &w[3], &tail) != 4) return std::nullopt;
  if (!(0.0 <= w[0] && w[0] < w[1] && w[1] <= 1.0 && 0.0 <= w[2] && w[2] < w[3] && w[3] <= 1.0)) return std::nullopt;
  return w;
}

// Passes on the window's part of each row, renumbered from the window's top.
class CropSink final : public raster::RowSink {
 public:
  CropSink(raster::RowSink& next, const PixelWindow& w) : next_(next), w_(w) {}
  bool WriteRow(int y, const float* pixels) override {
    if (y < w_.y0 || y >= w_.y1) return true;
    return next_.WriteRow(y - w_.y0, pixels + static_cast<std::size_t>(w_.x0) * raster::kChannels);
  }

 private:
  raster::RowSink& next_;
  PixelWindow w_;
};

}  // namespace

// One frame of the scene (the file's first, or --frame), to -o or its Display.
// `warned`: warnings printed by earlier frames, not printed again.
static int RenderFrame(const RenderOptions& o, std::ostream& err, std::set<std::string>* warned = nullptr) {
  const auto t0 = Clock::now();
  CatchInterrupts();
  // Step 1: the scene, the camera and what the options ask of them.
  auto loaded = LoadSceneAndCamera(o.file, o.camera, err, warned);
  if (const int* code = std::get_if<int>(&loaded)) return *code;
  const Scene& scene = std::get<LoadedScene>(loaded).scene;
  const Camera& camera = std::get<LoadedScene>(loaded).view.camera;
  const auto tLoaded = Clock::now();
  const std::string output = !o.output.empty() ? o.output : scene.image.displayName;
  const bool depthMap = WritesDepthMap(o, scene);
  if (output.empty()) {
    err << "patchscan: no output image: give -o IMAGE" << (scene.image.cameraFromWorld ? " (the scene has no Display file)" : "") << '\n';
    return kExitUsage;
  }
  if (const std::string why = ModeConflict(o); !why.empty()) {
    err << "patchscan: " << why << '\n';
    return kExitUsage;
  }
  const int aa = o.aa.value_or(scene.image.pixelSamples.value_or(kDefaultAa));
  std::optional<Vec4> cropNdc = scene.image.cropWindow;
  if (!o.crop.empty() && !(cropNdc = ParseCrop(o.crop))) {
    err << "patchscan: --crop: expected XMIN,XMAX,YMIN,YMAX with 0 <= XMIN < XMAX <= 1 and 0 <= YMIN < YMAX <= 1, found '"
        << o.crop << "'\n";
    return kExitUsage;
  }
  const PixelWindow window = cropNdc ? CropPixels(*cropNdc, camera.width, camera.height)
                                     : PixelWindow{0, 0, camera.width, camera.height};
  if (window.x1 <= window.x0 || window.y1 <= window.y0) {
    err << "patchscan: the crop window holds no pixel centre of the " << camera.width << "x" << camera.height
        << " image\n";
    return kExitUsage;
  }
  const int outWidth = window.x1 - window.x0, outHeight = window.y1 - window.y0;

  // Step 2: the front end: the direct scan, or the tessellated mesh.
  const int threads = o.threads > 0 ? o.threads : std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
  std::unique_ptr<DirectScanSource> scan;
  std::unique_ptr<PolygonFeed> polygons;  // a direct render's polygons, with its rows
  std::optional<raster::TriangleMesh> mesh;
  if (Direct(o.mode)) {
    scan = DirectScan(o, scene, camera, aa, threads);
    if (!scene.polygons.empty() && !scan->FeedsPolygons()) {
      raster::TriangleMesh triangles;
      AppendPolygonTriangles(scene.polygons, camera, static_cast<std::uint32_t>(scene.surfaces.size()), &triangles);
      polygons = std::make_unique<PolygonFeed>(*scan, std::move(triangles));
    }
  } else if (!(mesh = TessellatedMesh(o, scene, camera, threads))) {
    err << "patchscan: interrupted; no image written\n";
    return kExitInterrupted;
  }
  const auto tSetUp = Clock::now();

  // Step 3: the back end (after the scene's MakeShadow requests: its lights may read what
  // they make), and the rows' way to the image file.
  if (const auto code = MakeShadows(scene, err)) return *code;
  auto setup = SetUpBackEnd(o, scene, camera, aa, err);
  if (const int* code = std::get_if<int>(&setup)) return *code;
  BackEndSetup& backEnd = *std::get<std::unique_ptr<BackEndSetup>>(setup);
  backEnd.settings.threads = threads;
  // --compression, else the scene's Display's when the scene names the file.
  const std::string compression =
      !o.compression.empty() || !o.output.empty() ? o.compression : scene.image.displayCompression;
  if (const auto why = raster::ImageWriter::CheckFormat(output, o.aov, compression); why && !depthMap) {
    err << "patchscan: ";
    if (compression != o.compression) err << o.file << ':' << scene.image.displayLine << ": Display: ";
    err << *why << '\n';
    return kExitUsage;
  }
  raster::ImageWriter::Window placement;
  if (cropNdc) placement = {window.x0, window.y0, camera.width, camera.height};
  // Opening the output is output time: for a format other than PNG it loads OpenImageIO.
  const auto tOpen = Clock::now();
  auto opened = depthMap ? raster::ImageWriter::OpenDepthMap(output, outWidth, outHeight, LightCamera(camera))
                         : raster::ImageWriter::Open(output, outWidth, outHeight, o.aov, threads, placement, compression);
  const double openSeconds = Seconds(tOpen, Clock::now());
  if (auto* why = std::get_if<std::string>(&opened)) {
    err << "patchscan: " << *why << '\n';
    return kExitOutputError;
  }
  auto& writer = *std::get<std::unique_ptr<raster::ImageWriter>>(opened);
  std::unique_ptr<TrackerOverlay> overlay;
  // With more than one thread the image is encoded and written on a thread of its own,
  // overlapping the rows still being rendered.
  std::unique_ptr<raster::AsyncRowSink> async;
  if (threads > 1 && !writer.EncodesInParallel()) async = std::make_unique<raster::AsyncRowSink>(writer, outWidth);
  raster::RowSink* toImage = async ? static_cast<raster::RowSink*>(async.get()) : &writer;
  // A crop: the full frame's rows are rendered (the scan needs every row above the window
  // anyway), and only the window's part of them reaches the image.
  std::unique_ptr<CropSink> cropped;
  if (cropNdc) {
    cropped = std::make_unique<CropSink>(*toImage, window);
    toImage = cropped.get();
  }
  raster::RowSink* out = toImage;
  if (o.overlay == Overlay::Trackers) {
    overlay = std::make_unique<TrackerOverlay>(*toImage, camera.width, camera.height);
    scan->SetTrace(overlay.get());
    out = overlay.get();
  }

  // Step 4: render the rows, streaming each to the image; then commit it.
  const bool showProgress = !o.quiet && (o.progress || isatty(STDERR_FILENO) != 0);
  ProgressSink progress(*out, camera.height, err, showProgress);
  // A render shared between processes renders its own rows and brings the others' in.
  raster::RowSink* rows = &progress;
  std::unique_ptr<raster::RowSink> assembled;
  if (scan) {
    backEnd.settings.ownsRow = scan->OwnedRows();
    if ((assembled = scan->AssembleRows(progress))) rows = assembled.get();
  }
  raster::FragmentSource* source = polygons ? static_cast<raster::FragmentSource*>(polygons.get()) : scan.get();
  auto counted = scan ? raster::RenderFragments(*source, backEnd.settings, *rows)
                      : raster::RenderMesh(*mesh, backEnd.settings, progress);
  if (counted && overlay && !overlay->Finish()) counted.reset();
  if (counted && async && !async->Finish()) counted.reset();
  if (!counted) {
    if (gInterrupted) {
      err << "\npatchscan: interrupted; no image written\n";
      return kExitInterrupted;
    }
    if (const std::string why = backEnd.TextureError(); !why.empty()) {
      err << "patchscan: " << why << '\n';
      return kExitInputError;
    }
    err << "patchscan: " << output << ": writing the image failed\n";
    return kExitOutputError;
  }
  progress.Finish();
  // An empty image says why it may be empty.
  if ((*counted)[Counter::SamplesCovered] == 0) {
    if (!scene.warnings.empty())
      err << "patchscan: warning: the image is empty: nothing drawn covers a sample, and " << scene.warnings.size()
          << " kind" << (scene.warnings.size() == 1 ? " of request was" : "s of request were")
          << " skipped (above): what the scene shows may be among them\n";
    else
      err << "patchscan: warning: the image is empty: no surface covers a sample (" << scene.Ids()
          << " surfaces; is the camera looking at them?)\n";
  }
  const auto tCommit = Clock::now();
  if (auto committed = writer.Commit(); auto* why = std::get_if<std::string>(&committed)) {
    err << "patchscan: " << *why << '\n';
    return kExitOutputError;
  }
  const auto tDone = Clock::now();

  // Step 5: what it took.
  if (!o.stats && o.statsJson.empty()) return kExitOk;
  RenderReport report;
  report.mode = o.mode;
  report.counters = *counted;
  if (scan) {
    report.counters.Merge(scan->Stats());
    const DirectScanSource::Timing times = scan->Times();
    report.workerSeconds = times.workerSeconds;
    report.compositeSeconds = times.compositeSeconds;
    report.processes = scan->Processes();
  }
  report.load = Seconds(t0, tLoaded);
  report.setUp = Seconds(tLoaded, tSetUp);
  report.render = Seconds(tSetUp, tDone);
  // Encoding and writing, inside the render (on the writer's thread: overlapping it).
  report.output = openSeconds + (async ? async->WriterSeconds() : progress.OutputSeconds()) + Seconds(tCommit, tDone);
  report.peakKiB = PeakResidentKiB();
  report.texture = backEnd.TextureReport();
  report.imageLibrary = raster::imageio::Loaded();
  if (o.stats) PrintReport(report, err);
  if (!o.statsJson.empty()) {
    if (const auto why = WriteFileWhole(o.statsJson, ReportJson(report))) {
      err << "patchscan: " << *why << " (statistics)\n";
      return kExitOutputError;
    }
  }
  return kExitOk;
}


int RunRender(const RenderOptions& o, std::ostream& err) {
  // A RIB file of several frames renders each, in order, to its own Display; with --frame
  // or -o, one frame.
  const std::filesystem::path file(o.file);
  const bool rib = file.extension() == ".rib" || (file.extension() == ".gz" && file.stem().extension() == ".rib");
  std::vector<int> frames;
  if (rib && o.camera.frame < 0)
    for (const int n : RibFrames(o.file))
      if (std::find(frames.begin(), frames.end(), n) == frames.end()) frames.push_back(n);
  if (frames.size() <= 1) return RenderFrame(o, err);
  if (!o.output.empty()) {
    err << "patchscan: note: " << o.file << " has " << frames.size() << " frames; -o writes the first (give --frame N "
        << "for another, or leave out -o to render every frame to its Display)\n";
    return RenderFrame(o, err);
  }
  std::set<std::string> warned;
  for (const int n : frames) {
    RenderOptions one = o;
    one.camera.frame = n;
    if (const int code = RenderFrame(one, err, &warned); code != kExitOk) return code;
  }
  return kExitOk;
}

}  // namespace patchscan::cli
