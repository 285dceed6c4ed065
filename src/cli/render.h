// `patchscan render FILE -o IMAGE`: render a scene to an image file (render/frame.h).
#pragma once

#include <CLI/CLI.hpp>
#include <iosfwd>
#include <optional>
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
  // The command as parsed (set by AddRenderCommand): which options were given.
  const CLI::App* app = nullptr;
};

CLI::App* AddRenderCommand(CLI::App* app, RenderCommand* command);

// "A-B" or "A" (whole numbers, A <= B): --frames.
std::optional<render::FrameRange> ParseFrames(const std::string& text);

// Options given that the chosen mode ignores (--tess-rate in exact mode, --theta-steps in
// tess): a warning each on `err`, and the option back at its default.
void DropIgnoredOptions(const CLI::App& cmd, render::RenderOptions* o, std::ostream& err);

// Renders; messages to `err`; returns the exit code. The image (and the --stats-json
// file) is written whole or not at all.
int RunRender(const RenderCommand& command, std::ostream& err);

}  // namespace patchscan::cli
