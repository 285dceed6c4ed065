// `patchscan compare A B`: how far render A is from the reference render B.
#pragma once

#include <CLI/CLI.hpp>
#include <iosfwd>
#include <string>

namespace patchscan::cli {

// Exit codes of compare, in the manner of OpenImageIO's idiff.
constexpr int kCompareOk = 0;           // every measure within its warning threshold
constexpr int kCompareWarning = 1;      // some measure above its warning threshold only
constexpr int kCompareFailure = 2;      // some measure above its failure threshold
constexpr int kCompareDifferentSize = 3;
constexpr int kCompareFileError = 4;    // an image could not be read or written
// A bad command line: kExitUsage (cli/exit_codes.h), as for every command.

// A measure is checked against a threshold only when it was measured.
struct CompareThresholds {
  double silhouettePx = 0;  // maximum coverage-edge distance, pixels
  double rmse = 0;          // colour RMSE
  double depth = 0;         // 99th percentile relative depth error
  double normalDeg = 0;     // 99th percentile normal angle, degrees
};

struct CompareOptions {
  std::string a, b, diff, json;
  double diffScale = 1.0;
  CompareThresholds warn{0.5, 0.01, 1e-3, 1.0}, fail{1.0, 0.05, 1e-2, 5.0};
};

CLI::App* AddCompareCommand(CLI::App* app, CompareOptions* opts);

// Prints the report to `out`, errors to `err`; returns one of the codes above.
int RunCompare(const CompareOptions& opts, std::ostream& out, std::ostream& err);

}  // namespace patchscan::cli
