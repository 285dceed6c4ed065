// The patchscan program end to end: exit codes, messages naming file:line, help, version.
#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <algorithm>
#include <limits>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "cli/folder.h"

namespace {

const std::string kTeapot = PATCHSCAN_SURFACES_DIR "/teapot.bpt";

// The sRGB encoding of linear v (IEC 61966-2-1), written out here independently of the
// renderer's table.
double Srgb(double v) {
  v = std::clamp(v, 0.0, 1.0);
  return v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1.0 / 2.4) - 0.055;
}

// The value --stats prints for a counter of the table (core/counters.h), by its key; -1 if
// it is not printed.
long StatsValue(const std::string& stats, const std::string& key) {
  const std::size_t at = stats.find("\n  " + key + " ");
  return at == std::string::npos ? -1 : std::stol(stats.substr(at + 3 + key.size()));
}

TEST(Cli, InfoOnTheTeapot) {
  const Result r = Patchscan("info " + kTeapot);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(r.err, "");
  for (const char* line : {"surfaces: 32 (32 bicubic patches)\n", "control points: 512 (290 distinct)\n",
                           "collapsed edges: 8\n",
                           "world bounds: x [-3, 3.525]  y [-2, 2]  z [0, 3.15]\n",
                           "(framed automatically)"})
    EXPECT_NE(r.out.find(line), std::string::npos) << "missing '" << line << "' in\n" << r.out;
  // One line per patch: patch 21's line mentions its collapsed edge at the lid apex.
  int rows = 0;
  for (size_t i = 0; (i = r.out.find(" | x [", i)) != std::string::npos; ++i) ++rows;
  EXPECT_EQ(rows, 32);
}

TEST(Cli, InfoWithAGivenCamera) {
  const Result r = Patchscan("info " + kTeapot +
                          " --size 320x200 --eye 0,-12,4 --look-at 0,0,1.5 --up 0,0,1 --fov 35");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("camera: 320x200, eye 0,-12,4, look-at 0,0,1.5, up 0,0,1, fov 35"),
            std::string::npos)
      << r.out;
  EXPECT_EQ(r.out.find("framed automatically"), std::string::npos);
}

TEST(Cli, MalformedFileNamesFileAndLine) {
  const auto path = std::filesystem::temp_directory_path() / "patchscan_cli_bad.bpt";
  std::ofstream(path) << "1\n3 3\n0 0 0\n1 0\n";
  const Result r = Patchscan("info " + path.string());
  EXPECT_EQ(r.code, 1);
  EXPECT_EQ(r.out, "");
  EXPECT_EQ(r.err, "patchscan: " + path.string() +
                       ":4: expected 3 numbers (x y z of control point 2 of patch 1) alone on "
                       "this line, found 2\n");
  std::filesystem::remove(path);
}

TEST(Cli, MissingFileAndUnknownFormat) {
  Result r = Patchscan("info /nonexistent.bpt");
  EXPECT_EQ(r.code, 1);
  EXPECT_EQ(r.err, "patchscan: /nonexistent.bpt: cannot open: No such file or directory\n");
  r = Patchscan("info " PATCHSCAN_SURFACES_DIR "/README.md");
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find("unknown scene format '.md'"), std::string::npos) << r.err;
}

// A file's extension names its format in capitals too, as files from other systems come.
TEST(Cli, ExtensionsInCapitals) {
  Folder dir("capitals");
  std::filesystem::copy_file(PATCHSCAN_SURFACES_DIR "/quadrics.rib", dir.path / "QUADRICS.RIB");
  std::filesystem::copy_file(PATCHSCAN_SURFACES_DIR "/teapot.bpt", dir.path / "Teapot.Bpt");
  EXPECT_EQ(dir.Run("render QUADRICS.RIB --size 32x24 -o Q.PNG --quiet"), 0) << dir.Err();
  EXPECT_EQ(dir.Run("render Teapot.Bpt --size 32x24 -o T.EXR --quiet"), 0) << dir.Err();
  EXPECT_EQ(Pixels((dir.path / "Q.PNG").string()).size(), 32u * 24u * 4u);
  EXPECT_EQ(Pixels((dir.path / "T.EXR").string()).size(), 32u * 24u * 4u);
}

TEST(Cli, BadOptionsAreUsageErrors) {
  const std::pair<std::string, std::string> cases[] = {
      {"--size 640", "--size: expected WIDTHxHEIGHT with positive whole numbers, found '640'"},
      {"--size 0x10", "--size: expected WIDTHxHEIGHT with positive whole numbers, found '0x10'"},
      {"--eye 1,2", "--eye: expected three numbers X,Y,Z, found '1,2'"},
      {"--look-at a,b,c", "--look-at: expected three numbers X,Y,Z, found 'a,b,c'"},
      {"--up 0,0,0", "--up: the up vector must not be zero"},
      {"--eye 0,0,5 --look-at 0,0,0 --up 0,0,1", "camera: up vector is zero or along the view direction"},
      {"--eye 1,1,1 --look-at 1,1,1", "camera: eye and look-at are the same point"},
      {"--fov 0", "--fov: expected degrees"},
      {"--hither -1", "--hither: expected a positive distance, found '-1'"},
  };
  for (const auto& [args, message] : cases) {
    const Result r = Patchscan("info " + kTeapot + " " + args);
    EXPECT_EQ(r.code, kExitUsage) << args;
    EXPECT_NE(r.err.find(message), std::string::npos) << args << "\n" << r.err;
  }
  EXPECT_EQ(Patchscan("").code, kExitUsage);
  EXPECT_EQ(Patchscan("info").code, kExitUsage);
  EXPECT_EQ(Patchscan("frobnicate").code, kExitUsage);
}

TEST(Cli, HelpDocumentsEveryOptionWithDefaults) {
  const Result top = Patchscan("--help");
  EXPECT_EQ(top.code, 0);
  for (const char* word : {"info", "render", "compare", "convert", "--version", "Exit codes"})
    EXPECT_NE(top.out.find(word), std::string::npos) << "help lacks " << word << "\n" << top.out;
  const Result r = Patchscan("render --help");
  EXPECT_EQ(r.code, 0);
  for (const char* word : {"--frame", "--frames", "--output", "--mode", "--tess-rate", "--aa",
                           "--shading", "--texture", "--cull-backfaces", "--stats", "--stats-json",
                           "--overlay", "--no-extrapolate", "exact",
                           "--size", "640x480", "--eye", "--look-at", "--up", "--fov", "30",
                           "--hither"})
    EXPECT_NE(r.out.find(word), std::string::npos) << "help lacks " << word << "\n" << r.out;
  const Result sub = Patchscan("info --help");
  EXPECT_EQ(sub.code, 0);
  EXPECT_NE(sub.out.find("--look-at"), std::string::npos) << sub.out;
}

