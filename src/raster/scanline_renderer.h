// The shared scan-line back end (paper 000, Woo and Chall): a y-sorted list of triangles
// with integer sample-row bounds, an active list per sample row, nearest-depth resolve per
// sample on an l x l grid whose samples on pixel edges are shared with the neighbours,
// and one shading call per pixel per visible surface. No image-sized buffer: memory grows
// with the image width and the active set, and each finished row goes to a RowSink.
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include "raster/mesh.h"
#include "raster/shading.h"

namespace patchscan::raster {

enum class ShadingMode { Flat, Gouraud, Phong };

// Largest supersampling grid side: the per-pixel grouping of samples by surface is sized
// for l x l = 64 samples.
constexpr int kMaxAa = 8;

struct RenderSettings {
  int width = 0, height = 0;
  int aa = 1;  // l: l x l samples per pixel (l = 1: one sample at the pixel centre)
  ShadingMode shading = ShadingMode::Phong;
  bool cullBackFaces = false;
  double hither = 0.0;  // eye distance of the hither plane: nearer samples are dropped
  Vec3 eye = Vec3::Zero();
  Material material;
  LightRig lights;
};

// Counts paper 000 reports: n triangles, the most active on one sample row (m), the
// samples tested and covered, and the shading calls.
struct RenderStats {
  std::int64_t nTriangles = 0, nTrianglesSetUp = 0, maxActive = 0;
  std::int64_t nSamplesTested = 0, nSamplesCovered = 0, nShadingCalls = 0;
};

// Receives finished rows top to bottom: `rgba` holds width * 4 floats, colour
// premultiplied by alpha (= coverage). Returning false stops the render.
class RowSink {
 public:
  virtual ~RowSink() = default;
  virtual bool WriteRow(int y, const float* rgba) = 0;
};

// Renders `mesh`. nullopt if the sink stopped it. Allocates only before the first row.
std::optional<RenderStats> RenderMesh(const TriangleMesh& mesh, const RenderSettings& settings,
                                      RowSink& sink);

}  // namespace patchscan::raster
