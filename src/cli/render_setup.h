// What `render` builds before the first row: the back end's settings (lights, materials,
// textures) from the scene and the options, and the rows' path to the image file (the
// progress line, Ctrl-C).
#pragma once

#include <csignal>
#include <iosfwd>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <variant>

#include "cli/render.h"
#include "patch/camera.h"
#include "patch/scene.h"
#include "raster/scanline_renderer.h"
#include "raster/shadow_map.h"
#include "raster/texture.h"

namespace patchscan::cli {

// The back end's settings and the textures they point to (which must outlive them).
struct BackEndSetup {
  raster::RenderSettings settings;
  std::unique_ptr<raster::ImageTexture> texture;  // --texture FILE
  std::map<std::string, std::unique_ptr<raster::ImageTexture>> sceneTextures;
  std::map<std::string, std::unique_ptr<raster::ShadowMap>> shadowMaps;  // by file name
  // The first texture that could not be read, if any ("" when none failed).
  std::string TextureError() const;
  // What became of the textures, for --stats: "none", "never needed", "opened, N lookups".
  std::string TextureReport() const;
};

// Whether the render writes the frame's depth map: RenderMan's depth displays ("zfile",
// "shadow") when no -o is given, whatever the file's extension.
bool WritesDepthMap(const RenderOptions& o, const Scene& scene);

// The settings for rendering `scene` through `camera` at `aa` (the AOV channels made only
// for an output that keeps them: --aov, a depth map). On a bad option or a missing scene
// texture, prints the message to `err` and returns the exit code.
std::variant<std::unique_ptr<BackEndSetup>, int> SetUpBackEnd(const RenderOptions& o, const Scene& scene,
                                                              const Camera& camera, int aa, std::ostream& err);

// The matrices of `camera` as a light's camera, for the depth maps it renders.
raster::ShadowCamera LightCamera(const Camera& camera);

// The scene's MakeShadow requests, in order; on failure prints the message (file:line)
// and returns the exit code.
std::optional<int> MakeShadows(const Scene& scene, std::ostream& err);

// Set by SIGINT and SIGTERM once CatchInterrupts has run: the render stops at the next row.
extern volatile std::sig_atomic_t gInterrupted;
void CatchInterrupts();

// Passes rows on (none once interrupted), timing how long the next sink (the image writer)
// takes; when stderr is a terminal, shows the percentage done a few times a second.
class ProgressSink final : public raster::RowSink {
 public:
  // With `show`, a line on `err` a few times a second: the share of rows finished (scanned,
  // composited and shaded), the seconds since the start and an estimate of those left.
  ProgressSink(raster::RowSink& next, int height, std::ostream& err, bool show);
  // Clears the line, if an interrupted render left one.
  ~ProgressSink() override;
  bool WriteRow(int y, const float* pixels) override;
  // After the last row: the line at 100 % with the total time, ended, so what follows
  // (--stats) starts on a line of its own.
  void Finish();
  double OutputSeconds() const { return outputSeconds_; }

 private:
  raster::RowSink& next_;
  int height_, rows_ = 0;
  std::ostream& err_;
  bool show_, shown_ = false;
  double outputSeconds_ = 0.0;
  double lastShown_ = -1.0;  // seconds since start when the percentage was last shown
  double start_;
};

}  // namespace patchscan::cli
