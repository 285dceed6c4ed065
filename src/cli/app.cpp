#include "cli/app.h"

namespace patchscan::cli {

std::unique_ptr<CLI::App> MakeApp(Commands* c, const std::string& version) {
  auto app = std::make_unique<CLI::App>(
      "patchscan renders parametric surfaces (bicubic patches in any basis, quadrics, NURBS, "
      "subdivision surfaces) "
      "directly, with Blinn's scan-line algorithm, and compares them with tessellated "
      "renders through the same back end.",
      "patchscan");
  app->set_version_flag("--version", "patchscan " + version);
  app->require_subcommand(1);
  app->footer(
      "Exit codes: 0 success, 1 unreadable or malformed input file, 2 bad command line,\n"
      "3 the output could not be written, 70 an internal failure (memory exhausted), 130\n"
      "interrupted (Ctrl-C or SIGTERM: no output is left behind); 'compare' has its own: see\n"
      "its help.\n"
      "Run 'patchscan COMMAND --help' for one command's options.");
  c->infoCmd = AddInfoCommand(app.get(), &c->info);
  c->renderCmd = AddRenderCommand(app.get(), &c->render);
  c->compareCmd = AddCompareCommand(app.get(), &c->compare);
  c->convertCmd = AddConvertCommand(app.get(), &c->convert);
  return app;
}

}  // namespace patchscan::cli
