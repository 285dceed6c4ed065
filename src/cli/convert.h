// `patchscan convert FILE -o OUT.rib`: a scene and its camera as a RenderMan RIB file that
// renders the same image.
#pragma once

#include <CLI/CLI.hpp>
#include <iosfwd>
#include <optional>
#include <string>

#include "cli/camera_options.h"

namespace patchscan::cli {

struct ConvertOptions {
  std::string file, output;
  std::optional<int> aa;  // PixelSamples written; none: the render command's default
  std::string display;    // Display's file name written; empty: none
  render::CameraOptions camera;
};

CLI::App* AddConvertCommand(CLI::App* app, ConvertOptions* opts);

// Writes the RIB whole or not at all; messages to `err`; returns the exit code.
int RunConvert(const ConvertOptions& opts, std::ostream& err);

}  // namespace patchscan::cli
