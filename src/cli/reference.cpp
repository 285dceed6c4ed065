#include "cli/reference.h"

#include <sstream>

#include "cli/app.h"
#include "cli/help.h"

namespace patchscan::cli {
namespace {

// The commands in the order they were added.
std::vector<const CLI::App*> CommandsOf(const CLI::App& app) { return app.get_subcommands({}); }

// roff: a backslash printed as \e, a line starting with . or ' guarded, a hyphen in an
// option's name as \- (a minus sign, which a reader can copy and type).
std::string Roff(const std::string& text) {
  std::string out;
  bool lineStart = true;
  for (const char ch : text) {
    if (lineStart && (ch == '.' || ch == '\'')) out += "\\&";
    if (ch == '\\') out += "\\e";
    else out += ch;
    lineStart = ch == '\n';
  }
  return out;
}
std::string RoffName(const std::string& text) {
  std::string out;
  for (const char ch : text) out += ch == '-' ? std::string("\\-") : std::string(1, ch);
  return out;
}

// Markdown table cells: no pipe, no line break.
std::string Cell(const std::string& text) {
  std::string out;
  for (const char ch : text) out += ch == '|' ? std::string("\\|") : ch == '\n' ? std::string(" ") : std::string(1, ch);
  return out;
}

}  // namespace

std::string ManPage(const CLI::App& app, const CLI::App& mpi, const std::string& version) {
  std::ostringstream m;
  m << ".TH PATCHSCAN 1 \"\" \"patchscan " << Roff(version) << "\" \"User Commands\"\n"
    << ".SH NAME\npatchscan \\- " << Roff(kSummary) << "\n"
    << ".SH SYNOPSIS\n";
  for (const CLI::App* cmd : CommandsOf(app)) m << ".B " << RoffName(Usage(*cmd)) << "\n.br\n";
  m << ".B patchscan \\-\\-help\n.br\n.B patchscan \\-\\-version\n"
    << ".SH DESCRIPTION\n" << Roff(app.get_description()) << "\n";
  for (const CLI::App* cmd : CommandsOf(app)) {
    m << ".SH \"" << RoffName("patchscan " + cmd->get_name()) << "\"\n" << Roff(cmd->get_description()) << "\n";
    for (const CLI::Option* o : VisibleOptions(*cmd)) {
      m << ".TP\n.B " << RoffName(Spelling(*o)) << "\n" << Roff(Meaning(*o)) << "\n";
    }
  }
  // patchscan-mpi: its render command takes the options of patchscan's (the test
  // Reference.MpiTakesTheRenderOptions holds it to that).
  for (const CLI::App* cmd : CommandsOf(mpi))
    m << ".SH \"" << RoffName(Usage(*cmd)) << "\"\n" << Roff(mpi.get_description()) << "\n.PP\n"
      << Roff(mpi.get_footer()) << "\n";
  m << ".SH \"EXIT STATUS\"\n" << Roff(app.get_footer()) << "\n"
    << ".SH \"SEE ALSO\"\n"
    << "The documentation in docs/ of the source distribution: docs/index.md.\n";
  return m.str();
}

std::string MarkdownReference(const CLI::App& app, const CLI::App& mpi) {
  std::ostringstream m;
  m << "# Command-line reference\n\n"
    << "Generated from the program's own option definitions (`patchscan-reference`, at build\n"
    << "time); the same text as `patchscan COMMAND --help` and `man patchscan`.\n\n"
    << app.get_description() << "\n\n";
  for (const CLI::App* cmd : CommandsOf(app)) {
    m << "## patchscan " << cmd->get_name() << "\n\n"
      << "```\n" << Usage(*cmd) << "\n```\n\n"
      << cmd->get_description() << "\n\n"
      << "| option | meaning |\n|---|---|\n";
    for (const CLI::Option* o : VisibleOptions(*cmd))
      m << "| `" << Cell(Spelling(*o)) << "` | " << Cell(Meaning(*o)) << " |\n";
    m << "\n";
  }
  for (const CLI::App* cmd : CommandsOf(mpi))
    m << "## patchscan-mpi " << cmd->get_name() << "\n\n```\n" << Usage(*cmd) << "\n```\n\n" << mpi.get_description()
      << "\n\n" << mpi.get_footer() << "\n\n";
  m << "## Exit codes\n\n" << app.get_footer() << "\n";
  return m.str();
}

std::vector<std::string> OptionNames(const CLI::App& app) {
  std::vector<std::string> names;
  for (const CLI::App* cmd : CommandsOf(app))
    for (const CLI::Option* o : VisibleOptions(*cmd)) {
      if (!o->nonpositional()) names.push_back(cmd->get_name() + " " + o->get_name(true));
      for (const std::string& n : o->get_lnames()) names.push_back(cmd->get_name() + " --" + n);
      for (const std::string& n : o->get_snames()) names.push_back(cmd->get_name() + " -" + n);
    }
  return names;
}

}  // namespace patchscan::cli
