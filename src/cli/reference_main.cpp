// patchscan-reference MAN_PAGE MARKDOWN: writes the man page (patchscan.1) and the Markdown
// reference (docs/cli.md) of the patchscan program, from its own option definitions. Run
// by the build; not installed.
#include <fstream>
#include <iostream>

#include "cli/app.h"
#include "cli/reference.h"
#include "patchscan_version.h"


int main(int argc, char** argv) {
  if (argc != 3) {
    std::cerr << "usage: patchscan-reference MAN_PAGE MARKDOWN\n";
    return 2;
  }
  using namespace patchscan::cli;
  Commands commands;
  const auto app = MakeApp(&commands, PATCHSCAN_VERSION);
  RenderCommand mpiCommand;
  const auto mpi = MakeMpiApp(&mpiCommand, PATCHSCAN_VERSION);
  std::ofstream man(argv[1]), markdown(argv[2]);
  man << ManPage(*app, *mpi, PATCHSCAN_VERSION);
  markdown << MarkdownReference(*app, *mpi);
  if (!man.flush() || !markdown.flush()) {
    std::cerr << "patchscan-reference: cannot write " << argv[1] << " or " << argv[2] << "\n";
    return 1;
  }
  return 0;
}
