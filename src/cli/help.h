// `--help` for a terminal: each option on a line of its own with its placeholders
// (`--size WxH`, `--y-step PX`), its meaning wrapped to the terminal's width beneath it,
// as man pages and pbrt's help lay them out. The command-line reference and the man page
// (cli/reference.h) spell options the same way.
#pragma once

#include <CLI/CLI.hpp>
#include <string>

namespace patchscan::cli {

// How an option is written: "-o, --output IMAGE", "--mode exact|theta|tess", "FILE".
std::string Spelling(const CLI::Option& o);

// "patchscan render FILE [options]".
std::string Usage(const CLI::App& cmd);

// The options a user sees (help and version included; those in no group are hidden).
std::vector<const CLI::Option*> VisibleOptions(const CLI::App& cmd);

// The option's meaning with what its value may be and its default:
// "supersampling ... (1 to 8; default 3)".
std::string Meaning(const CLI::Option& o);

// `text` broken at spaces into lines of at most `width` columns (a word longer than that
// stands alone), each indented by `indent` spaces; the text's own line breaks are kept.
std::string Wrap(const std::string& text, int width, int indent);

// The columns of the terminal on standard output: its window's, else $COLUMNS, else 80;
// at least 40 and at most 120 (longer lines are hard to read).
int TerminalWidth();

// CLI11's help formatter, replaced: a program's help lists its commands with their first
// sentence; a command's gives its usage, description and options, wrapped to `width`.
class HelpFormatter : public CLI::Formatter {
 public:
  explicit HelpFormatter(int width) : width_(width) {}
  std::string make_help(const CLI::App* app, std::string name, CLI::AppFormatMode mode) const override;

 private:
  int width_;
};

}  // namespace patchscan::cli
