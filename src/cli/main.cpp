// patchscan: the command-line program. The only place that parses arguments, prints to the
// terminal, or picks an exit code.
#include <CLI/CLI.hpp>
#include <iostream>

#include "cli/compare.h"
#include "cli/convert.h"
#include "cli/exit_codes.h"
#include "cli/info.h"
#include "cli/render.h"

#ifndef PATCHSCAN_VERSION
#error "PATCHSCAN_VERSION must be defined by the build"
#endif

int main(int argc, char** argv) {
  using namespace patchscan::cli;
  CLI::App app(
      "patchscan renders parametric surfaces (bicubic patches in any basis, quadrics, NURBS, "
      "subdivision surfaces) "
      "directly, with Blinn's scan-line algorithm, and compares them with tessellated "
      "renders through the same back end.",
      "patchscan");
  app.set_version_flag("--version", std::string("patchscan ") + PATCHSCAN_VERSION);
  app.require_subcommand(1);
  app.footer(
      "Exit codes: 0 success, 1 unreadable or malformed input file, 2 bad command line,\n"
      "3 the output could not be written, 70 an internal failure (memory exhausted), 130\n"
      "interrupted (Ctrl-C or SIGTERM: no output is left behind); 'compare' has its own: see\n"
      "its help.\n"
      "Run 'patchscan COMMAND --help' for one command's options.");

  InfoOptions info;
  CLI::App* infoCmd = AddInfoCommand(&app, &info);
  RenderCommand render;
  CLI::App* renderCmd = AddRenderCommand(&app, &render);
  CompareOptions compare;
  CLI::App* compareCmd = AddCompareCommand(&app, &compare);
  ConvertOptions convert;
  CLI::App* convertCmd = AddConvertCommand(&app, &convert);

  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp&) {
    // Top-level --help documents every command and option; a command's --help, its own.
    const CLI::App* shown = infoCmd->parsed()      ? infoCmd
                            : renderCmd->parsed()  ? renderCmd
                            : compareCmd->parsed() ? compareCmd
                            : convertCmd->parsed() ? convertCmd
                                                   : &app;
    std::cout << (shown == &app ? app.help("", CLI::AppFormatMode::All) : shown->help());
    return kExitOk;
  } catch (const CLI::CallForVersion&) {
    std::cout << app.version() << '\n';
    return kExitOk;
  } catch (const CLI::ParseError& e) {
    std::cerr << "patchscan: " << e.what() << "\nRun 'patchscan --help' for usage.\n";
    // compare's codes follow idiff, where 2 means the images differ.
    return compareCmd->parsed() ? kCompareFileError : kExitUsage;
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
