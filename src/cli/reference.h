// The command-line reference, generated from the program's own option definitions
// (cli/app.h): a man page (patchscan.1, roff) and a Markdown page (docs/cli.md). Built by
// patchscan-reference at build time, so neither can drift from --help.
#pragma once

#include <CLI/CLI.hpp>

#include <string>
#include <vector>

namespace patchscan::cli {

// The man page of the whole program (`app`, cli::MakeApp) and of patchscan-mpi (`mpi`,
// cli::MakeMpiApp): every command, every option with its default.
std::string ManPage(const CLI::App& app, const CLI::App& mpi, const std::string& version);

// The same as Markdown: a section per command, a table of its options.
std::string MarkdownReference(const CLI::App& app, const CLI::App& mpi);

// Every option a user can give, as "command --long-name" (or "command NAME" for a
// positional argument): what a reference must mention.
std::vector<std::string> OptionNames(const CLI::App& app);

}  // namespace patchscan::cli
