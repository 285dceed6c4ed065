// What a render is asked for: the scene file, the mode and its knobs, the back end's
// options and the camera's. Plain data: src/cli fills it from the command line, a program
// using the library fills it itself.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>

#include "patch/subdiv.h"
#include "scene/scene.h"
#include "raster/scanline_renderer.h"
#include "xscan/exact_scan.h"
#include "xscan/tess_feed.h"

namespace patchscan::render {

// Supersampling when neither the options nor a RIB scene's PixelSamples say: a 3 x 3 grid
// whose edge samples are shared, 2 x 2 new samples a pixel (Woo and Chall's grid).
constexpr int kDefaultAa = 3;

// Where the back end's samples come from: Blinn's Y scan with the exact X scan or with the
// θ-sampled one (Blinn 1978, §3 and §4), or tessellated surfaces.
enum class RenderMode { Exact, Theta, Tess };
// "exact", "theta" or "tess": the mode's name on the command line and in reports.
const char* ModeName(RenderMode mode);
// Both direct modes run Blinn's Y scan (they differ in the X scan).
inline bool Direct(RenderMode m) { return m != RenderMode::Tess; }

enum class Overlay { None, Trackers };

// The camera: a RIB scene's own, or one framing the scene, adjusted by these (empty: not given).
struct CameraOptions {
  std::string size;  // "WxH"; empty: the scene's Format, else kDefaultWidth x kDefaultHeight
  std::string eye, lookAt, up;  // "X,Y,Z"
  std::optional<double> fovDeg;  // none: the scene's Projection, else kDefaultFovDeg
  std::string hither;  // empty: the scene's Clipping, else automatic
  int frame = -1;      // RIB: the frame to read; -1: the first
  SubdivScheme objScheme = SubdivScheme::CatmullClark;  // .obj: how its cage is subdivided
  bool cadAsNurbs = false;  // CAD: every face as trimmed NURBS (LoadOptions)
};

constexpr int kDefaultWidth = 640, kDefaultHeight = 480;
constexpr double kDefaultFovDeg = 30.0;

class SharedRows;
struct RenderOptions;

// Makes the front end of a frame whose rows are shared between processes (patchscan-mpi,
// render/shared_rows.h) for the scene and camera of the frame.
using ShareRows = std::function<std::unique_ptr<SharedRows>(const RenderOptions&, const Scene&, const Camera&,
                                                            const ExactScanOptions&, int aa, int threads)>;

// Frames first to last of a RIB file, by their FrameBegin numbers.
struct FrameRange {
  int first = 0, last = 0;
};

struct RenderOptions {
  std::string file;  // the scene file
  // The image file; "": the scene's Display, else <stem>.png in the current directory.
  // Of a RIB file of several frames, the picture of the last frame that writes one (the
  // others go to their Displays).
  std::string output;
  std::optional<FrameRange> frames;  // RenderFile: only these frames; none: every frame
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
  std::string texture = "none";  // "none", "checker" or an image file
  // A bump map for every surface without its own: "FILE" or "FILE:AMPLITUDE" (world units
  // per unit of the height texture's value, default 1); "": none.
  std::string bump;
  // An environment map reflected by every metal, plastic and default surface without its own:
  // "FILE" or "FILE:KR" (the share reflected, default 1); "": none.
  std::string environment;
  std::string normalMap;  // a tangent-space normal map for every surface; "": none
  bool cullBackFaces = false;
  bool hiddenLine = false;
  double opacity = 1.0;
  bool aov = false;
  std::string compression;  // the image file's (raster/image_writer.h); "": the format's default
  // "xmin,xmax,ymin,ymax": a window of the frame in RenderMan's NDC (0..1, y down), as RIB
  // CropWindow; empty: the scene's CropWindow, else the whole frame.
  std::string crop;
  std::uint64_t seed = 1;
  int threads = 0;  // 0: one per core
  bool progress = false;  // a progress line on the log while rendering
  CameraOptions camera;
  // Set: the frame's rows are shared between processes, whose front end this makes (else a
  // PartitionedScan of every surface on `threads` workers).
  ShareRows shareRows;
};

// The scan options of a direct render at `aa` (θ steps and the slab height in sample rows).
ExactScanOptions ScanOptionsFor(const RenderOptions& o, int aa);

// The threads this machine runs at once (at least 1).
int Cores();

// The worker threads `threads` asks for: itself, or one per core when 0.
int ThreadsFor(int threads);

}  // namespace patchscan::render
