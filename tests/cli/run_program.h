// Runs the patchscan program as a user does, for the command-line tests: its exit code,
// stdout and stderr.
#pragma once

#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace {

// A bad command line, for every command (sysexits' EX_USAGE).
constexpr int kExitUsage = 64;

struct Result {
  int code;
  std::string out, err;
};

std::string Slurp(const std::filesystem::path& p) {
  std::ifstream f(p);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

// Runs the program with `args` (shell words), capturing stdout, stderr and the exit code;
// `env`: shell assignments before the command ("COLUMNS=60").
Result Patchscan(const std::string& args, const std::string& env = "") {
  const auto dir = std::filesystem::temp_directory_path();
  const auto out = dir / ("patchscan_cli_out_" + std::to_string(::getpid()));
  const auto err = dir / ("patchscan_cli_err_" + std::to_string(::getpid()));
  const std::string cmd = env + (env.empty() ? "" : " ") + std::string(PATCHSCAN_BINARY) + " " + args + " >" + out.string() +
                          " 2>" + err.string() + " </dev/null";
  const int status = std::system(cmd.c_str());
  Result r{WIFEXITED(status) ? WEXITSTATUS(status) : -1, Slurp(out), Slurp(err)};
  std::filesystem::remove(out);
  std::filesystem::remove(err);
  return r;
}

}  // namespace
