// The camera options shared by every command that looks at a scene.
#pragma once

#include <CLI/CLI.hpp>
#include <iosfwd>
#include <optional>
#include <string>

#include "patch/camera.h"
#include "patch/scene.h"

namespace patchscan::cli {

struct CameraOptions {
  std::string size = "640x480";
  std::string eye, lookAt, up;
  double fovDeg = 30.0;
  std::string hither;  // empty: automatic
};

// Adds --size, --eye, --look-at, --up, --fov and --hither to `cmd`.
void AddCameraOptions(CLI::App* cmd, CameraOptions* opts);

// The camera for `scene`: the options given, with automatic framing of the scene's bounds
// for whatever of eye and look-at is missing. On a bad option value, the message for
// the user. `framed` says whether automatic framing chose the eye.
struct ResolvedCamera {
  Camera camera;
  bool framed = false;
};
std::variant<ResolvedCamera, std::string> ResolveCamera(const CameraOptions& opts,
                                                        const Scene& scene);

// Loads a scene file and resolves the camera for it. On failure, prints the message to
// `err` and returns the exit code to end with.
struct LoadedScene {
  Scene scene;
  ResolvedCamera view;
};
std::variant<LoadedScene, int> LoadSceneAndCamera(const std::string& file,
                                                  const CameraOptions& opts, std::ostream& err);

// Parses "X,Y,Z" into a vector; nullopt if it is not three finite numbers.
std::optional<Vec3> ParseVec3(const std::string& text);
// Parses "WxH" into positive sizes; nullopt otherwise.
std::optional<std::pair<int, int>> ParseSize(const std::string& text);

}  // namespace patchscan::cli