TEST(Cli, RenderWritesTheImage) {
  const auto dir = std::filesystem::temp_directory_path() / "patchscan_cli_render";
  std::filesystem::create_directories(dir);
  const std::string out = (dir / "teapot.png").string();
  const Result r = Patchscan("render " + kTeapot + " -o " + out + " --size 96x72 --mode tess --tess-rate 4 --stats");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(std::filesystem::exists(out));
  EXPECT_EQ(StatsValue(r.err, "triangles"), 1024) << r.err;  // 32 x 4 x 4 x 2
  EXPECT_EQ(StatsValue(r.err, "walks"), -1) << "tess mode runs no x scan:\n" << r.err;
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir), {}), 1);
  std::filesystem::remove_all(dir);
}

TEST(Cli, ProgressLineAndQuiet) {
  const auto dir = std::filesystem::temp_directory_path() / "patchscan_cli_progress";
  std::filesystem::create_directories(dir);
  const std::string out = (dir / "teapot.png").string(), js = (dir / "stats.json").string();
  // Not a terminal: no progress line; one line naming the image written, its size, mode
  // and seconds.
  Result r = Patchscan("render " + kTeapot + " -o " + out + " --size 64x48");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(r.err.rfind("patchscan: wrote " + out + " (64x48, exact, ", 0), 0u) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_EQ(r.err.find('\r'), std::string::npos) << r.err;
  // Asked: it ends at 100 % with every row and the time, on a line of its own before --stats.
  r = Patchscan("render " + kTeapot + " -o " + out + " --size 64x48 --progress --stats --threads 2 --stats-json " + js);
  ASSERT_EQ(r.code, 0) << r.err;
  const std::size_t done = r.err.find("\rrender: 100% (48/48 rows, ");
  ASSERT_NE(done, std::string::npos) << r.err;
  EXPECT_LT(done, r.err.find("set up:\n")) << r.err;
  EXPECT_NE(r.err.find(" s)"), std::string::npos) << r.err;
  // The workers' and the compositor's times: one figure per worker.
  EXPECT_NE(r.err.find("workers: 2, seconds scanning each: "), std::string::npos) << r.err;
  const std::string json = Slurp(js);
  const std::size_t w = json.find("\"seconds_workers\": [");
  ASSERT_NE(w, std::string::npos) << json;
  const std::string list = json.substr(w, json.find(']', w) - w);
  EXPECT_EQ(std::count(list.begin(), list.end(), ','), 1) << list;
  EXPECT_NE(json.find("\"seconds_composite\": "), std::string::npos) << json;
  // --quiet: silent, and the two conflict.
  r = Patchscan("render " + kTeapot + " -o " + out + " --size 64x48 --quiet");
  EXPECT_EQ(r.code, 0);
  EXPECT_EQ(r.err, "");
  EXPECT_EQ(Patchscan("render " + kTeapot + " -o " + out + " --quiet --progress").code, kExitUsage);
  std::filesystem::remove_all(dir);
}

TEST(Cli, OpenImageIOIsLoadedOnlyWhenARunNeedsIt) {
  // raster/image_io.h: PNG is encoded by patchscan itself, so a PNG render of a scene without
  // textures never loads OpenImageIO's module (and its 260 libraries); another format does.
  const auto dir = std::filesystem::temp_directory_path() / "patchscan_cli_imageio";
  std::filesystem::create_directories(dir);
  const std::string js = (dir / "stats.json").string();
  Result r = Patchscan("render " + kTeapot + " -o " + (dir / "a.png").string() + " --size 1x1 --stats-json " + js);
  ASSERT_EQ(r.code, 0) << r.err;
  std::string json = Slurp(js);
  EXPECT_NE(json.find("\"image_library_loaded\": false"), std::string::npos) << json;
  EXPECT_NE(json.find("\"cad_library_loaded\": false"), std::string::npos) << json;
#ifndef PATCHSCAN_SANITIZED
  // Start-up in proportion to the run: a 1x1 render resident in under 16 MB (it was 134 MB
  // with OpenImageIO linked in, 39 MB with Open CASCADE; the sanitizers' shadow memory would
  // not fit).
  constexpr long kStartUpKiB = 16 * 1024;
  const std::size_t rss = json.find("\"peak_rss_kib\": ");
  ASSERT_NE(rss, std::string::npos) << json;
  EXPECT_LT(std::stol(json.substr(rss + 16)), kStartUpKiB) << json;
#endif
  r = Patchscan("render " + kTeapot + " -o " + (dir / "a.exr").string() + " --size 1x1 --stats-json " + js);
  ASSERT_EQ(r.code, 0) << r.err;
  json = Slurp(js);
  EXPECT_NE(json.find("\"image_library_loaded\": true"), std::string::npos) << json;
  EXPECT_TRUE(std::filesystem::exists(dir / "a.exr"));
  // A compression the format does not have is a usage error, and nothing is written.
  r = Patchscan("render " + kTeapot + " -o " + (dir / "b.png").string() + " --size 1x1 --compression piz");
  EXPECT_EQ(r.code, kExitUsage);
  EXPECT_NE(r.err.find("compression 'piz' is not one of PNG's"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "b.png"));
  std::filesystem::remove_all(dir);
}

TEST(Cli, ARibDisplaysCompressionIsUsed) {
  // RenderMan's display drivers take "compression": the file the scene names is written
  // with it (unless --compression says otherwise); one its format lacks is refused, naming
  // the Display's line.
  const auto dir = std::filesystem::temp_directory_path() / ("patchscan_cli_display_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  auto scene = [&](const std::string& compression) {
    std::ofstream(dir / "s.rib") << "Format 32 24 1\nDisplay \"c.tif\" \"tiff\" \"rgba\" \"string compression\" [\""
                                  << compression << "\"]\nProjection \"perspective\" \"fov\" [40]\n"
                                  << "Translate 0 -1 8\nWorldBegin\nGeometry \"teapot\"\nWorldEnd\n";
  };
  auto stored = [&] {
    auto in = OIIO::ImageInput::open((dir / "c.tif").string());
    return in ? std::string(in->spec().get_string_attribute("compression")) : std::string("(unreadable)");
  };
  const std::string cd = "cd " + dir.string() + " && " + PATCHSCAN_BINARY + " render s.rib";
  scene("lzw");
  ASSERT_EQ(std::system((cd + " 2>err.txt").c_str()), 0) << Slurp(dir / "err.txt");
  EXPECT_EQ(stored(), "lzw");
  ASSERT_EQ(std::system((cd + " --compression packbits 2>err.txt").c_str()), 0) << Slurp(dir / "err.txt");
  EXPECT_EQ(stored(), "packbits");
  std::filesystem::remove(dir / "c.tif");
  scene("piz");
  EXPECT_EQ(WEXITSTATUS(std::system((cd + " 2>err.txt").c_str())), kExitUsage);
  EXPECT_NE(Slurp(dir / "err.txt").find("s.rib:2: Display: c.tif: compression 'piz' is not one of TIFF's"),
            std::string::npos)
      << Slurp(dir / "err.txt");
  EXPECT_FALSE(std::filesystem::exists(dir / "c.tif"));
  std::filesystem::remove_all(dir);
}

