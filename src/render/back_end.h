// What a render builds before the first row: the back end's settings (lights, materials,
// textures, shadow maps) from the scene and the options, and the textures the scene makes
// (MakeShadow, MakeLatLongEnvironment).
#pragma once

#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "patch/camera.h"
#include "raster/scanline_renderer.h"
#include "raster/shadow_map.h"
#include "raster/texture.h"
#include "render/options.h"
#include "render/status.h"
#include "scene/scene.h"

namespace patchscan::render {

// The back end's settings and the textures they point to (which must outlive them).
struct BackEndSetup {
  raster::RenderSettings settings;
  std::unique_ptr<raster::ImageTexture> texture;  // RenderOptions::texture, a file
  std::map<std::string, std::unique_ptr<raster::ImageTexture>> sceneTextures;  // by file: the scene's, --bump's
  std::map<std::string, std::unique_ptr<raster::ShadowMap>> shadowMaps;  // by file name
  // Shadow maps that could not be read, each naming the light and the frame that would
  // write the map: the light casts no shadow through them.
  std::vector<std::string> warnings;
  // The first texture that could not be read, if any ("" when none failed).
  std::string TextureError() const;
  // What became of the textures, for reports: "none", "never needed", "opened, N lookups".
  std::string TextureReport() const;
};

// Whether the render writes the frame's depth map: RenderMan's depth displays ("zfile",
// "shadow") when no output is given, whatever the file's extension.
bool WritesDepthMap(const RenderOptions& o, const Scene& scene);

// The settings for rendering `scene` through `camera` at `aa` (the AOV channels made only
// for an output that keeps them: aov, a depth map). Failure: a texture option naming no
// file (BadOption), a scene's texture missing (InputError). A shadow map missing or
// unreadable is a warning, as in RenderMan: a shadow pass not rendered yet does not stop
// the picture.
Result<std::unique_ptr<BackEndSetup>> SetUpBackEnd(const RenderOptions& o, const Scene& scene, const Camera& camera,
                                                   int aa);

// The matrices of `camera` as a light's camera, for the depth maps it renders.
raster::ShadowCamera LightCamera(const Camera& camera);

// Runs the scene's MakeShadow and MakeLatLongEnvironment requests, in order; a warning for
// each that fails, with its file:line and the frame of o.file that writes its input.
std::vector<std::string> MakeTextures(const Scene& scene, const std::string& ribFile);

}  // namespace patchscan::render
