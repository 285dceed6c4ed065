#include "render/frame.h"

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <memory>
#include <ostream>
#include <vector>

#include "patch/tessellate.h"
#include "raster/async_row_sink.h"
#include "raster/image_io.h"
#include "raster/image_writer.h"
#include "render/back_end.h"
#include "render/crop.h"
#include "render/interrupt.h"
#include "render/load.h"
#include "render/progress.h"
#include "render/shared_rows.h"
#include "scene/cad_library.h"
#include "scene/rib/reader.h"
#include "xscan/overlay.h"
#include "xscan/partitioned_scan.h"
#include "xscan/polygon_feed.h"
#include "xscan/row_scan.h"
#include "xscan/tess_feed.h"

namespace patchscan::render {
namespace {

using Clock = std::chrono::steady_clock;
double Seconds(Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double>(b - a).count(); }

Failure BadOption(std::string why) { return {Outcome::BadOption, std::move(why)}; }
Failure Stopped() { return {Outcome::Interrupted, "interrupted; no image written"}; }

// The options that do not fit the mode: the message for the user, or empty.
std::string ModeConflict(const RenderOptions& o) {
  const std::string mode = ModeName(o.mode);
  if (Direct(o.mode) && (o.shading != raster::ShadingMode::Phong || o.hiddenLine))
    return "--mode " + mode + " shades every sample with its own normal: --shading flat/gouraud and --hidden-line "
           "need a triangle mode (--mode tess)";
  if (!Direct(o.mode) && o.overlay != Overlay::None)
    return "--overlay trackers draws the Y scan's trackers: it needs --mode exact or theta";
  return {};
}

// The chord deviation in world units that is `px` pixels on the screen where the scene comes
// nearest the eye: the smallest over its box's corners and centre in front of the eye of the
// world length one pixel spans there (by the screen's derivative along each axis).
double WorldPerPixels(const Scene& scene, const Camera& camera, double px) {
  const Mat4 m = ScreenFromWorld(camera);
  const Bounds3 b = scene.WorldBounds();
  const double step = 1e-6 * std::max(b.Diagonal().norm(), 1e-300);
  double most = 0.0;  // pixels a world unit spans, at most
  for (int k = 0; k < 9; ++k) {
    const Vec3 p = k == 8 ? b.Centre() : Vec3(k & 1 ? b.hi.x() : b.lo.x(), k & 2 ? b.hi.y() : b.lo.y(), k & 4 ? b.hi.z() : b.lo.z());
    const Vec4 h = m * p.homogeneous();
    if (!(h.w() > 0.0)) continue;
    for (int axis = 0; axis < 3; ++axis) {
      const Vec4 g = m * (p + step * Vec3::Unit(axis)).homogeneous();
      if (g.w() > 0.0) most = std::max(most, (g.head<2>() / g.w() - h.head<2>() / h.w()).norm() / step);
    }
  }
  return most > 0.0 ? px / most : px * b.Diagonal().norm() / std::max(camera.width, camera.height);
}

// The tessellated mode's mesh, tessellated on `threads` threads (nullopt: interrupted). A
// CAD file at the default --tess-error is meshed by Open CASCADE as CAD viewers mesh it, its
// chord deviation that many pixels where the model comes nearest; its pieces otherwise.
std::optional<raster::TriangleMesh> TessellatedMesh(const RenderOptions& o, const Scene& scene, const Camera& camera,
                                                    int threads) {
  std::optional<TessMesh> tess;
  if (scene.cad && scene.cad->mesh && o.tessRate == 0 && o.tessPixels == 0.0)
    tess = scene.cad->mesh(WorldPerPixels(scene, camera, o.tessError));
  else
    tess = TessellateScene(scene.surfaces, camera, TessSettings{o.tessRate, o.tessPixels, o.tessError}, threads,
                           [] { return gInterrupted != 0; });
  if (!tess) return std::nullopt;
  WeldBoundaryVertices(&*tess, kWeldRelTol * scene.WorldBounds().Diagonal().norm());
  raster::TriangleMesh mesh = ToRasterMesh(*tess, camera);
  AppendScenePolygons(scene, camera, &mesh);
  return mesh;
}

// A frame's front end. Direct modes: the scan (this process's own, or its part of one
// shared between processes) and the polygons fed with its rows; tess mode: the mesh.
struct FrontEnd {
  std::unique_ptr<DirectScanSource> own;
  std::unique_ptr<SharedRows> shared;
  std::unique_ptr<PolygonFeed> polygons;
  std::optional<raster::TriangleMesh> mesh;

