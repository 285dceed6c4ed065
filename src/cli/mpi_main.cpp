// patchscan-mpi: `patchscan render` across MPI processes (mpirun -n N patchscan-mpi render
// FILE ...). Process 0 reads the command line and the scene as patchscan does, scans its
// share of the surfaces, merges every process's rows and writes the image; the others scan
// their shares (shared_scan.h). The image is the one `patchscan render` makes, bit for bit.
#include <mpi.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <iostream>
#include <thread>

#include "cli/app.h"
#include "cli/exit_codes.h"
#include "cli/help.h"
#include "mpi/shared_scan.h"
#include "patchscan_version.h"


int main(int argc, char** argv) {
  using namespace patchscan;
  int provided = 0;
  // Only each process's main thread calls MPI (the scans' threads do not).
  MPI_Init_thread(&argc, &argv, MPI_THREAD_FUNNELED, &provided);
  int rank = 0, size = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);

  cli::RenderCommand command;
  render::RenderOptions& options = command.options;
  const std::unique_ptr<CLI::App> made = cli::MakeMpiApp(&command, PATCHSCAN_VERSION, cli::TerminalWidth());
  CLI::App& app = *made;
  CLI::App* renderCmd = app.get_subcommand("render");
  int code = cli::kExitOk;
  bool parsed = false;
  try {
    app.parse(argc, argv);
    parsed = true;
  } catch (const CLI::CallForHelp&) {
    if (rank == 0) std::cout << (renderCmd->parsed() ? renderCmd->help() : app.help());
  } catch (const CLI::CallForVersion&) {
    if (rank == 0) std::cout << app.version() << '\n';
  } catch (const CLI::ParseError& e) {
    if (rank == 0) std::cerr << "patchscan-mpi: " << e.what() << "\nRun 'patchscan-mpi render --help' for usage.\n";
    code = cli::kExitUsage;
  }
  if (parsed && options.overlay != render::Overlay::None && size > 1) {
    if (rank == 0) std::cerr << "patchscan-mpi: --overlay draws one process's trackers: run it with one process\n";
    code = cli::kExitUsage;
    parsed = false;
  }
  // Every process parsed the same command line, so all agree on whether to go on.
  if (parsed) {
    // Threads by default: the node's cores shared among its processes (one each at least).
    // A core apiece for every process's threads would put several busy threads on each
    // core when processes share a node: three processes on two cores took minutes for a
    // render of a second. An explicit --threads is taken as given, with a note where it
    // oversubscribes the node the same way.
    MPI_Comm node = MPI_COMM_NULL;
    MPI_Comm_split_type(MPI_COMM_WORLD, MPI_COMM_TYPE_SHARED, rank, MPI_INFO_NULL, &node);
    int onNode = 1, nodeRank = 0;
    MPI_Comm_size(node, &onNode);
    MPI_Comm_rank(node, &nodeRank);
    MPI_Comm_free(&node);
    const int cores = std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
    const int share = std::max(1, cores / std::max(onNode, 1));
    if (options.threads <= 0) {
      options.threads = share;
    } else if (nodeRank == 0 && options.threads > share && static_cast<long>(onNode) * options.threads > cores) {
      std::cerr << "patchscan-mpi: note: " << onNode << " processes on this machine with --threads "
                << options.threads << " each want " << static_cast<long>(onNode) * options.threads << " of its "
                << cores << " cores; busy threads sharing a core slow every process down (without --threads each "
                << "takes " << share << ")\n";
    }
  }
  if (parsed) {
    if (rank == 0) {
      options.shareRows = [](const render::RenderOptions& o, const Scene& scene, const Camera& camera,
                             const ExactScanOptions& xo, int aa, int threads) {
        return mpi::MakeSharedScan(MPI_COMM_WORLD, o, scene, camera, xo, aa, threads);
      };
      try {
        code = cli::RunRender(command, std::cerr);
      } catch (const std::exception& e) {
        std::cerr << "patchscan-mpi: failed: " << e.what() << "; no output written\n";
        code = cli::kExitInternal;
      }
      mpi::FinishAll(MPI_COMM_WORLD, code);
    } else {
      code = mpi::ServeFrames(MPI_COMM_WORLD, options);
    }
  }
  MPI_Finalize();
  return code;
}
