// A scene file and the camera that looks at it: read, the camera resolved from the scene
// and the options, and what every render through the library sets the same way.
#pragma once

#include <iosfwd>
#include <optional>
#include <set>
#include <string>
#include <utility>

#include "patch/camera.h"
#include "raster/mesh.h"
#include "raster/scanline_renderer.h"
#include "render/options.h"
#include "render/status.h"
#include "scene/scene.h"

namespace patchscan::render {

// The camera for `scene`: a RIB scene's own camera unless an eye, look-at or up is given
// (size, fov and hither still apply to it); otherwise the options given, with automatic
// framing of the scene's bounds for whatever of eye and look-at is missing. `framed` says
// whether automatic framing chose the eye. On a bad option value, the message for the user.
struct ResolvedCamera {
  Camera camera;
  bool framed = false;
};
std::variant<ResolvedCamera, std::string> ResolveCamera(const CameraOptions& opts, const Scene& scene);

// Reads a scene file and resolves its camera; the curves face it. The scene's warnings
// ("patchscan: warning: ...") go to `log`, each once when `warned` (those already
// given) is passed. Failure: InputError for the file, BadOption for the camera.
// Writes "patchscan: warning: WARNING" to `log`, unless `warned` holds it already (it is
// added).
void Warn(const std::string& warning, std::ostream& log, std::set<std::string>* warned);

struct LoadedScene {
  Scene scene;
  ResolvedCamera view;
};
Result<LoadedScene> LoadSceneAndCamera(const std::string& file, const CameraOptions& opts, std::ostream& log,
                                       std::set<std::string>* warned = nullptr);

// Parses "X,Y,Z" into a vector; nullopt if it is not three finite numbers.
std::optional<Vec3> ParseVec3(const std::string& text);
// Parses "WxH" into positive sizes; nullopt otherwise.
std::optional<std::pair<int, int>> ParseSize(const std::string& text);

// The back end's settings for what `camera` sees at `aa`: the image, the eye and the view
// axis; the default material and lights. Every render through the library starts from these.
raster::RenderSettings SettingsFor(const Camera& camera, int aa);

// The triangles of the scene's polygons for `camera` appended to `out`, its polygons[k]'s
// with surface id surfaces.size() + k (after every surface's).
void AppendScenePolygons(const Scene& scene, const Camera& camera, raster::TriangleMesh* out);
// The same triangles on their own.
raster::TriangleMesh PolygonTriangles(const Scene& scene, const Camera& camera);

}  // namespace patchscan::render
