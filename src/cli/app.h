// The patchscan program's command line, whole: every command with its options. main.cpp
// parses with it; the reference generator (cli/reference.h) documents it, so that the man
// page and docs/cli.md cannot drift from --help.
#pragma once

#include <CLI/CLI.hpp>

#include <memory>
#include <string>

#include "cli/compare.h"
#include "cli/convert.h"
#include "cli/info.h"
#include "cli/render.h"

namespace patchscan::cli {

// The values the command line fills, and each command's CLI11 subcommand.
struct Commands {
  InfoOptions info;
  RenderCommand render;
  CompareOptions compare;
  ConvertOptions convert;
  CLI::App* infoCmd = nullptr;
  CLI::App* renderCmd = nullptr;
  CLI::App* compareCmd = nullptr;
  CLI::App* convertCmd = nullptr;
};

// The program's one-line summary (the man page's NAME) and its description.
inline constexpr const char* kSummary = "render parametric surfaces directly, with Blinn's scan-line algorithm";

// The whole command line, writing into *commands (which must outlive it). `version`: what
// --version prints after "patchscan "; `width`: the columns --help is wrapped to.
std::unique_ptr<CLI::App> MakeApp(Commands* commands, const std::string& version, int width = 80);

// patchscan-mpi's command line: the render command alone, writing into *command.
std::unique_ptr<CLI::App> MakeMpiApp(RenderCommand* command, const std::string& version, int width = 80);

}  // namespace patchscan::cli