TEST(Cli, ExactModeIsTheDefaultAndReportsItsTrackers) {
  const auto dir = std::filesystem::temp_directory_path() / "patchscan_cli_exact";
  std::filesystem::create_directories(dir);
  const std::string out = (dir / "teapot.png").string(), js = (dir / "stats.json").string();
  Result r = Patchscan("render " + kTeapot + " -o " + out + " --size 96x72 --stats --stats-json " + js +
                       " --overlay trackers");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(std::filesystem::exists(out));
  EXPECT_EQ(StatsValue(r.err, "surfaces"), 32) << r.err;
  EXPECT_GT(StatsValue(r.err, "samples_covered"), 0) << r.err;
  EXPECT_EQ(StatsValue(r.err, "theta_chains"), -1) << "exact mode makes no θ chains:\n" << r.err;
  for (const char* line : {"newton_iterations_per_tracker_row", "\nx scan:\n", "untracked_silhouettes", "peak memory: "})
    EXPECT_NE(r.err.find(line), std::string::npos) << "missing '" << line << "' in\n" << r.err;
  const std::string json = Slurp(js);
  for (const char* key : {"\"mode\": \"exact\"", "\"newton_iterations_per_tracker_row\": ",
                          "\"untracked_silhouettes\": ", "\"failures\": 0", "\"seconds_output\": ",
                          "\"seconds_resolve\": ", "\"seconds_hand_over\": ", "\"seconds_shading\": ["})
    EXPECT_NE(json.find(key), std::string::npos) << key << " in " << json;
  // What needs triangles is ignored in exact mode, and the overlay outside the direct modes,
  // each with a warning: one rule for every option a mode does not use.
  const std::pair<const char*, const char*> ignored[] = {
      {" --shading flat", "--shading is for --mode tess; --mode exact ignores it"},
      {" --hidden-line", "--hidden-line is for --mode tess; --mode exact ignores it"},
      {" --tess-rate 4", "--tess-rate is for --mode tess; --mode exact ignores it"},
      {" --mode tess --overlay trackers", "--overlay is for --mode exact or theta; --mode tess ignores it"},
      {" --mode tess --theta-steps 8", "--theta-steps is for --mode theta; --mode tess ignores it"},
      {" --mode exact --y-step 2", "--y-step is for --mode theta; --mode exact ignores it"},
  };
  for (const auto& [args, warning] : ignored) {
    std::filesystem::remove(out);
    r = Patchscan("render " + kTeapot + " -o " + out + " --size 32x24" + args);
    EXPECT_EQ(r.code, 0) << args << "\n" << r.err;
    EXPECT_NE(r.err.find(std::string("patchscan: warning: ") + warning), std::string::npos) << r.err;
    EXPECT_TRUE(std::filesystem::exists(out));
  }
  // An option the mode uses says nothing.
  r = Patchscan("render " + kTeapot + " -o " + out + " --size 32x24 --mode tess --shading flat --tess-rate 2");
  EXPECT_EQ(r.err.find("warning"), std::string::npos) << r.err;
  std::filesystem::remove_all(dir);
}

TEST(Cli, ThetaStepOfOneSampleRowTakesRowsNotSlabs) {
  // The default (--y-step 0) is rows at any --aa (chains on every row, advanced from the
  // row before); --y-step 1 is one sample row at --aa 1 (rows) and two at --aa 3 (slabs).
  const auto dir = std::filesystem::temp_directory_path() / "patchscan_cli_ystep";
  std::filesystem::create_directories(dir);
  const std::string out = (dir / "teapot.png").string();
  for (const auto& [args, slabs] : {std::pair{" --aa 1", false}, {" --aa 1 --y-step 1", false},
                                    {" --aa 3", false}, {" --aa 3 --y-step 1", true}}) {
    // At 320x240 half the teapot's patches keep their chains at the default 16 steps (at
    // 96x72 all turn too many steps per pixel and take the exact X scan).
    const Result r = Patchscan("render " + kTeapot + " -o " + out + " --size 320x240 --mode theta --stats" + args);
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_EQ(StatsValue(r.err, "slab_triangles") > 0, slabs) << args << "\n" << r.err;
    EXPECT_EQ(StatsValue(r.err, "slab_intervals") > 0, slabs) << args << "\n" << r.err;
    // Rows advance their chains; so do slabs' intervals taken row by row, for the surfaces
    // without the event.
    if (!slabs) {
      EXPECT_GT(StatsValue(r.err, "theta_rows_advanced"), 0) << args << "\n" << r.err;
    }
  }
  std::filesystem::remove_all(dir);
}

TEST(Cli, ThetaSlabsLeaveNoCrackOnASeamSeenExactlyVertical) {
  // surfaces/nurbs.rib's ground is one NURBS surface of 4 x 4 spans, scanned as 16 patches;
  // its camera looks straight down the middle, so the seam between the spans at x = 0 is a
  // vertical line on screen, through a column of samples. Both patches' θ slabs end on it,
  // each at its own tracker's point (equal to rounding): every sample the exact render
  // covers there is covered by θ too (before the shared ends were snapped to a grid, 24
  // pixels of the seam lost one or two of their nine samples).
  const auto dir = std::filesystem::temp_directory_path() / "patchscan_cli_seam";
  std::filesystem::create_directories(dir);
  const std::string scene = std::string(PATCHSCAN_SURFACES_DIR) + "/nurbs.rib";
  const std::string exact = (dir / "exact.png").string(), theta = (dir / "theta.png").string();
  ASSERT_EQ(Patchscan("render " + scene + " --size 480x360 --mode exact -o " + exact).code, 0);
  ASSERT_EQ(Patchscan("render " + scene + " --size 480x360 --mode theta --y-step 1 -o " + theta).code, 0);
  const std::vector<float> a = Pixels(exact), b = Pixels(theta);
  ASSERT_EQ(a.size(), 480u * 360u * 4u);
  ASSERT_EQ(b.size(), a.size());
  int cracked = 0, covered = 0;
  for (int y = 0; y < 360; ++y)
    for (int x = 236; x < 244; ++x) {
      const std::size_t k = (static_cast<std::size_t>(y) * 480 + x) * 4 + 3;
      if (a[k] < 1.0f) continue;
      ++covered;
      if (b[k] < 1.0f) {
        ++cracked;
        ADD_FAILURE() << "pixel (" << x << ", " << y << "): theta alpha " << b[k];
      }
    }
  EXPECT_GT(covered, 1000);
  EXPECT_EQ(cracked, 0);
  std::filesystem::remove_all(dir);
}