  DirectScanSource* Scan() const { return shared ? &shared->Source() : own.get(); }
  raster::FragmentSource& Rows() const {
    return polygons ? static_cast<raster::FragmentSource&>(*polygons) : *Scan();
  }
};

// The direct modes' front end: Blinn's Y scan with the exact or the θ-sampled X scan. With
// threads, the exact scan's rows are split between them (RowScan: sort-first, occlusion
// culling kept); the θ scans' surfaces are dealt out to `threads` workers (PartitionedScan:
// Molnar's object partition). One scan, on one thread, when tracing: the overlay is not shared.
FrontEnd DirectFrontEnd(const RenderOptions& o, const Scene& scene, const Camera& camera, int aa, int threads) {
  FrontEnd f;
  const ExactScanOptions xo = ScanOptionsFor(o, aa);
  if (o.shareRows) {
    f.shared = o.shareRows(o, scene, camera, xo, aa, threads);  // it hands the polygons over itself
    return f;
  }
  const bool traced = o.overlay != Overlay::None;
  if (threads > 1 && !traced && RowScan::Splits(xo)) {
    f.own = std::make_unique<RowScan>(scene.surfaces, camera, xo, threads);
  } else {
    // A worker a thread the machine runs at once: more only split the surfaces finer, and
    // every batch waits for the most loaded (the image is the same for any number).
    const int workers = traced ? 1 : std::min(threads, Cores());
    f.own = std::make_unique<PartitionedScan>(scene.surfaces, camera, xo, workers, threads);
  }
  if (!scene.polygons.empty()) f.polygons = std::make_unique<PolygonFeed>(*f.own, PolygonTriangles(scene, camera));
  return f;
}

// The warning an empty image gives: why it may be empty.
void WarnEmpty(const Scene& scene, std::ostream& log) {
  if (!scene.warnings.empty())
    log << "patchscan: warning: the image is empty: nothing drawn covers a sample, and " << scene.warnings.size()
        << " kind" << (scene.warnings.size() == 1 ? " of request was" : "s of request were")
        << " skipped (above): what the scene shows may be among them\n";
  else
    log << "patchscan: warning: the image is empty: no surface covers a sample (" << scene.Ids()
        << " surfaces; is the camera looking at them?)\n";
}

// The image file: the options', else the scene's Display, else (POV-Ray's habit) the
// scene file's name with .png in the current directory, which the log is told.
std::string OutputFor(const RenderOptions& o, const Scene& scene, std::ostream& log) {
  if (!o.output.empty()) return o.output;
  if (!scene.image.displayName.empty()) return scene.image.displayName;
  std::filesystem::path stem = std::filesystem::path(o.file).filename();
  if (stem.extension() == ".gz") stem = stem.stem();
  const std::string output = stem.stem().string() + ".png";
  log << "patchscan: note: no -o" << (scene.image.cameraFromWorld ? " and no Display" : "") << ": writing " << output
      << " in the current directory\n";
  return output;
}

}  // namespace

Result<RenderReport> RenderFrame(const RenderOptions& o, std::ostream& log, std::set<std::string>* warned) {
  const auto t0 = Clock::now();
  // Step 1: the scene, the camera and what the options ask of them.
  auto loaded = LoadSceneAndCamera(o.file, o.camera, log, warned);
  if (auto* failed = std::get_if<Failure>(&loaded)) return *failed;
  const Scene& scene = std::get<LoadedScene>(loaded).scene;
  const Camera& camera = std::get<LoadedScene>(loaded).view.camera;
  const auto tLoaded = Clock::now();
  const std::string output = OutputFor(o, scene, log);
  const bool depthMap = WritesDepthMap(o, scene);
  if (std::string why = ModeConflict(o); !why.empty()) return BadOption(std::move(why));
  const int aa = o.aa.value_or(scene.image.pixelSamples.value_or(kDefaultAa));
  std::optional<Vec4> cropNdc = scene.image.cropWindow;
  if (!o.crop.empty() && !(cropNdc = ParseCrop(o.crop)))
    return BadOption(
        "--crop: expected XMIN,XMAX,YMIN,YMAX with 0 <= XMIN < XMAX <= 1 and 0 <= YMIN < YMAX <= 1, found '" +
        o.crop + "'");
  const PixelWindow window = cropNdc ? CropPixels(*cropNdc, camera.width, camera.height)
                                     : PixelWindow{0, 0, camera.width, camera.height};
  if (window.x1 <= window.x0 || window.y1 <= window.y0)
    return BadOption("the crop window holds no pixel centre of the " + std::to_string(camera.width) + "x" +
                     std::to_string(camera.height) + " image");
  const int outWidth = window.x1 - window.x0, outHeight = window.y1 - window.y0;

  // Step 2: the front end: the direct scan, or the tessellated mesh.
  const int threads = ThreadsFor(o.threads);
  FrontEnd front;
  if (Direct(o.mode)) front = DirectFrontEnd(o, scene, camera, aa, threads);
  else if (!(front.mesh = TessellatedMesh(o, scene, camera, threads))) return Stopped();
  DirectScanSource* scan = front.Scan();
  const auto tSetUp = Clock::now();

  // Step 3: the back end (after the scene's MakeShadow requests: its lights may read what
  // they make), and the rows' way to the image file.
  for (const std::string& w : MakeTextures(scene, o.file)) Warn(w, log, warned);
  auto setup = SetUpBackEnd(o, scene, camera, aa);
  if (auto* failed = std::get_if<Failure>(&setup)) return *failed;
  BackEndSetup& backEnd = *std::get<std::unique_ptr<BackEndSetup>>(setup);
  for (const std::string& w : backEnd.warnings) Warn(w, log, warned);
  backEnd.settings.threads = threads;
  // The options' compression, else the scene's Display's when the scene names the file.
  const std::string compression =
      !o.compression.empty() || !o.output.empty() ? o.compression : scene.image.displayCompression;
  if (const auto why = raster::ImageWriter::CheckFormat(output, o.aov, compression); why && !depthMap) {
    if (compression != o.compression)
      return BadOption(o.file + ':' + std::to_string(scene.image.displayLine) + ": Display: " + *why);
    return BadOption(*why);
  }
  raster::ImageWriter::Window placement;
  if (cropNdc) placement = {window.x0, window.y0, camera.width, camera.height};
  // Opening the output is output time: for a format other than PNG it loads OpenImageIO.
  const auto tOpen = Clock::now();
  auto opened = depthMap ? raster::ImageWriter::OpenDepthMap(output, outWidth, outHeight, LightCamera(camera))
                         : raster::ImageWriter::Open(output, outWidth, outHeight, o.aov, threads, placement, compression);
  const double openSeconds = Seconds(tOpen, Clock::now());
  if (auto* why = std::get_if<std::string>(&opened)) return Failure{Outcome::OutputError, *why};
  auto& writer = *std::get<std::unique_ptr<raster::ImageWriter>>(opened);
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
  std::unique_ptr<TrackerOverlay> overlay;
  if (o.overlay == Overlay::Trackers) {
    overlay = std::make_unique<TrackerOverlay>(*toImage, camera.width, camera.height);
    scan->SetTrace(overlay.get());
    out = overlay.get();
  }

  // Step 4: render the rows, streaming each to the image; then commit it.
  ProgressSink progress(*out, camera.height, log, o.progress);
  // A render shared between processes renders its own rows and brings the others' in.
  raster::RowSink* rows = &progress;
  std::unique_ptr<raster::RowSink> assembled;
  if (front.shared) {
    backEnd.settings.ownsRow = front.shared->OwnedRows();
    if ((assembled = front.shared->AssembleRows(progress))) rows = assembled.get();
  }
  raster::BackEndTimes backEndTimes;
  auto counted = scan ? raster::RenderFragments(front.Rows(), backEnd.settings, *rows, &backEndTimes)
                      : raster::RenderMesh(*front.mesh, backEnd.settings, progress, &backEndTimes);
  if (counted && overlay && !overlay->Finish()) counted.reset();
  if (counted && async && !async->Finish()) counted.reset();
  if (!counted) {
    if (gInterrupted) return Stopped();
    if (std::string why = backEnd.TextureError(); !why.empty()) return Failure{Outcome::InputError, std::move(why)};
    return Failure{Outcome::OutputError, output + ": writing the image failed"};
  }
  progress.Finish();
  if ((*counted)[Counter::SamplesCovered] == 0) WarnEmpty(scene, log);
  const auto tCommit = Clock::now();
  if (auto committed = writer.Commit(); auto* why = std::get_if<std::string>(&committed))
    return Failure{Outcome::OutputError, *why};
  const auto tDone = Clock::now();

  // Step 5: what it took.
  RenderReport report;
  report.mode = o.mode;
  report.image = output;
  report.width = outWidth;
  report.height = outHeight;
  report.depthMap = depthMap;
  report.counters = *counted;
  if (scan) {
    report.counters.Merge(scan->Stats());
    const DirectScanSource::Timing times = scan->Times();
    report.workerSeconds = times.workerSeconds;
    report.compositeSeconds = times.compositeSeconds;
  }
  if (front.shared) report.processes = front.shared->Processes();
  report.load = Seconds(t0, tLoaded);
  report.setUp = Seconds(tLoaded, tSetUp);
  report.render = Seconds(tSetUp, tDone);
  // Encoding and writing, inside the render (on the writer's thread: overlapping it).
  report.output = openSeconds + (async ? async->WriterSeconds() : progress.OutputSeconds()) + Seconds(tCommit, tDone);
  report.backEnd = std::move(backEndTimes);
  report.peakKiB = PeakResidentKiB();
  report.texture = backEnd.TextureReport();
  report.imageLibrary = raster::imageio::Loaded();
  report.cadLibrary = CadLoaded();
  return report;
}

std::optional<Failure> RenderFile(const RenderOptions& o, std::ostream& log, const FrameDone& done) {
  auto one = [&](const RenderOptions& frame, std::set<std::string>* warned) -> std::optional<Failure> {
    auto rendered = RenderFrame(frame, log, warned);
    if (auto* failed = std::get_if<Failure>(&rendered)) return *failed;
    return done ? done(std::get<RenderReport>(rendered)) : std::nullopt;
  };
  const std::filesystem::path file(o.file);
  const bool rib = file.extension() == ".rib" || (file.extension() == ".gz" && file.stem().extension() == ".rib");
  if (o.frames && !rib) return BadOption("--frames: " + o.file + " is not a RIB file (only RIB files have frames)");
  if (!rib || o.camera.frame >= 0) return one(o, nullptr);
  // Each frame once, in the file's order (a number given twice names the first).
  std::vector<RibFrame> frames;
  std::string numbers;
  for (const RibFrame& f : RibFrames(o.file)) {
    if (std::any_of(frames.begin(), frames.end(), [&](const RibFrame& g) { return g.number == f.number; })) continue;
    numbers += (numbers.empty() ? "" : ", ") + std::to_string(f.number);
    if (!o.frames || (f.number >= o.frames->first && f.number <= o.frames->last)) frames.push_back(f);
  }
  if (o.frames && frames.empty())
    return BadOption("--frames " + std::to_string(o.frames->first) + "-" + std::to_string(o.frames->last) + ": " +
                     o.file + " has no such frame (its frames: " + (numbers.empty() ? "none" : numbers) + ")");
  if (frames.empty()) return one(o, nullptr);
  // Every frame in order (a shadow pass writes the map a later frame reads), each to its
  // Display; -o takes the place of the last frame's that writes a picture.
  auto picture = std::find_if(frames.rbegin(), frames.rend(), [](const RibFrame& f) { return !f.depthMap; });
  if (!o.output.empty() && picture == frames.rend()) {
    std::string chosen;
    for (const RibFrame& f : frames) chosen += (chosen.empty() ? "" : ", ") + std::to_string(f.number);
    return BadOption("-o " + o.output + ": frame" + (frames.size() == 1 ? " " : "s ") + chosen + " of " + o.file +
                     " write" + (frames.size() == 1 ? "s" : "") +
                     " a depth map, not a picture (leave out -o: a depth map goes to its Display)");
  }
  const int pictureFrame = picture == frames.rend() ? 0 : picture->number;
  std::set<std::string> warned;
  for (const RibFrame& f : frames) {
    RenderOptions frame = o;
    frame.camera.frame = f.number;
    if (f.number != pictureFrame) frame.output.clear();
    if (auto failed = one(frame, &warned)) return failed;
  }
  return std::nullopt;
}

}  // namespace patchscan::render
