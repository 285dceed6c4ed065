// The camera options shared by every command that looks at a scene.
#pragma once

#include <CLI/CLI.hpp>

#include "render/options.h"

namespace patchscan::cli {

// Adds --size, --eye, --look-at, --up, --fov, --hither, --frame and --obj-scheme to `cmd`.
void AddCameraOptions(CLI::App* cmd, render::CameraOptions* opts);

}  // namespace patchscan::cli
