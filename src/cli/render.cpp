#include "cli/render.h"

#include <unistd.h>

#include <algorithm>
#include <iomanip>
#include <ostream>
#include <sstream>

#include "cli/camera_options.h"
#include "cli/checks.h"
#include "cli/exit_codes.h"
#include "cli/file_output.h"
#include "raster/image_writer.h"
#include "render/frame.h"
#include "render/interrupt.h"
#include "xscan/tess_feed.h"

namespace patchscan::cli {

CLI::App* AddRenderCommand(CLI::App* app, RenderCommand* command) {
  render::RenderOptions* o = &command->options;
  CLI::App* cmd = app->add_subcommand(
      "render",
      "Render a scene file to an image. The format follows the output's extension: .png, "
      ".tif/.tiff, .jpg/.jpeg (no alpha) or .exr; alpha is coverage. 8-bit PNG and JPEG hold "
      "sRGB-encoded colour (PNG with straight alpha); 16-bit TIFF and half-float EXR the linear, "
      "premultiplied values. The image is written to a temporary file and renamed into place, "
      "so a failed render leaves no file.");
  cmd->add_option("FILE", o->file, "scene file: .bpt (Bézier patches), .rib (RenderMan scene), .obj (a subdivision cage), or a CAD model: .step, .stp, .iges, .igs, .brep")
      ->type_name("FILE")
      ->required();
  cmd->add_option("-o,--output", o->output,
                  "output image file (default: the scene's Display, else FILE's name with .png in the current "
                  "directory). Of a RIB file of several frames, -o takes the place of the last frame's Display "
                  "that writes a picture; the others (shadow passes) still write theirs")
      ->type_name("IMAGE");
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
      ->type_name("N")
      ->check(WholeNumber(1, 4096))
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
      ->type_name("PX")
      ->check(Number(0.0, 64.0))
      ->capture_default_str();
  cmd->add_flag("--no-extrapolate", o->noExtrapolate,
                "exact mode: start each tracker's Newton iteration from its last position "
                "instead of extrapolating from its last two (to measure what extrapolation saves)");
  AddChoiceOption(cmd, "--overlay", &o->overlay, ChoiceNames<render::Overlay>{{"none", render::Overlay::None}, {"trackers", render::Overlay::Trackers}},
                  "exact and theta modes: trackers = draw what the scan did over the image: each tracker's "
                  "path as dots (boundary-edge trackers blue, silhouette trackers red) and each "
                  "event as a ring (maximum passed yellow, saddle magenta, fold green, "
                  "silhouette tracker born pink, tracker died black, crossing repaired by the "
                  "x scan orange, walk or sample given up cyan)");
  auto* tessError = cmd->add_option("--tess-error", o->tessError,
                                    "tess mode (the default tessellation): rates chosen per surface from the "
                                    "screen so that no triangle lies more than about this many pixels from "
                                    "the surface (chord error; equal rates on shared edges); a CAD file is meshed by Open "
                                    "CASCADE with this chord deviation where the model comes nearest")
                         ->type_name("PX")
                         ->check(Number(0.01, 1e6))
                         ->capture_default_str();
  auto* tessRate = cmd->add_option("--tess-rate", o->tessRate,
                                   "tess mode: uniform tessellation instead, this many segments per patch edge")
                       ->type_name("N")
                       ->check(WholeNumber(1, kMaxTessRate));
  auto* tessPixels = cmd->add_option("--tess-pixels", o->tessPixels,
                                     "tess mode: screen-adaptive tessellation instead, per-edge rates making "
                                     "edges about this many pixels long (equal on shared edges)")
                         ->type_name("PX")
                         ->check(Number(0.01, 1e6));
  tessError->excludes(tessRate)->excludes(tessPixels);
  tessRate->excludes(tessPixels);
  cmd->add_option("--aa", o->aa,
                  "supersampling: an l x l grid of samples per pixel whose edge samples are "
                  "shared with the neighbours (1: one sample at the pixel centre; default: a RIB "
                  "scene's PixelSamples, else 3)")
      ->type_name("N")
      ->check(WholeNumber(1, raster::kMaxAa));
  AddChoiceOption(cmd, "--shading", &o->shading,
                  ChoiceNames<raster::ShadingMode>{{"flat", raster::ShadingMode::Flat},
                                                   {"gouraud", raster::ShadingMode::Gouraud},
                                                   {"phong", raster::ShadingMode::Phong}},
                  "flat, gouraud or phong");
  cmd->add_option("--texture", o->texture,
                  "none; checker, a procedural 8x8 uv checker; or an image file read through "
                  "OpenImageIO's TextureSystem (mipmapped, opened only when a visible sample "
                  "needs it; 'maketx' makes mipmapped files)")
      ->type_name("none|checker|FILE")
      ->capture_default_str();
  cmd->add_option("--bump", o->bump,
                  "a bump map for every surface whose scene gives none (Blinn 1978): the first "
                  "channel of an image file as a height along the normal, times AMPLITUDE (world "
                  "units, default 1); the normal is perturbed, the surface does not move")
      ->type_name("FILE[:AMPLITUDE]");
  cmd->add_option("--normal-map", o->normalMap,
                  "a tangent-space normal map for every surface (after any bump): RGB = (1 + n) / 2 "
                  "in the frame of the surface's tangent along s, the tangent towards the image's top "
                  "(-t: OpenGL's convention, green up) and the normal")
      ->type_name("FILE");
  cmd->add_option("--environment", o->environment,
                  "an environment map (Blinn and Newell 1976) reflected by every metal, plastic and "
                  "default surface whose scene gives none: a lat-long image (+y up, as OpenEXR's; "
                  "'maketx --envlatl' makes a filtered one), KR times the highlights' colour "
                  "(default 1)")
      ->type_name("FILE[:KR]");
  cmd->add_flag("--cull-backfaces", o->cullBackFaces,
                "drop triangles facing away from the eye (default: two-sided)");
  cmd->add_option("--opacity", o->opacity,
                  "opacity of every surface; below 1, linear transparency: each sample blends "
                  "its 4 nearest surfaces front to back")
      ->type_name("ALPHA")
      ->check(Number(1e-3, 1.0))
      ->capture_default_str();
  cmd->add_flag("--hidden-line", o->hiddenLine,
                "hidden-line mode: visible surfaces in white with their triangle edges in black, "
                "unshaded");
  cmd->add_flag("--aov", o->aov,
                "also write the channels Z (eye distance), N.x N.y N.z (world normal), u v and id "
                "(surface index) of the surface covering most of each pixel; .exr only");
  cmd->add_option("--compression", o->compression, raster::ImageWriter::kCompressionHelp)->type_name("METHOD[:LEVEL]");
  cmd->add_option("--crop", o->crop,
                  "render a window of the image: XMIN,XMAX,YMIN,YMAX as fractions of the width and "
                  "height from the top left (RenderMan's CropWindow, which a RIB scene may give); "
                  "the pixels whose centres lie in it, the same as the full render's there, in an "
                  "image of the window's size (EXR and TIFF record where it lies in the frame)")
      ->type_name("X0,X1,Y0,Y1");
  cmd->add_option("--seed", o->seed,
                  "seed of the stochastic extra shading calls (same seed, same image)")
      ->type_name("N")
      ->capture_default_str();
  cmd->add_option("--threads", o->threads,
                  "worker threads (default: one per core). The scene's surfaces are dealt out to "
                  "them and each scans its share row by row (Molnar 1990's object partition); their "
                  "rows are composited by depth in a fixed order, so the image is the same for any "
                  "number. 1: one thread. --overlay uses one worker")
      ->type_name("N")
      ->check(WholeNumber(1, 1024));
  cmd->add_flag("--stats", command->stats, "print counts, times and peak memory to stderr");
  auto* progress = cmd->add_flag("--progress", command->progress,
                                 "show progress on stderr (rows finished, elapsed time, time left) even when "
                                 "stderr is not a terminal (default: only on a terminal)");
  cmd->add_flag("--quiet", command->quiet, "no progress line (errors and warnings are still printed)")->excludes(progress);
  cmd->add_option("--stats-json", command->statsJson, "write counts and times as JSON to this file")->type_name("FILE");
  AddCameraOptions(cmd, &o->camera);
  cmd->add_option_function<std::string>(
         "--frames", [o](const std::string& text) { o->frames = ParseFrames(text); },
         "RIB scenes: render frames A to B (by their FrameBegin numbers) in order, or frame A alone; the "
         "frames before A are not run, so a shadow map they would write must exist already (default: "
         "every frame)")
      ->type_name("A-B")
      ->check(CLI::Validator(
          [](std::string& text) {
            return ParseFrames(text) ? std::string() : "expected A-B or A, whole numbers, A <= B, found '" + text + "'";
          },
          ""))
      ->excludes(cmd->get_option("--frame"));
  command->app = cmd;
  return cmd;
}

std::optional<render::FrameRange> ParseFrames(const std::string& text) {
  const std::size_t dash = text.find('-', 1);
  const std::string first = text.substr(0, dash), last = dash == std::string::npos ? first : text.substr(dash + 1);
  auto whole = [](const std::string& t, int* n) {
    if (t.empty() || t.size() > 10 || t.find_first_not_of("0123456789") != std::string::npos) return false;
    *n = std::stoi(t);
    return true;
  };
  render::FrameRange r;
  if (!whole(first, &r.first) || !whole(last, &r.last) || r.first > r.last) return std::nullopt;
  return r;
}

namespace {

// The options only some modes use: the modes, and how the option returns to its default
// when the chosen mode would ignore it. One rule for all: such an option warns and is
// dropped (pbrt and oiiotool warn of options that do nothing, too).
struct ModalOption {
  const char* name;
  std::vector<render::RenderMode> modes;
  void (*reset)(render::RenderOptions*);
};
using M = render::RenderMode;
const ModalOption kModalOptions[] = {
    {"--theta-steps", {M::Theta}, [](render::RenderOptions* o) { o->thetaSteps = render::RenderOptions{}.thetaSteps; }},
    {"--y-step", {M::Theta}, [](render::RenderOptions* o) { o->yStep = 0.0; }},
    {"--no-extrapolate", {M::Exact, M::Theta}, [](render::RenderOptions* o) { o->noExtrapolate = false; }},
    {"--overlay", {M::Exact, M::Theta}, [](render::RenderOptions* o) { o->overlay = render::Overlay::None; }},
    {"--tess-error", {M::Tess}, [](render::RenderOptions* o) { o->tessError = kDefaultChordErrorPx; }},
    {"--tess-rate", {M::Tess}, [](render::RenderOptions* o) { o->tessRate = 0; }},
    {"--tess-pixels", {M::Tess}, [](render::RenderOptions* o) { o->tessPixels = 0.0; }},
    {"--shading", {M::Tess}, [](render::RenderOptions* o) { o->shading = raster::ShadingMode::Phong; }},
    {"--hidden-line", {M::Tess}, [](render::RenderOptions* o) { o->hiddenLine = false; }},
};

}  // namespace

void DropIgnoredOptions(const CLI::App& cmd, render::RenderOptions* o, std::ostream& err) {
  for (const ModalOption& m : kModalOptions) {
    if (cmd.count(m.name) == 0 || std::find(m.modes.begin(), m.modes.end(), o->mode) != m.modes.end()) continue;
    std::string modes;
    for (const M mode : m.modes) modes += std::string(modes.empty() ? "" : " or ") + render::ModeName(mode);
    err << "patchscan: warning: " << m.name << " is for --mode " << modes << "; --mode " << render::ModeName(o->mode)
        << " ignores it\n";
    m.reset(o);
  }
}

int RunRender(const RenderCommand& c, std::ostream& err) {
  render::CatchInterrupts();
  render::RenderOptions o = c.options;
  if (c.app) DropIgnoredOptions(*c.app, &o, err);
  o.progress = !c.quiet && (c.progress || isatty(STDERR_FILENO) != 0);
  const auto failed = render::RenderFile(o, err, [&](const render::RenderReport& report) -> std::optional<render::Failure> {
    // One line per image written, as a user of pbrt or POV-Ray expects to see it.
    if (!c.quiet) {
      std::ostringstream seconds;
      seconds << std::setprecision(3) << report.load + report.setUp + report.render;
      err << "patchscan: wrote " << report.image << " (" << report.width << "x" << report.height << ", "
          << (report.depthMap ? "depth map" : render::ModeName(report.mode)) << ", " << seconds.str() << " s)\n";
    }
    if (c.stats) render::PrintReport(report, err);
    if (c.statsJson.empty()) return std::nullopt;
    if (const auto why = WriteFileWhole(c.statsJson, render::ReportJson(report)))
      return render::Failure{render::Outcome::OutputError, *why + " (statistics)"};
    return std::nullopt;
  });
  return failed ? Fail(*failed, err) : kExitOk;
}

}  // namespace patchscan::cli
