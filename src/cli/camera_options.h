// The camera options shared by every command that looks at a scene.
#pragma once

#include <CLI/CLI.hpp>
#include <iosfwd>
#include <optional>
#include <set>
#include <string>

#include "patch/camera.h"
#include "patch/scene.h"

namespace patchscan::cli {

struct CameraOptions {
  std::string size;  // empty: the scene's Format, else 640x480
  std::string eye, lookAt, up;
  std::optional<double> fovDeg;  // none: the scene's Projection, else 30
  std::string hither;  // empty: the scene's Clipping, else automatic
  int frame = -1;      // RIB: the frame to read; -1: the first
  SubdivScheme objScheme = SubdivScheme::CatmullClark;  // .obj: how its cage is subdivided
};

constexpr int kDefaultWidth = 640, kDefaultHeight = 480;
constexpr double kDefaultFovDeg = 30.0;

// Adds --size, --eye, --look-at, --up, --fov and --hither to `cmd`.
void AddCameraOptions(CLI::App* cmd, CameraOptions* opts);

// The camera for `scene`: a RIB scene's own camera unless --eye, --look-at or --up is
// given (--size, --fov and --hither still apply to it); otherwise the options given, with
// automatic framing of the scene's bounds for whatever of eye and look-at is missing. On a bad option value, the message for
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
                                                  const CameraOptions& opts, std::ostream& err,
                                                  std::set<std::string>* warned = nullptr);

// Parses "X,Y,Z" into a vector; nullopt if it is not three finite numbers.
std::optional<Vec3> ParseVec3(const std::string& text);
// Parses "WxH" into positive sizes; nullopt otherwise.
std::optional<std::pair<int, int>> ParseSize(const std::string& text);

}  // namespace patchscan::cli