TEST(Cli, SameBytesForAnyNumberOfThreads) {
  // --threads N deals the surfaces out to N workers and composites their rows in a fixed
  // order (tests/xscan/partition_test.cpp): the files are the same bytes for every N, in
  // every mode, with the AOVs.
  const auto dir = std::filesystem::temp_directory_path() / "patchscan_cli_threads";
  std::filesystem::create_directories(dir);
  // The lit teapot's texture is looked up from every shading thread.
  const std::string lit = std::string(PATCHSCAN_SURFACES_DIR) + "/teapot_lit.rib";
  for (const std::string& scene : {kTeapot, lit})
  for (const char* mode : {"exact", "theta", "tess"}) {
    for (const char* ext : {".png", ".exr"}) {
      const std::string aov = std::string(ext) == ".exr" ? " --aov" : "";
      const std::string one = (dir / (std::string("one") + ext)).string();
      ASSERT_EQ(Patchscan("render " + scene + " --size 80x60 --mode " + mode + aov + " --threads 1 -o " + one).code, 0);
      for (int n : {2, 3, 7}) {
        const std::string many = (dir / (std::string("many") + ext)).string();
        const Result r = Patchscan("render " + scene + " --size 80x60 --mode " + mode + aov + " --threads " +
                                   std::to_string(n) + " -o " + many);
        ASSERT_EQ(r.code, 0) << r.err;
        // (An EXR's header carries the time it was written: its pixels are compared.)
        if (std::string(ext) == ".png") {
          EXPECT_EQ(Slurp(one), Slurp(many)) << scene << " " << mode << ext << ", --threads " << n;
        } else {
          EXPECT_EQ(Pixels(one), Pixels(many)) << scene << " " << mode << ext << ", --threads " << n;
        }
      }
    }
  }
  std::filesystem::remove_all(dir);
}

TEST(Cli, ThetaSlabsTradeSilhouetteAccuracyForScanLines) {
  // --y-step h: the silhouette between two lines h px apart is a chord, within
  // h/4 + h^2/(8R) px of the curve (tests/xscan/theta_slab_test.cpp); the tightest
  // outline of the teapot at this size (the spout's tip) has R of a few pixels. 0: every
  // sample row has its own chains, and coverage is exact mode's.
  const auto dir = std::filesystem::temp_directory_path() / "patchscan_cli_slabs";
  std::filesystem::create_directories(dir);
  const std::string scene = "render " + kTeapot + " --aov --aa 4 --size 160x120 -o ";
  const std::string exact = (dir / "exact.exr").string();
  ASSERT_EQ(Patchscan(scene + exact).code, 0);
  for (const double h : {0.0, 1.0, 3.0}) {
    const std::string theta = (dir / "theta.exr").string(), js = (dir / "s.json").string();
    std::ostringstream step;
    step << h;
    const Result r = Patchscan(scene + theta + " --mode theta --y-step " + step.str() + " --stats-json " + js);
    ASSERT_EQ(r.code, 0) << r.err;
    const std::string json = Slurp(js);
    // (At 3 px nearly every interval of this small teapot holds an event of some patch
    // and is taken row by row.)
    if (h <= 1.0) {
      EXPECT_EQ(json.find("\"slab_triangles\": 0,") != std::string::npos, h == 0.0) << json;
    }
    const double bound = h == 0.0 ? 1e-9 : h / 4 + h * h / (8 * 3.0);
    std::ostringstream fail;
    fail << " --fail-silhouette " << bound << " --fail-rmse 1 --fail-depth 1 --fail-normal 180 --warn-silhouette " << bound
         << " --warn-rmse 1 --warn-depth 1 --warn-normal 180";
    const Result c = Patchscan("compare " + theta + " " + exact + fail.str());
    EXPECT_EQ(c.code, 0) << "--y-step " << h << ": " << c.out;
  }
  std::filesystem::remove_all(dir);
}

TEST(Cli, FailedRenderLeavesNoFile) {
  // Unknown image format, missing directory, bad scene: no output, non-zero exit.
  Result r = Patchscan("render " + kTeapot + " -o /tmp/patchscan_cli_x.xyz");
  EXPECT_EQ(r.code, kExitUsage);
  EXPECT_NE(r.err.find("unknown image format '.xyz'"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists("/tmp/patchscan_cli_x.xyz"));
  // A file that cannot be created: the output-error code, and the user's name for it (not
  // the temporary file's), in every format.
  for (const char* ext : {"png", "exr", "tif", "jpg"}) {
    const std::string path = std::string("/nonexistent/dir/out.") + ext;
    r = Patchscan("render " + kTeapot + " --size 32x24 -o " + path);
    EXPECT_EQ(r.code, 3) << r.err;
    EXPECT_EQ(r.err, "patchscan: " + path + ": cannot write: No such file or directory\n");
    EXPECT_FALSE(std::filesystem::exists(path));
  }
  r = Patchscan("render /nonexistent.bpt -o /tmp/patchscan_cli_y.png");
  EXPECT_EQ(r.code, 1);
  EXPECT_FALSE(std::filesystem::exists("/tmp/patchscan_cli_y.png"));
  r = Patchscan("render " + kTeapot + " -o /tmp/patchscan_cli_z.png --aa 9");
  EXPECT_EQ(r.code, kExitUsage);
  EXPECT_FALSE(std::filesystem::exists("/tmp/patchscan_cli_z.png"));
}

TEST(Cli, TextureIsOpenedOnlyWhenVisible) {
  const auto dir = std::filesystem::temp_directory_path() / "patchscan_cli_texture";
  std::filesystem::create_directories(dir);
  const std::string tex = (dir / "tex.png").string(), out = (dir / "out.png").string();
  // A 2x2 texture written through the program itself: render anything small to PNG.
  ASSERT_EQ(Patchscan("render " + kTeapot + " -o " + tex + " --size 8x8").code, 0);
  // Looking away from the teapot: no visible sample, so the texture is never opened.
  Result r = Patchscan("render " + kTeapot + " -o " + out + " --size 32x24 --texture " + tex +
                       " --eye 0,-10,1 --look-at 0,-20,1 --stats");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("texture: never needed"), std::string::npos) << r.err;
  r = Patchscan("render " + kTeapot + " -o " + out + " --size 32x24 --texture " + tex + " --stats");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("texture: opened"), std::string::npos) << r.err;
  // A missing file is a usage error; an unreadable one an input error; neither leaves output.
  std::filesystem::remove(out);
  r = Patchscan("render " + kTeapot + " -o " + out + " --texture " + (dir / "none.png").string());
  EXPECT_EQ(r.code, kExitUsage);
  std::ofstream(dir / "bad.png") << "not an image";
  r = Patchscan("render " + kTeapot + " -o " + out + " --size 32x24 --texture " + (dir / "bad.png").string());
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_NE(r.err.find("cannot read texture"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(out));
  std::filesystem::remove_all(dir);
}

