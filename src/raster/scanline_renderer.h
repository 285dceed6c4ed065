// The shared scan-line back end (Woo and Chall 1990, Woo and Chall): a y-sorted list of triangles
// with integer sample-row bounds, an active list per sample row, nearest-depth resolve per
// sample on an l x l grid whose samples on pixel edges are shared with the neighbours,
// and one shading call per pixel per visible surface. No image-sized buffer: memory grows
// with the image width and the active set, and each finished row goes to a RowSink.
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "core/counters.h"
#include "raster/fragment.h"
#include "raster/mesh.h"
#include "raster/shading.h"

namespace patchscan::raster {

enum class ShadingMode { Flat, Gouraud, Phong };

// Largest supersampling grid side: the per-pixel grouping of samples by surface is sized
// for l x l = 64 samples.
constexpr int kMaxAa = 8;
// With transparency, the nearest fragments kept per sample: beyond four layers of opacity
// 0.5 less than 1/16 of the light remains.
constexpr int kMaxLayers = 4;

// How a depth map's pixel takes its depth from its samples (RenderMan's Hider "hidden"
// "depthfilter"): Surface, the AOV's (the eye distance where the surface covering most of
// the pixel is shaded); the nearest, farthest or mean of the covered samples' nearest
// depths; or Midpoint, the nearest of the samples' midpoints between their two nearest
// distinct surfaces (Woo 1992: a lit surface lies half the occluder's thickness in front of its
// map's depth, so it does not shadow itself without a bias; a sample with one surface has
// nothing behind it to shadow and counts as infinitely far).
enum class DepthFilter { Surface, Min, Max, Average, Midpoint };

struct RenderSettings {
  int width = 0, height = 0;
  int aa = 1;  // l: l x l samples per pixel (l = 1: one sample at the pixel centre)
  ShadingMode shading = ShadingMode::Phong;
  bool cullBackFaces = false;
  double hither = 0.0;  // eye distance of the hither plane: nearer samples are dropped
  double opacity = 1.0;     // (0, 1]: below 1, linear transparency over kMaxLayers layers
  bool hiddenLine = false;  // white surfaces with their triangle edges in black, unshaded
  std::uint64_t seed = 1;   // of the stochastic extra shading calls (Woo and Chall 1990 §3.4.2)
  int threads = 1;          // rows are shaded on this many threads, a few in flight (same image for any)
  // Whether the AOV channels are made (an EXR with them, a depth map); else each pixel's
  // AOV channels hold the background's and only colour and alpha are the render's.
  bool aovs = true;
  Vec3 eye = Vec3::Zero();
  // Orthographic: view rays all run along `forward`; triangles carry their depth in their
  // vertices (W = 1), and fragments' w is that depth.
  bool orthographic = false;
  Vec3 forward = Vec3(0, 0, 1);
  // The camera's projection to pixels, for bump maps (raster/bump.h); zero: none applied.
  ScreenRows screen = ScreenRows::Zero();
  // A render shared between processes (patchscan-mpi): only the pixel rows this owns are
  // rendered and handed to the sink, and only their sample rows asked of the source
  // (empty: every row).
  std::function<bool(int pixelRow)> ownsRow;
  Material material;  // of every surface, unless materialOf is given
  // Per surface id, an index into materials (a scene's own materials); empty: `material`.
  std::vector<Material> materials;
  std::vector<std::uint32_t> materialOf;
  LightRig lights;

  const Material& MaterialOf(std::uint32_t surfaceId) const {
    return materialOf.empty() ? material : materials[materialOf[surfaceId]];
  }
  DepthFilter depthFilter = DepthFilter::Surface;  // of the Z channel (kChannelZ)
  // Whether any surface is seen through (the back end then keeps kMaxLayers per sample).
  bool AnyTransparency() const;
  // The fragments each sample keeps, nearest first: kMaxLayers with transparency, three
  // for a midpoint depth filter (the nearest surface may come twice, at a seam), else one.
  int Layers() const;
  // The point the eye looks from at world point p: the eye, or (orthographic) a unit
  // step back along the view axis.
  Vec3 EyeFor(const Vec3& p) const { return orthographic ? Vec3(p - forward) : eye; }
};

// The channels of a row handed to a RowSink, per pixel.
constexpr int kChannelZ = 4;    // w, the eye distance along the view axis (+inf: no surface)
constexpr int kChannelN = 5;    // 3 channels: unit world normal (0: no surface)
constexpr int kChannelUv = 8;   // 2 channels: surface (u, v) (0: no surface)
constexpr int kChannelId = 10;  // surface id, -1: no surface
constexpr int kChannels = 11;

// Receives finished rows top to bottom: `pixels` holds width * kChannels floats: colour
// premultiplied by alpha (= coverage), alpha, then the AOV channels above, taken from the
// surface covering most of the pixel (with RenderSettings::aovs; else the background's).
// Returning false stops the render.
class RowSink {
 public:
  virtual ~RowSink() = default;
  virtual bool WriteRow(int y, const float* pixels) = 0;
};

// Where a render's back end spent its time, for --stats (seconds of wall clock). The calling
// thread resolves each pixel row's samples in order (asking the source for its rows, so
// waiting for a scan that runs ahead counts here) and hands finished rows to the sink in
// order: those two are the back end's serial part. Pixels are shaded on every thread:
// `shading` holds each thread's seconds shading (one entry per thread of the render).
struct BackEndTimes {
  double resolve = 0.0;
  double handOver = 0.0;
  std::vector<double> shading;
};

// The renders below return the counts Woo and Chall 1990 reports (core/counters.h, the back-end
// group): n triangles, the most active on one sample row (m), the samples tested and
// covered, and the shading calls.

// Renders `mesh`. nullopt if the sink stopped it or the material's texture could not be
// read (the texture's Error() says why). Allocates only before the first row.
std::optional<Counters> RenderMesh(const TriangleMesh& mesh, const RenderSettings& settings,
                                      RowSink& sink, BackEndTimes* times = nullptr);

// Renders the fragments `source` produces row by row (exact renders). Shading mode flat
// and Gouraud and hidden-line mode need triangles and are not applied: every shading call
// uses the fragments' exact normals. A group of samples of one surface in a pixel is
// shaded once with its fragments' attributes averaged.
std::optional<Counters> RenderFragments(FragmentSource& source, const RenderSettings& settings,
                                           RowSink& sink, BackEndTimes* times = nullptr);

}  // namespace patchscan::raster
