// patchscan: the command-line program. The only place that parses arguments, prints to the
// terminal, or picks an exit code.
#include <CLI/CLI.hpp>
#include <iostream>

#include "cli/app.h"
#include "cli/exit_codes.h"
#include "cli/help.h"
#include "patchscan_version.h"


int main(int argc, char** argv) {
  using namespace patchscan::cli;
  Commands commands;
  const std::unique_ptr<CLI::App> made = MakeApp(&commands, PATCHSCAN_VERSION, TerminalWidth());
  CLI::App& app = *made;
  CLI::App* infoCmd = commands.infoCmd;
  CLI::App* renderCmd = commands.renderCmd;
  CLI::App* compareCmd = commands.compareCmd;
  CLI::App* convertCmd = commands.convertCmd;
  InfoOptions& info = commands.info;
  RenderCommand& render = commands.render;
  CompareOptions& compare = commands.compare;
  ConvertOptions& convert = commands.convert;

  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp&) {
    // Top-level --help lists the commands; a command's --help gives its options.
    const CLI::App* shown = infoCmd->parsed()      ? infoCmd
                            : renderCmd->parsed()  ? renderCmd
                            : compareCmd->parsed() ? compareCmd
                            : convertCmd->parsed() ? convertCmd
                                                   : &app;
    std::cout << shown->help();
    return kExitOk;
  } catch (const CLI::CallForVersion&) {
    std::cout << app.version() << '\n';
    return kExitOk;
  } catch (const CLI::ParseError& e) {
    const CLI::App* command = infoCmd->parsed()      ? infoCmd
                              : renderCmd->parsed()  ? renderCmd
                              : compareCmd->parsed() ? compareCmd
                              : convertCmd->parsed() ? convertCmd
                                                     : nullptr;
    if (!command && argc > 1 && argv[1][0] != '-') {
      // CLI11 says only that a command is required: name the word it did not know.
      std::string known;
      for (const CLI::App* c : app.get_subcommands({})) known += (known.empty() ? "" : ", ") + c->get_name();
      std::cerr << "patchscan: unknown command '" << argv[1] << "' (the commands: " << known
                << ")\nRun 'patchscan --help' for usage.\n";
      return kExitUsage;
    }
    std::cerr << "patchscan: " << e.what() << "\nRun 'patchscan " << (command ? command->get_name() + " " : "")
              << "--help' for usage.\n";
    return kExitUsage;
  }

  // A failure no command foresaw (memory exhausted, in a worker thread or not): the stack
  // unwinds, so no unfinished output file is left, and the program says so.
  try {
    if (infoCmd->parsed()) return RunInfo(info, std::cout, std::cerr);
    if (renderCmd->parsed()) return RunRender(render, std::cerr);
    if (compareCmd->parsed()) return RunCompare(compare, std::cout, std::cerr);
    if (convertCmd->parsed()) return RunConvert(convert, std::cerr);
  } catch (const std::exception& e) {
    std::cerr << "patchscan: failed: " << e.what() << "; no output written\n";
    return kExitInternal;
  }
  return kExitUsage;
}
