// The program's exit codes: only src/cli picks them.
#pragma once

#include <ostream>

#include "render/status.h"

namespace patchscan::cli {

constexpr int kExitOk = 0;
constexpr int kExitInputError = 1;  // a scene file could not be read or is malformed
// A bad command line or option value, for every command: sysexits' EX_USAGE, which no
// command's own codes use (compare's 2 means a measure past its failure threshold).
constexpr int kExitUsage = 64;
constexpr int kExitOutputError = 3; // an output file could not be written
constexpr int kExitInternal = 70;     // a failure no input explains (sysexits' EX_SOFTWARE): memory exhausted
constexpr int kExitInterrupted = 130; // stopped by SIGINT or SIGTERM (128 + SIGINT, as shells report)

// The exit code for a failure of the library's.
constexpr int ExitCode(render::Outcome outcome) {
  switch (outcome) {
    case render::Outcome::BadOption: return kExitUsage;
    case render::Outcome::InputError: return kExitInputError;
    case render::Outcome::OutputError: return kExitOutputError;
    case render::Outcome::Interrupted: return kExitInterrupted;
  }
  return kExitInternal;
}

// Prints the failure's message as the program's and returns its exit code.
inline int Fail(const render::Failure& f, std::ostream& err) {
  err << "patchscan: " << f.message << '\n';
  return ExitCode(f.outcome);
}

}  // namespace patchscan::cli
