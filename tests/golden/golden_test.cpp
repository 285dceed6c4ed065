// Golden images: renders of the cases in cases.txt compared with the references beside
// it. On failure the actual, reference and difference images are written to the test's
// working directory, and the message names them.
#include <gtest/gtest.h>

#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>

namespace {

// The references were rendered by this program; the same build reproduces them bit for
// bit. Other compilers or libm versions may move a few edge samples and shading values:
// allowed are an RMSE of 1/255 over all channels and at most 0.5% of the pixels differing
// by more than 8/255 in some channel. A real regression (a lost triangle, a wrong light,
// a shifted image) exceeds both by far.
constexpr double kGoldenRmse = 1.0 / 255;
constexpr double kGoldenFailThreshold = 8.0 / 255;
constexpr double kGoldenMaxFailFraction = 0.005;

const std::filesystem::path kGoldenDir = PATCHSCAN_TESTS_DIR "/golden";

struct Case {
  std::string name, args;
};

std::vector<Case> Cases() {
  std::ifstream in(kGoldenDir / "cases.txt");
  std::vector<Case> cases;
  for (std::string line; std::getline(in, line);) {
    if (line.empty() || line[0] == '#') continue;
    const size_t colon = line.find(':');
    cases.push_back({line.substr(0, colon), line.substr(colon + 1)});
  }
  return cases;
}

TEST(Golden, ImagesMatchTheirReferences) {
  const auto cases = Cases();
  ASSERT_GE(cases.size(), 6u);
  for (const Case& c : cases) {
    const std::string actual = c.name + ".actual.png";
    const std::string cmd = std::string(PATCHSCAN_BINARY) + " render " PATCHSCAN_SURFACES_DIR
                            "/teapot.bpt -o " + actual + " " + c.args;
    ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
    OIIO::ImageBuf got(actual), want((kGoldenDir / (c.name + ".png")).string());
    ASSERT_TRUE(got.read() && want.read()) << c.name << ": " << got.geterror() << want.geterror();
    const auto cmp = OIIO::ImageBufAlgo::compare(got, want, static_cast<float>(kGoldenFailThreshold),
                                                 static_cast<float>(kGoldenFailThreshold));
    const double pixels = static_cast<double>(got.spec().width) * got.spec().height;
    const bool ok = cmp.rms_error <= kGoldenRmse &&
                    static_cast<double>(cmp.nfail) <= kGoldenMaxFailFraction * pixels &&
                    got.spec().width == want.spec().width && got.spec().height == want.spec().height;
    if (!ok) {
      const std::string diff = c.name + ".difference.png", ref = c.name + ".reference.png";
      OIIO::ImageBuf d = OIIO::ImageBufAlgo::absdiff(got, want);
      d = OIIO::ImageBufAlgo::mul(d, 8.0f);
      d.write(diff);
      want.write(ref);
      ADD_FAILURE() << c.name << ": rmse " << cmp.rms_error << ", " << cmp.nfail
                    << " pixels off by more than " << kGoldenFailThreshold << "; see "
                    << std::filesystem::absolute(actual) << ", " << ref << ", " << diff
                    << "\n  command: " << cmd;
    } else {
      std::filesystem::remove(actual);
    }
  }
}

}  // namespace
