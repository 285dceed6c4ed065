// `patchscan info FILE`: what a scene file holds and where its surfaces fall on screen.
#pragma once

#include <CLI/CLI.hpp>
#include <iosfwd>
#include <string>

#include "cli/camera_options.h"

namespace patchscan::cli {

struct InfoOptions {
  std::string file;
  bool json = false;  // one JSON object instead of text
  render::CameraOptions camera;
};

CLI::App* AddInfoCommand(CLI::App* app, InfoOptions* opts);

// Prints the report to `out`, errors to `err`; returns the exit code.
int RunInfo(const InfoOptions& opts, std::ostream& out, std::ostream& err);

}  // namespace patchscan::cli
