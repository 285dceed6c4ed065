#include "cli/app.h"

#include "cli/help.h"

namespace patchscan::cli {

std::unique_ptr<CLI::App> MakeApp(Commands* c, const std::string& version, int width) {
  auto app = std::make_unique<CLI::App>(
      "patchscan renders parametric surfaces (bicubic patches in any basis, quadrics, NURBS, "
      "subdivision surfaces) "
      "directly, with Blinn's scan-line algorithm, and compares them with tessellated "
      "renders through the same back end.",
      "patchscan");
  // Set first: the commands take their parent's formatter when they are added.
  app->formatter(std::make_shared<HelpFormatter>(width));
  app->set_version_flag("--version", "patchscan " + version);
  app->require_subcommand(1);
  app->footer(
      "Exit codes: 0 success, 1 unreadable or malformed input file, 3 the output could not be written, 64 bad "
      "command line (sysexits' EX_USAGE, for every command), 70 an internal failure (memory exhausted), 130 "
      "interrupted (Ctrl-C or SIGTERM: no output is left behind); 'compare' has its own for what it measures: see "
      "its help.");
  c->infoCmd = AddInfoCommand(app.get(), &c->info);
  c->renderCmd = AddRenderCommand(app.get(), &c->render);
  c->compareCmd = AddCompareCommand(app.get(), &c->compare);
  c->convertCmd = AddConvertCommand(app.get(), &c->convert);
  return app;
}

std::unique_ptr<CLI::App> MakeMpiApp(RenderCommand* command, const std::string& version, int width) {
  auto app = std::make_unique<CLI::App>(
      "patchscan-mpi renders a scene across MPI processes (mpirun -n N patchscan-mpi render FILE ...): the "
      "scene's surfaces are dealt out to the processes, each scans its share row by row on its own --threads "
      "(default: the node's cores shared among its processes), and process 0 merges their rows by depth in the "
      "scan order of all surfaces (Molnar 1990's object partition and z-composition) and writes the image: the "
      "same image as 'patchscan render', bit for bit, for any number of processes. Tess mode renders on process "
      "0 alone. Its options are those of 'patchscan render'; --overlay needs one process.",
      "patchscan-mpi");
  app->formatter(std::make_shared<HelpFormatter>(width));
  app->set_version_flag("--version", "patchscan-mpi " + version);
  app->require_subcommand(1);
  app->footer(
      "Exit codes, the same on every process: those of 'patchscan render' (0 success, 1 unreadable input, 3 "
      "unwritable output, 64 bad command line, 70 an internal failure or a failed process, 130 interrupted).");
  AddRenderCommand(app.get(), command);
  return app;
}

}  // namespace patchscan::cli
