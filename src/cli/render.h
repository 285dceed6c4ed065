// `patchscan render FILE -o IMAGE`: render a scene to an image file.
#pragma once

#include <CLI/CLI.hpp>
#include <cstdint>
#include <functional>
#include <iosfwd>
#include <memory>
#include <optional>
#include <string>

#include "cli/camera_options.h"
#include "cli/choice_option.h"
#include "raster/scanline_renderer.h"
#include "xscan/partitioned_scan.h"
#include "xscan/tess_feed.h"

namespace patchscan::cli {

constexpr int kDefaultAa = 3;

// Where the back end's samples come from: Blinn's Y scan with the exact X scan or with the
// θ-sampled one (paper 001 §3, §4), or tessellated surfaces.
enum class RenderMode { Exact, Theta, Tess };
inline const ChoiceNames<RenderMode> kRenderModeNames = {
    {"exact", RenderMode::Exact}, {"theta", RenderMode::Theta}, {"tess", RenderMode::Tess}};
// Both direct modes run Blinn's Y scan (they differ in the X scan).
inline bool Direct(RenderMode m) { return m != RenderMode::Tess; }

enum class Overlay { None, Trackers };

struct RenderOptions {
  std::string file, output;
  RenderMode mode = RenderMode::Exact;
  bool noExtrapolate = false;
  int thetaSteps = 16;
  double yStep = 0.0;  // theta mode: pixels between scan lines with chains; 0: every sample row
  Overlay overlay = Overlay::None;
  // Tessellation (xscan/tess_feed.h): uniform at tessRate > 0, or edges tessPixels long,
  // else (the default) a chord error of at most tessError pixels.
  int tessRate = 0;
  double tessPixels = 0.0;
  double tessError = kDefaultChordErrorPx;
  std::optional<int> aa;  // none: a RIB scene's PixelSamples, else kDefaultAa
  raster::ShadingMode shading = raster::ShadingMode::Phong;
  std::string texture = "none";
  bool cullBackFaces = false;
  bool hiddenLine = false;
  double opacity = 1.0;
  bool aov = false;
  std::string compression;  // --compression: the image file's (raster/image_writer.h); "": the format's default
  // --crop "xmin,xmax,ymin,ymax": a window of the frame in RenderMan's NDC (0..1, y down),
  // as RIB CropWindow; empty: the scene's CropWindow, else the whole frame.
  std::string crop;
  std::uint64_t seed = 1;
  int threads = 0;  // 0: one per core
  bool stats = false;
  // Progress on stderr: by default only when stderr is a terminal; --progress always,
  // --quiet never.
  bool progress = false, quiet = false;
  std::string statsJson;
  CameraOptions camera;
  // The direct modes' front end for a frame: by default a PartitionedScan of every surface
  // on `threads` workers; patchscan-mpi gives one shared between its processes.
  std::function<std::unique_ptr<DirectScanSource>(const RenderOptions&, const Scene&, const Camera&,
                                                  const ExactScanOptions&, int aa, int threads)>
      makeDirectScan;
};

// The scan options of a direct render at `aa` (θ steps and the slab height in sample rows).
ExactScanOptions ScanOptionsFor(const RenderOptions& o, int aa);

CLI::App* AddRenderCommand(CLI::App* app, RenderOptions* opts);

// Renders; messages to `err`; returns the exit code. The image (and the --stats-json
// file) is written whole or not at all.
int RunRender(const RenderOptions& opts, std::ostream& err);

}  // namespace patchscan::cli
