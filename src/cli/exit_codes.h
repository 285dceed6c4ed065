// The program's exit codes: only src/cli picks them.
#pragma once

namespace patchscan::cli {

constexpr int kExitOk = 0;
constexpr int kExitInputError = 1;  // a scene file could not be read or is malformed
constexpr int kExitUsage = 2;       // bad command line or option value
constexpr int kExitOutputError = 3; // an output file could not be written
constexpr int kExitInternal = 70;     // a failure no input explains (sysexits' EX_SOFTWARE): memory exhausted
constexpr int kExitInterrupted = 130; // stopped by SIGINT or SIGTERM (128 + SIGINT, as shells report)

}  // namespace patchscan::cli
