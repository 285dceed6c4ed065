#include "cli/help.h"

#include <sys/ioctl.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <sstream>

namespace patchscan::cli {
namespace {

// The option's type name as set (its placeholder) and the descriptions its validators add,
// which CLI11 joins with ':'.
std::vector<std::string> TypeParts(const CLI::Option& o) {
  std::vector<std::string> parts;
  std::stringstream s(o.get_type_name());
  for (std::string part; std::getline(s, part, ':');) parts.push_back(part);
  return parts;
}

// A command's summary in the program's help: its description up to the first full stop
// or colon.
std::string FirstSentence(const std::string& text) {
  const auto end = std::min(text.find(". "), text.find(": "));
  return end == std::string::npos ? text : text.substr(0, end) + '.';
}

}  // namespace

std::vector<const CLI::Option*> VisibleOptions(const CLI::App& cmd) {
  return cmd.get_options([](const CLI::Option* o) { return !o->get_group().empty(); });
}

std::string Spelling(const CLI::Option& o) {
  if (!o.nonpositional()) return o.get_name(true);
  std::string s;
  for (const std::string& n : o.get_snames()) s += (s.empty() ? "-" : ", -") + n;
  for (const std::string& n : o.get_lnames()) s += (s.empty() ? "--" : ", --") + n;
  if (o.get_expected_min() > 0) {
    const auto parts = TypeParts(o);
    s += " " + (parts.empty() || parts[0].empty() ? std::string("VALUE") : parts[0]);
  }
  return s;
}

std::string Usage(const CLI::App& cmd) {
  std::string s = cmd.get_parent() ? cmd.get_parent()->get_name() + " " + cmd.get_name() : cmd.get_name();
  if (!cmd.get_parent() && !cmd.get_subcommands({}).empty()) s += " COMMAND";
  for (const CLI::Option* o : VisibleOptions(cmd))
    if (!o->nonpositional()) s += o->get_required() ? " " + o->get_name(true) : " [" + o->get_name(true) + "]";
  return s + " [options]";
}

std::string Meaning(const CLI::Option& o) {
  std::string bounds;
  const auto parts = TypeParts(o);
  // A choice's words are its placeholder already; a range is said after the meaning.
  for (std::size_t i = 1; i < parts.size(); ++i)
    if (!parts[i].empty() && parts[i][0] != '{') bounds += (bounds.empty() ? "" : ", ") + parts[i];
  const std::string given = o.get_default_str();
  if (!given.empty()) bounds += (bounds.empty() ? "default " : "; default ") + given;
  return bounds.empty() ? o.get_description() : o.get_description() + " (" + bounds + ")";
}

std::string Wrap(const std::string& text, int width, int indent) {
  const std::string pad(static_cast<std::size_t>(std::max(indent, 0)), ' ');
  const std::size_t room = static_cast<std::size_t>(std::max(width - indent, 20));
  std::string out;
  std::stringstream paragraphs(text);
  for (std::string paragraph; std::getline(paragraphs, paragraph);) {
    std::stringstream words(paragraph);
    std::string line;
    for (std::string word; words >> word;) {
      if (!line.empty() && line.size() + 1 + word.size() > room) {
        out += pad + line + '\n';
        line.clear();
      }
      line += (line.empty() ? "" : " ") + word;
    }
    out += pad + line + '\n';
  }
  return out;
}

int TerminalWidth() {
  int columns = 0;
  winsize w{};
  if (isatty(STDOUT_FILENO) && ioctl(STDOUT_FILENO, TIOCGWINSZ, &w) == 0) columns = w.ws_col;
  if (columns <= 0)
    if (const char* env = std::getenv("COLUMNS")) columns = std::atoi(env);
  if (columns <= 0) columns = 80;
  return std::clamp(columns, 40, 120);
}

std::string HelpFormatter::make_help(const CLI::App* app, std::string, CLI::AppFormatMode) const {
  std::ostringstream h;
  h << "Usage: " << Usage(*app) << "\n\n" << Wrap(app->get_description(), width_, 0);
  const auto commands = app->get_subcommands({});
  if (!commands.empty()) {
    h << "\nCommands:\n";
    std::size_t longest = 0;
    for (const CLI::App* c : commands) longest = std::max(longest, c->get_name().size());
    for (const CLI::App* c : commands) {
      const std::string name = "  " + c->get_name() + std::string(longest - c->get_name().size() + 2, ' ');
      const std::string wrapped = Wrap(FirstSentence(c->get_description()), width_, static_cast<int>(name.size()));
      h << name << wrapped.substr(name.size());
    }
  }
  // The options by group, the groups in the order of their first option; positionals first.
  std::vector<std::string> groups{"Arguments"};
  for (const CLI::Option* o : VisibleOptions(*app))
    if (o->nonpositional() && std::find(groups.begin(), groups.end(), o->get_group()) == groups.end())
      groups.push_back(o->get_group());
  for (const std::string& group : groups) {
    std::string listed;
    for (const CLI::Option* o : VisibleOptions(*app))
      if (o->nonpositional() ? o->get_group() == group : group == "Arguments")
        listed += "  " + Spelling(*o) + "\n" + Wrap(Meaning(*o), width_, 8);
    if (!listed.empty()) h << '\n' << group << ":\n" << listed;
  }
  if (!app->get_footer().empty()) h << '\n' << Wrap(app->get_footer(), width_, 0);
  if (!commands.empty()) h << "\nRun '" << app->get_name() << " COMMAND --help' for a command's options.\n";
  return h.str();
}

}  // namespace patchscan::cli
