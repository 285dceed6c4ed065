// `patchscan render FILE -o IMAGE`: render a scene to an image file.
#pragma once

#include <CLI/CLI.hpp>
#include <cstdint>
#include <iosfwd>
#include <optional>
#include <string>

#include "cli/camera_options.h"

namespace patchscan::cli {

constexpr int kDefaultAa = 3;

struct RenderOptions {
  std::string file, output;
  std::string mode = "exact";
  bool noExtrapolate = false;
  int thetaSteps = 16;
  double yStep = 1.0;  // theta mode: pixels between scan lines with chains; 0: every sample row
  std::string overlay = "none";
  int tessRate = 8;
  double tessPixels = 0.0;  // > 0: screen-adaptive tessellation instead of tessRate
  std::optional<int> aa;  // none: a RIB scene's PixelSamples, else kDefaultAa
  std::string shading = "phong";
  std::string texture = "none";
  bool cullBackFaces = false;
  bool hiddenLine = false;
  double opacity = 1.0;
  bool aov = false;
  std::uint64_t seed = 1;
  bool stats = false;
  std::string statsJson;
  CameraOptions camera;
};

CLI::App* AddRenderCommand(CLI::App* app, RenderOptions* opts);

// Renders; messages to `err`; returns the exit code. The image is written whole or not
// at all.
int RunRender(const RenderOptions& opts, std::ostream& err);

}  // namespace patchscan::cli
