// The command line's errors, as a user meets them: the word it did not know, what a value
// should have been, and the help to read next.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <cstdlib>
#include <sstream>
#include <string>

#include "cli/run_program.h"

namespace {

const std::string kTeapot = PATCHSCAN_SURFACES_DIR "/teapot.bpt";

TEST(Usage, AnUnknownCommandIsNamed) {
  const Result r = Patchscan("rendr " + kTeapot);
  EXPECT_EQ(r.code, kExitUsage);
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
    EXPECT_EQ(r.code, kExitUsage) << args;
    EXPECT_NE(r.err.find(message), std::string::npos) << args << "\n" << r.err;
  }
}

TEST(Usage, AThresholdOutOfRangeDoesNotPrintTheLargestDouble) {
  const Result r = Patchscan("compare a.exr b.exr --warn-rmse -1");
  EXPECT_EQ(r.code, kExitUsage);  // a bad command line, as for every command
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

// --help: wrapped to the terminal ($COLUMNS when stdout is not one), options with
// placeholders of their own, never CLI11's type names.
TEST(Usage, HelpFitsTheTerminalWithPlaceholders) {
  for (const int columns : {60, 80, 100}) {
    for (const std::string command : {"", "info ", "render ", "compare ", "convert "}) {
      const Result r = Patchscan(command + "--help", "COLUMNS=" + std::to_string(columns));
      ASSERT_EQ(r.code, 0) << command;
      std::istringstream lines(r.out);
      for (std::string line; std::getline(lines, line);)
        EXPECT_LE(line.size(), static_cast<std::size_t>(columns)) << command << "at " << columns << ": " << line;
      for (const char* cli11 : {" TEXT", " FLOAT", " INT", " UINT", " VALUE", "[1 - "})
        EXPECT_EQ(r.out.find(cli11), std::string::npos) << command << "shows '" << cli11 << "'";
    }
  }
  const Result render = Patchscan("render --help");
  EXPECT_EQ(render.out.rfind("Usage: patchscan render FILE [options]\n", 0), 0u) << render.out;
  for (const char* spelled : {"  -o, --output IMAGE\n", "  --size WxH\n", "  --y-step PX\n", "  --aa N\n",
                              "  --mode exact|theta|tess\n", "  --frames A-B\n", "  --eye X,Y,Z\n"})
    EXPECT_NE(render.out.find(spelled), std::string::npos) << spelled << " in\n" << render.out;
  // The program's help lists the commands, one summary each.
  const Result top = Patchscan("--help");
  EXPECT_NE(top.out.find("Commands:\n  info     Describe a scene file.\n"), std::string::npos) << top.out;
}

// compare and render agree on a bad command line.
TEST(Usage, EveryCommandExitsTheSameOnABadCommandLine) {
  for (const std::string command : {"info", "render", "compare", "convert"})
    EXPECT_EQ(Patchscan(command + " --no-such-option").code, kExitUsage) << command;
  EXPECT_EQ(Patchscan("").code, kExitUsage);
}

// A scene file without a Display and without -o: <stem>.png in the current directory,
// said; an output without an extension: said so.
TEST(Usage, TheOutputWithoutOAndWithoutExtension) {
  const auto dir = std::filesystem::temp_directory_path() / ("patchscan_usage_out_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string cd = "cd " + dir.string() + " && " + PATCHSCAN_BINARY + " render ";
  ASSERT_EQ(std::system((cd + kTeapot + " --size 32x24 2>err.txt").c_str()), 0) << Slurp(dir / "err.txt");
  EXPECT_TRUE(std::filesystem::exists(dir / "teapot.png"));
  EXPECT_NE(Slurp(dir / "err.txt").find("patchscan: note: no -o: writing teapot.png in the current directory\n"),
            std::string::npos) << Slurp(dir / "err.txt");
  ASSERT_EQ(std::system((cd + PATCHSCAN_SURFACES_DIR "/cube_tags.obj --size 32x24 --quiet").c_str()), 0);
  EXPECT_TRUE(std::filesystem::exists(dir / "cube_tags.png"));
  const Result r = Patchscan("render " + kTeapot + " -o " + (dir / "picture").string());
  EXPECT_EQ(r.code, kExitUsage);
  EXPECT_NE(r.err.find("picture: no extension: the image's format follows it (.png"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "picture"));
  std::filesystem::remove_all(dir);
}

// --version: the release (CHANGELOG.md's newest) and, built from a git checkout, the commit.
TEST(Usage, TheVersionIsTheRelease) {
  const Result r = Patchscan("--version");
  EXPECT_EQ(r.code, 0);
  EXPECT_EQ(r.out.rfind("patchscan " PATCHSCAN_RELEASE, 0), 0u) << r.out;
  const std::string changelog = Slurp(PATCHSCAN_SOURCE_DIR "/CHANGELOG.md");
  EXPECT_NE(changelog.find("\n## " PATCHSCAN_RELEASE " "), std::string::npos)
      << "CHANGELOG.md has no section for " PATCHSCAN_RELEASE;
}

}  // namespace
