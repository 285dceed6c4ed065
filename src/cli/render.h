// `patchscan render FILE -o IMAGE`: render a scene to an image file (render/frame.h).
#pragma once

#include <CLI/CLI.hpp>
#include <iosfwd>
#include <string>

#include "cli/choice_option.h"
#include "render/options.h"

namespace patchscan::cli {

inline const ChoiceNames<render::RenderMode> kRenderModeNames = {{"exact", render::RenderMode::Exact},
                                                                 {"theta", render::RenderMode::Theta},
                                                                 {"tess", render::RenderMode::Tess}};

// The render command's options: the library's, and what the program does with its reports.
struct RenderCommand {
  render::RenderOptions options;
  bool stats = false;
  // Progress on stderr: by default only when stderr is a terminal; --progress always,
  // --quiet never.
  bool progress = false, quiet = false;
  std::string statsJson;
};

CLI::App* AddRenderCommand(CLI::App* app, RenderCommand* command);

// Renders; messages to `err`; returns the exit code. The image (and the --stats-json
// file) is written whole or not at all.
int RunRender(const RenderCommand& command, std::ostream& err);

}  // namespace patchscan::cli