TEST(Cli, CompareMeasuresAndAnswersInTheMannerOfIdiff) {
  const auto dir = std::filesystem::temp_directory_path() / "patchscan_cli_compare";
  std::filesystem::create_directories(dir);
  const std::string exact = (dir / "exact.exr").string(), theta = (dir / "theta.exr").string(),
                    small = (dir / "small.exr").string(), diff = (dir / "diff.png").string(),
                    js = (dir / "c.json").string();
  const std::string scene = "render " + kTeapot + " --aov --aa 2 --size 96x72 -o ";
  ASSERT_EQ(Patchscan(scene + exact).code, 0);
  ASSERT_EQ(Patchscan(scene + theta + " --mode theta --theta-steps 4").code, 0);
  ASSERT_EQ(Patchscan("render " + kTeapot + " --aov --size 48x36 -o " + small).code, 0);

  // An image against itself: no error at all.
  Result r = Patchscan("compare " + exact + " " + exact);
  EXPECT_EQ(r.code, 0) << r.out << r.err;
  for (const char* line : {"coverage edges: max 0 px", "depth (relative): max 0,", "colour: RMSE 0,", "PASS"})
    EXPECT_NE(r.out.find(line), std::string::npos) << "missing '" << line << "' in\n" << r.out;
  // Theta with 4 steps against exact: the depth and normals differ between the chords' ends.
  r = Patchscan("compare " + theta + " " + exact + " --json " + js + " --diff " + diff +
                " --fail-normal 0 --warn-normal 0");
  EXPECT_EQ(r.code, 2) << r.out << r.err;
  EXPECT_NE(r.out.find("FAIL: p99 normal angle"), std::string::npos) << r.out;
  EXPECT_TRUE(std::filesystem::exists(diff));
  const std::string json = Slurp(js);
  for (const char* key : {"\"silhouette_px\": {\"max\": ", "\"normal_degrees\": {\"max\": ", "\"verdict\": 2"})
    EXPECT_NE(json.find(key), std::string::npos) << key << " in " << json;
  // The same measures against thresholds that only warn, and against lax ones.
  const std::string lax = " --fail-silhouette 100 --fail-rmse 1 --fail-depth 1 --fail-normal 180";
  r = Patchscan("compare " + theta + " " + exact + lax + " --warn-normal 0");
  EXPECT_EQ(r.code, 1) << r.out;
  EXPECT_NE(r.out.find("WARNING: p99 normal angle"), std::string::npos) << r.out;
  r = Patchscan("compare " + theta + " " + exact + lax +
                " --warn-silhouette 100 --warn-rmse 1 --warn-depth 1 --warn-normal 180");
  EXPECT_EQ(r.code, 0) << r.out;
  // Different sizes 3; unreadable files 4; a bad command line 64, as for every command; the diff image not left
  // behind when it cannot be written.
  EXPECT_EQ(Patchscan("compare " + small + " " + exact).code, 3);
  r = Patchscan("compare " + exact + " " + (dir / "missing.exr").string());
  EXPECT_EQ(r.code, 4);
  EXPECT_NE(r.err.find("missing.exr"), std::string::npos) << r.err;
  EXPECT_EQ(Patchscan("compare " + exact).code, kExitUsage);
  EXPECT_EQ(Patchscan("compare " + exact + " " + exact + " --fail-rmse -1").code, kExitUsage);
  EXPECT_EQ(Patchscan("compare " + exact + " " + exact + " --diff /nonexistent/d.png").code, 4);
  std::filesystem::remove_all(dir);
}

TEST(Cli, InterruptStopsTheRenderAndLeavesNoFile) {
  // A render far too long to finish, interrupted once its temporary file exists (so the
  // signal arrives mid-render, not before the handler is installed).
  const auto dir = std::filesystem::temp_directory_path() / "patchscan_cli_interrupt";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const std::string out = (dir / "big.png").string();
  const pid_t pid = fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    std::freopen("/dev/null", "w", stderr);
    execl(PATCHSCAN_BINARY, PATCHSCAN_BINARY, "render", kTeapot.c_str(), "-o", out.c_str(), "--size",
          "16384x16384", "--aa", "8", static_cast<char*>(nullptr));
    _exit(127);
  }
  bool started = false;
  for (int i = 0; i < 6000 && !started; ++i) {  // up to a minute for the render to start
    for (const auto& e : std::filesystem::directory_iterator(dir))
      started |= e.path().filename().string().find(".partial-") != std::string::npos;
    if (!started) usleep(10000);
  }
  EXPECT_TRUE(started);
  kill(pid, SIGINT);
  int status = 0;
  ASSERT_EQ(waitpid(pid, &status, 0), pid);
  ASSERT_TRUE(WIFEXITED(status)) << "ended by signal " << (WIFSIGNALED(status) ? WTERMSIG(status) : 0);
  EXPECT_EQ(WEXITSTATUS(status), 130);
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir), {}), 0) << "files left in " << dir;
  std::filesystem::remove_all(dir);
}

