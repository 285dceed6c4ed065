// The command line's errors, as a user meets them: the word it did not know, what a value
// should have been, and the help to read next.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <cstdlib>
#include <string>

#include "cli/run_program.h"

namespace {

const std::string kTeapot = PATCHSCAN_SURFACES_DIR "/teapot.bpt";

TEST(Usage, AnUnknownCommandIsNamed) {
  const Result r = Patchscan("rendr " + kTeapot);
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("unknown command 'rendr' (the commands: info, render, compare, convert)"), std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("Run 'patchscan --help'"), std::string::npos) << r.err;
}

TEST(Usage, AValueOutOfItsKindSaysWhatIsExpected) {
  const std::pair<std::string, std::string> cases[] = {
      {"render " + kTeapot + " -o x.png --aa 3.5", "--aa: expected a whole number from 1 to 8, found '3.5'"},
      {"render " + kTeapot + " -o x.png --aa 9", "--aa: expected a whole number from 1 to 8, found '9'"},
      {"render " + kTeapot + " -o x.png --theta-steps many", "--theta-steps: expected a whole number from 1 to 4096, found 'many'"},
      {"render " + kTeapot + " -o x.png --y-step 100", "--y-step: expected a number from 0 to 64, found '100'"},
      {"render " + kTeapot + " -o x.png --opacity 0", "--opacity: expected a number from 0.001 to 1, found '0'"},
      {"convert " + kTeapot + " -o x.rib --aa 0", "--aa: expected a whole number from 1 to 8, found '0'"},
  };
  for (const auto& [args, message] : cases) {
    const Result r = Patchscan(args);
    EXPECT_EQ(r.code, 2) << args;
    EXPECT_NE(r.err.find(message), std::string::npos) << args << "\n" << r.err;
  }
}

TEST(Usage, AThresholdOutOfRangeDoesNotPrintTheLargestDouble) {
  const Result r = Patchscan("compare a.exr b.exr --warn-rmse -1");
  EXPECT_EQ(r.code, 4);  // compare's bad command line, as idiff's
  EXPECT_NE(r.err.find("--warn-rmse: expected a number of 0 or more, found '-1'"), std::string::npos) << r.err;
  EXPECT_LT(r.err.size(), 200u) << r.err;
}

TEST(Usage, AnErrorPointsToItsCommandsHelp) {
  for (const std::string command : {"info", "render", "compare", "convert"}) {
    const Result r = Patchscan(command + " --no-such-option");
    EXPECT_NE(r.err.find("Run 'patchscan " + command + " --help' for usage."), std::string::npos) << r.err;
  }
}

TEST(Usage, EachImageWrittenIsOneLineUnlessQuiet) {
  const auto dir = std::filesystem::temp_directory_path() / ("patchscan_usage_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  std::filesystem::copy_file(PATCHSCAN_SURFACES_DIR "/shadows.rib", dir / "shadows.rib");
  // Two frames, each to its Display beside the scene: the light's depth map, then the
  // picture that reads it.
  const std::string cd = "cd " + dir.string() + " && " + PATCHSCAN_BINARY + " render shadows.rib --size 64x48";
  ASSERT_EQ(std::system((cd + " 2>err.txt").c_str()), 0) << Slurp(dir / "err.txt");
  const std::string err = Slurp(dir / "err.txt");
  EXPECT_NE(err.find("patchscan: wrote spot.z (64x48, depth map, "), std::string::npos) << err;
  EXPECT_NE(err.find("patchscan: wrote lit.png (64x48, exact, "), std::string::npos) << err;
  EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 2) << err;
  const Result r = Patchscan("render " + kTeapot + " -o " + (dir / "t.png").string() + " --size 32x24 --mode tess --quiet");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(r.err, "");
  std::filesystem::remove_all(dir);
}

}  // namespace