// A file of several frames renders each to its own Display; a "zfile" or "shadow" Display
// gets the frame's depth map (TIFF, one float channel, whatever its extension); -o takes
// the place of the last frame's picture; --frames A-B renders some of them.
TEST(Cli, EveryFrameRendersToItsDisplay) {
  const auto dir = std::filesystem::temp_directory_path() / ("patchscan_cli_frames_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  std::ofstream(dir / "f.rib") << "Format 64 48 1\nProjection \"perspective\" \"fov\" 40\n"
                                  "FrameBegin 1\nDisplay \"depth.z\" \"zfile\" \"z\"\nTranslate 0 0 5\nWorldBegin\n"
                                  "Sphere 1 -1 1 360\nWorldEnd\nFrameEnd\n"
                                  "FrameBegin 2\nDisplay \"two.png\" \"file\" \"rgba\"\nTranslate 0 0 5\nWorldBegin\n"
                                  "Sphere 1 -1 1 360\nWorldEnd\nFrameEnd\n"
                                  "FrameBegin 3\nDisplay \"map.shd\" \"shadow\" \"z\"\nTranslate 0 0 7\nWorldBegin\n"
                                  "Sphere 1 -1 1 360\nWorldEnd\nFrameEnd\n";
  const std::string cd = "cd " + dir.string() + " && " + PATCHSCAN_BINARY;
  EXPECT_EQ(std::system((cd + " render f.rib 2>err.txt").c_str()), 0) << Slurp(dir / "err.txt");
  EXPECT_TRUE(std::filesystem::exists(dir / "two.png"));
  for (const auto& [name, nearest] : {std::pair{"depth.z", 4.0}, std::pair{"map.shd", 6.0}}) {
    auto in = OIIO::ImageInput::open((dir / name).string());
    ASSERT_TRUE(in) << name;
    const OIIO::ImageSpec& spec = in->spec();
    EXPECT_EQ(spec.nchannels, 1);
    EXPECT_EQ(spec.format, OIIO::TypeDesc::FLOAT);
    std::vector<float> z(static_cast<std::size_t>(spec.width * spec.height));
    ASSERT_TRUE(in->read_image(0, 0, 0, 1, OIIO::TypeDesc::FLOAT, z.data()));
    // The sphere's nearest point, 1 before its centre; no surface: the largest float.
    EXPECT_NEAR(*std::min_element(z.begin(), z.end()), nearest, 1e-2) << name;
    EXPECT_EQ(*std::max_element(z.begin(), z.end()), std::numeric_limits<float>::max()) << name;
  }
  // -o takes the place of the last picture (frame 2's two.png); the depth passes before and
  // after it still write theirs.
  for (const char* name : {"depth.z", "two.png", "map.shd"}) std::filesystem::remove(dir / name);
  Result r = Patchscan("render " + (dir / "f.rib").string() + " -o " + (dir / "one.png").string());
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(std::filesystem::exists(dir / "one.png"));
  EXPECT_FALSE(std::filesystem::exists(dir / "two.png"));
  EXPECT_NE(r.err.find("wrote depth.z (64x48, depth map"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("wrote map.shd (64x48, depth map"), std::string::npos) << r.err;
  // --frames A-B: those frames only, in order.
  std::filesystem::remove(dir / "depth.z");
  EXPECT_EQ(std::system((cd + " render f.rib --frames 2-3 --quiet").c_str()), 0);
  EXPECT_FALSE(std::filesystem::exists(dir / "depth.z"));
  EXPECT_TRUE(std::filesystem::exists(dir / "two.png"));
  // Frames that write only depth maps have no picture for -o; frames the file lacks are
  // named; a file without frames has no --frames.
  r = Patchscan("render " + (dir / "f.rib").string() + " --frames 3 -o " + (dir / "x.png").string());
  EXPECT_EQ(r.code, kExitUsage);
  EXPECT_NE(r.err.find("frame 3 of " + (dir / "f.rib").string() + " writes a depth map, not a picture"),
            std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "x.png"));
  r = Patchscan("render " + (dir / "f.rib").string() + " --frames 5-9");
  EXPECT_EQ(r.code, kExitUsage);
  EXPECT_NE(r.err.find("has no such frame (its frames: 1, 2, 3)"), std::string::npos) << r.err;
  r = Patchscan("render " + kTeapot + " --frames 1 -o " + (dir / "x.png").string());
  EXPECT_EQ(r.code, kExitUsage);
  EXPECT_NE(r.err.find("is not a RIB file"), std::string::npos) << r.err;
  for (const char* bad : {"2-1", "a", "1-", "-3"}) EXPECT_EQ(Patchscan("render " + kTeapot + " --frames " + bad).code, kExitUsage) << bad;
  EXPECT_EQ(Patchscan("render " + kTeapot + " --frame 1 --frames 1").code, kExitUsage);
  std::filesystem::remove_all(dir);
}

// surfaces/still_life.rib, a scene as production exports it: two frames that read one
// world from an archive (polygons, instanced NURBS vases, the teapot, a subdivision cube,
// a torus, curves), a shadow map made between them. Every frame renders, with no warning
// (nothing in it is skipped), in every mode and at any number of threads alike.
TEST(Cli, AProductionSceneRendersEveryFrame) {
  const auto dir = std::filesystem::temp_directory_path() / ("patchscan_cli_still_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string cd = "cd " + dir.string() + " && " + PATCHSCAN_BINARY;
  const std::string scene = PATCHSCAN_SURFACES_DIR "/still_life.rib";
  // --quiet: no line per image, so that any warning shows.
  ASSERT_EQ(std::system((cd + " render " + scene + " --size 240x135 --aa 2 --quiet 2>err.txt").c_str()), 0)
      << Slurp(dir / "err.txt");
  EXPECT_EQ(Slurp(dir / "err.txt"), "");
  EXPECT_TRUE(std::filesystem::exists(dir / "key.z"));
  EXPECT_TRUE(std::filesystem::exists(dir / "key.shd"));
  EXPECT_TRUE(std::filesystem::exists(dir / "still_life.png"));
  for (const char* mode : {"exact", "theta", "tess"}) {
    std::string first;
    for (const char* threads : {"1", "2", "3"}) {
      const std::string out = (dir / (std::string(mode) + threads + ".png")).string();
      ASSERT_EQ(std::system((cd + " render " + scene + " --frame 2 --size 240x135 --aa 2 --mode " + mode + " --threads " +
                             threads + " -o " + out + " 2>err.txt").c_str()),
                0)
          << Slurp(dir / "err.txt");
      if (first.empty()) first = Slurp(out);
      else EXPECT_EQ(Slurp(out), first) << mode << " at " << threads << " threads";
    }
  }
  std::filesystem::remove_all(dir);
}

// An image left empty says so, and names the skipped requests as a possible cause.
TEST(Cli, AnEmptyImageSaysSo) {
  const auto dir = std::filesystem::temp_directory_path() / ("patchscan_cli_empty_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  std::ofstream(dir / "skipped.rib") << "Format 40 30 1\nWorldBegin\nTranslate 0 0 5\nBlobby 0 [] [] []\nBlobby 0 [] [] []\nWorldEnd\n";
  std::ofstream(dir / "away.rib") << "Format 40 30 1\nWorldBegin\nTranslate 0 0 -5\nSphere 1 -1 1 360\nWorldEnd\n";
  Result r = Patchscan("render " + (dir / "skipped.rib").string() + " -o " + (dir / "a.png").string());
  EXPECT_EQ(r.code, 0);
  EXPECT_NE(r.err.find("skipped.rib:4: Blobby is not supported here: skipped (2 times)"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("warning: the image is empty: nothing drawn covers a sample, and 1 kind of request was skipped"),
            std::string::npos) << r.err;
  r = Patchscan("render " + (dir / "away.rib").string() + " -o " + (dir / "b.png").string());
  EXPECT_EQ(r.code, 0);
  EXPECT_NE(r.err.find("warning: the image is empty: no surface covers a sample (1 surfaces"), std::string::npos) << r.err;
  std::filesystem::remove_all(dir);
}

// A RIB scene renders in every mode; its Display names the image when -o is not given;
// --frame chooses a frame; warnings name file:line on stderr.
TEST(Cli, RibScenesRenderInEveryMode) {
  const auto dir = std::filesystem::temp_directory_path() / ("patchscan_cli_rib_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  for (const char* mode : {"exact", "theta", "tess"})
    for (const char* scene : {"quadrics.rib", "teapot_lit.rib", "patchmesh.rib", "cages.rib", "cube_tags.obj", "nurbs.rib", "trimmed.rib",
                              "polygons.rib", "curves.rib"}) {
      const std::string out = (dir / (std::string(mode) + "_" + scene + ".png")).string();
      const Result r = Patchscan("render " PATCHSCAN_SURFACES_DIR "/" + std::string(scene) + " -o " + out +
                                 " --size 96x72 --aa 2 --mode " + mode);
      EXPECT_EQ(r.code, 0) << mode << " " << scene << "\n" << r.err;
      EXPECT_TRUE(std::filesystem::exists(out)) << out;
    }
  std::ofstream(dir / "s.rib") << "Display \"shown.png\" \"file\" \"rgba\"\nFormat 40 30 1\n"
                                  "Hider \"raytrace\"\nTranslate 0 0 5\nFrameBegin 1\nWorldBegin\nSphere 1 -1 1 360\n"
                                  "WorldEnd\nFrameEnd\nFrameBegin 2\nDisplay \"two.png\" \"file\" \"rgba\"\n"
                                  "WorldBegin\nSphere 2 -2 2 360\nWorldEnd\nFrameEnd\n";
  // Display names a file relative to the working directory.
  const std::string cd = "cd " + dir.string() + " && " + PATCHSCAN_BINARY;
  // Every frame, each to its own Display, the warnings of the file once.
  int code = std::system((cd + " render s.rib --mode tess --quiet 2>err.txt").c_str());
  EXPECT_EQ(code, 0);
  EXPECT_TRUE(std::filesystem::exists(dir / "shown.png"));
  EXPECT_TRUE(std::filesystem::exists(dir / "two.png"));
  EXPECT_EQ(Slurp(dir / "err.txt"), "patchscan: warning: " + (std::string("s.rib")) + ":3: Hider 'raytrace' is not supported here: the scan-line hider is used\n");
  std::filesystem::remove(dir / "two.png");
  code = std::system((cd + " render s.rib --frame 2 --mode tess 2>/dev/null").c_str());
  EXPECT_EQ(code, 0);
  EXPECT_TRUE(std::filesystem::exists(dir / "two.png"));
  Result r = Patchscan("info " + (dir / "s.rib").string() + " --frame 2");
  EXPECT_NE(r.out.find("sphere radius 2"), std::string::npos) << r.out;
  r = Patchscan("info " + (dir / "s.rib").string() + " --frame 3");
  EXPECT_EQ(r.code, 1);
  EXPECT_EQ(r.err, "patchscan: " + (dir / "s.rib").string() + ": no FrameBegin 3 in the file\n");
  std::filesystem::remove_all(dir);
}

// convert: the RIB written renders to the same bytes as the .bpt it came from, in each
// mode, for a wide and a tall image (the field of view of the shorter side).
TEST(Cli, ConvertWritesARibThatRendersTheSameImage) {
  const auto dir = std::filesystem::temp_directory_path() / ("patchscan_cli_convert_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  for (const char* size : {"96x72", "60x90"}) {
    const std::string rib = (dir / (std::string(size) + ".rib")).string();
    Result r = Patchscan("convert " + kTeapot + " -o " + rib + " --size " + size);
    ASSERT_EQ(r.code, 0) << r.err;
    for (const char* mode : {"exact", "theta", "tess"}) {
      const std::string a = (dir / "a.png").string(), b = (dir / "b.png").string();
      ASSERT_EQ(Patchscan("render " + kTeapot + " -o " + a + " --size " + size + " --mode " + mode).code, 0);
      ASSERT_EQ(Patchscan("render " + rib + " -o " + b + " --mode " + mode).code, 0);
      EXPECT_EQ(Slurp(a), Slurp(b)) << size << " " << mode;
    }
  }
  // An orthographic RIB camera survives the round trip too.
  std::ofstream(dir / "o.rib") << "Format 64 48 1\nProjection \"orthographic\"\nScreenWindow -4 4 -3 3\n"
                                  "Translate 0 -1 10\nRotate -110 1 0 0\nWorldBegin\nGeometry \"teapot\"\nWorldEnd\n";
  ASSERT_EQ(Patchscan("convert " + (dir / "o.rib").string() + " -o " + (dir / "o2.rib").string()).code, 0);
  for (const char* mode : {"exact", "tess"}) {
    const std::string a = (dir / "a.png").string(), b = (dir / "b.png").string();
    ASSERT_EQ(Patchscan("render " + (dir / "o.rib").string() + " -o " + a + " --mode " + mode).code, 0);
    ASSERT_EQ(Patchscan("render " + (dir / "o2.rib").string() + " -o " + b + " --mode " + mode).code, 0);
    EXPECT_EQ(Slurp(a), Slurp(b)) << "orthographic " << mode;
  }
  // Appearance survives: the quadrics with their colours, shaders, sides and the scene's
  // lights; the lit, textured teapot (its texture named by an absolute path, so the copy
  // renders from another directory). Same bytes, in each mode, at the scene's own size.
  // Subdivision cages are written as the SubdivisionMesh they were read as, an .obj's too;
  // NURBS as the NuPatch of each Bézier piece.
  for (const char* scene : {"quadrics.rib", "teapot_lit.rib", "cages.rib", "cube_tags.obj", "nurbs.rib", "trimmed.rib", "polygons.rib",
                            "curves.rib"}) {
    const std::string source = std::string(PATCHSCAN_SURFACES_DIR) + "/" + scene;
    const std::string copy = (dir / (std::string("copy_") + scene + ".rib")).string();
    ASSERT_EQ(Patchscan("convert " + source + " -o " + copy + " --size 160x120").code, 0) << scene;
    for (const char* mode : {"exact", "theta", "tess"}) {
      const std::string a = (dir / "a.png").string(), b = (dir / "b.png").string();
      ASSERT_EQ(Patchscan("render " + source + " -o " + a + " --size 160x120 --mode " + mode).code, 0);
      ASSERT_EQ(Patchscan("render " + copy + " -o " + b + " --mode " + mode).code, 0);
      EXPECT_EQ(Slurp(a), Slurp(b)) << scene << " " << mode;
    }
  }
  // A scene that cannot be read is refused, and nothing is written.
  std::ofstream(dir / "q.rib") << "WorldBegin\nSubdivisionMesh \"catmull-clark\" [4] [0 1 2 7] \"P\" [0 0 0 1 0 0 1 1 0]\n";
  const Result r = Patchscan("convert " + (dir / "q.rib").string() + " -o " + (dir / "out.rib").string());
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find("q.rib:2:"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "out.rib"));
  std::filesystem::remove_all(dir);
}

TEST(Cli, Version) {
  const Result r = Patchscan("--version");
  EXPECT_EQ(r.code, 0);
  EXPECT_EQ(r.out.rfind("patchscan ", 0), 0u) << r.out;
}

TEST(Cli, PngIsTheExrOfTheSameRenderInSrgb) {
  // The 8-bit PNG holds sRGB-encoded straight colour; the EXR the linear, premultiplied
  // colour of the same render: every pixel agrees to one 8-bit code (and the rounding of
  // half floats, at most 1e-3 relative, which sRGB's slope of 12.92 near black turns into
  // a little more).
  const auto dir = std::filesystem::temp_directory_path() / ("patchscan_cli_srgb_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string png = (dir / "t.png").string(), exr = (dir / "t.exr").string();
  for (const std::string& out : {png, exr})
    ASSERT_EQ(Patchscan("render " + kTeapot + " -o " + out + " --size 96x72 --aa 2").code, 0);
  const std::vector<float> a = Pixels(png), b = Pixels(exr);
  ASSERT_EQ(a.size(), b.size());
  ASSERT_FALSE(a.empty());
  constexpr double kTol = 0.5 / 255 + 0.004;
  int compared = 0;
  for (std::size_t k = 0; k < a.size(); k += 4) {
    const double alpha = b[k + 3];
    EXPECT_NEAR(a[k + 3], alpha, 0.5 / 255 + 1e-3) << "alpha at pixel " << k / 4;
    if (a[k + 3] * 255 < 0.5) continue;
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(a[k + c], Srgb(b[k + c] / alpha), kTol) << "pixel " << k / 4;
    ++compared;
  }
  EXPECT_GT(compared, 1000);
  std::filesystem::remove_all(dir);
}

TEST(Cli, CropRendersAWindowWithTheFullRendersPixels) {
  // --crop and RIB CropWindow: the pixels whose centres lie in the window (RenderMan's
  // rule: from ceil(W xmin) to ceil(W xmax) - 1), bit for bit those of the full render, in
  // every mode and format; an EXR records where the window lies in the frame.
  const auto dir = std::filesystem::temp_directory_path() / ("patchscan_cli_crop_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  constexpr int kW = 160, kH = 120;
  const int x0 = 40, x1 = 96, y0 = 36, y1 = 96;  // ceil(160 0.25), ceil(160 0.6), ceil(120 0.3), ceil(120 0.8)
  for (const char* mode : {"exact", "theta", "tess"})
    for (const char* ext : {".png", ".exr"}) {
      const std::string full = (dir / (std::string("full") + ext)).string();
      const std::string crop = (dir / (std::string("crop") + ext)).string();
      const std::string common = " --size 160x120 --mode " + std::string(mode) + (std::string(ext) == ".exr" ? " --aov" : "");
      ASSERT_EQ(Patchscan("render " + kTeapot + " -o " + full + common).code, 0);
      ASSERT_EQ(Patchscan("render " + kTeapot + " -o " + crop + common + " --crop 0.25,0.6,0.3,0.8").code, 0);
      auto in = OIIO::ImageInput::open(crop);
      ASSERT_TRUE(in);
      EXPECT_EQ(in->spec().width, x1 - x0);
      EXPECT_EQ(in->spec().height, y1 - y0);
      if (std::string(ext) == ".exr") {
        EXPECT_EQ(in->spec().x, x0);
        EXPECT_EQ(in->spec().y, y0);
        EXPECT_EQ(in->spec().full_width, kW);
        EXPECT_EQ(in->spec().full_height, kH);
      }
      const int n = in->spec().nchannels;
      in.reset();
      const std::vector<float> a = Pixels(full), b = Pixels(crop);
      ASSERT_EQ(b.size(), static_cast<std::size_t>((x1 - x0) * (y1 - y0) * n));
      long differ = 0;
      for (int y = y0; y < y1; ++y)
        for (int x = x0; x < x1; ++x)
          for (int c = 0; c < n; ++c)
            differ += std::memcmp(&a[static_cast<std::size_t>((y * kW + x) * n + c)],
                                  &b[static_cast<std::size_t>(((y - y0) * (x1 - x0) + x - x0) * n + c)], sizeof(float)) != 0;
      EXPECT_EQ(differ, 0) << mode << ext;
    }
  // The same window from a RIB scene's CropWindow.
  std::ofstream(dir / "c.rib") << "Format 160 120 1\nCropWindow 0.25 0.6 0.3 0.8\nProjection \"perspective\" \"fov\" 40\n"
                                  "WorldBegin\nTranslate 0 0 5\nSphere 1 -1 1 360\nWorldEnd\n";
  ASSERT_EQ(Patchscan("render " + (dir / "c.rib").string() + " -o " + (dir / "c.png").string()).code, 0);
  const std::vector<float> c = Pixels((dir / "c.png").string());
  EXPECT_EQ(c.size(), static_cast<std::size_t>((x1 - x0) * (y1 - y0) * 4));
  // Windows that are no window, or hold no pixel centre.
  for (const char* bad : {"0.5,0.5,0,1", "0,1,0.6,0.2", "-0.1,0.5,0,1", "0,1,0,1.5", "0.1,0.2,0.3", "a,b,c,d"}) {
    const Result r = Patchscan("render " + kTeapot + " -o " + (dir / "x.png").string() + " --size 160x120 --crop " + bad);
    EXPECT_EQ(r.code, kExitUsage) << bad << "\n" << r.err;
    EXPECT_NE(r.err.find("--crop"), std::string::npos) << r.err;
  }
  const Result none = Patchscan("render " + kTeapot + " -o " + (dir / "x.png").string() + " --size 160x120 --crop 0.001,0.002,0,1");
  EXPECT_EQ(none.code, kExitUsage) << none.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "x.png"));
  std::filesystem::remove_all(dir);
}

}  // namespace
