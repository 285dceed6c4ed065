// The .bpt reader: the teapot set's invariants, the format's accepted variants, and the
// exact message for every kind of malformed input.
#include <gtest/gtest.h>

#include <fstream>
#include <set>
#include <sstream>

#include "patch/bicubic.h"
#include "scene/bpt_reader.h"
#include "scene/text_file.h"

namespace patchscan {
namespace {

std::string Surfaces(const char* name) { return std::string(PATCHSCAN_SURFACES_DIR "/") + name; }

BptFile MustRead(const std::string& path) {
  auto r = ReadBpt(path);
  if (auto* e = std::get_if<SourceError>(&r)) ADD_FAILURE() << e->What();
  return std::get<BptFile>(r);
}

TEST(BptReader, TeapotInvariants) {
  // shared data/README.md: 32 patches, 512 points, 290 distinct, 8 collapsed edges, and
  // the bounding box x [-3, 3.525], y [-2, 2], z [0, 3.15].
  const BptFile f = MustRead(Surfaces("teapot.bpt"));
  ASSERT_EQ(f.patches.size(), 32u);
  std::set<std::tuple<double, double, double>> distinct;
  Bounds3 box;
  int points = 0, collapsed = 0;
  for (const BptPatch& p : f.patches) {
    for (const Vec3& q : p.cv) {
      distinct.insert({q.x(), q.y(), q.z()});
      box.Extend(q);
      ++points;
    }
    collapsed += std::popcount(CollapsedEdges(BicubicPatch(p.cv)));
  }
  EXPECT_EQ(points, 512);
  EXPECT_EQ(distinct.size(), 290u);
  EXPECT_EQ(collapsed, 8);
  EXPECT_EQ(box.lo, Vec3(-3, -2, 0));
  EXPECT_EQ(box.hi, Vec3(3.525, 2, 3.15));
  EXPECT_EQ(f.patches[0].line, 2);
  EXPECT_EQ(f.patches[1].line, 19);
}

TEST(BptReader, TeacupAndTeaspoon) {
  EXPECT_EQ(MustRead(Surfaces("teacup.bpt")).patches.size(), 26u);
  EXPECT_EQ(MustRead(Surfaces("teaspoon.bpt")).patches.size(), 16u);
}

std::string TeapotText() {
  return std::get<std::string>(ReadTextFile(Surfaces("teapot.bpt")));
}

void ExpectSamePatches(const BptFile& a, const BptFile& b) {
  ASSERT_EQ(a.patches.size(), b.patches.size());
  for (size_t i = 0; i < a.patches.size(); ++i)
    for (int k = 0; k < 16; ++k) EXPECT_EQ(a.patches[i].cv[k], b.patches[i].cv[k]);
}

TEST(BptReader, AcceptsTheFormatsVariants) {
  const std::string text = TeapotText();
  const BptFile ref = std::get<BptFile>(ParseBpt(text, "teapot"));
  auto replaced = [&](const std::string& from, const std::string& to) {
    std::string s;
    for (size_t i = 0; i < text.size();) {
      if (text.compare(i, from.size(), from) == 0) {
        s += to;
        i += from.size();
      } else {
        s += text[i++];
      }
    }
    return s;
  };
  const std::pair<const char*, std::string> variants[] = {
      {"CRLF", replaced("\n", "\r\n")},
      {"tabs", replaced(" ", "\t")},
      {"4 4 point counts", replaced("3 3\n", "4 4\n")},
      {"comments", "# the Utah teapot\n" + replaced("\n", "   # a comment 1 2 3\n")},
      {"everything on one line", replaced("\n", " ")},
      {"no final newline", text.substr(0, text.size() - 1)},
  };
  for (const auto& [name, variant] : variants) {
    auto r = ParseBpt(variant, name);
    if (auto* e = std::get_if<SourceError>(&r)) {
      ADD_FAILURE() << name << ": " << e->What();
      continue;
    }
    ExpectSamePatches(std::get<BptFile>(r), ref);
  }
}

// One flat patch in line layout: count on line 1, dimensions on line 2, points on 3-18.
std::string OnePatch() {
  std::ostringstream s;
  s << "1\n3 3\n";
  for (int j = 0; j < 4; ++j)
    for (int i = 0; i < 4; ++i) s << i << ' ' << j << " 0\n";
  return s.str();
}

std::string WithLine(int line, const std::string& replacement) {
  std::istringstream in(OnePatch());
  std::string out, l;
  for (int n = 1; std::getline(in, l); ++n) out += (n == line ? replacement : l) + "\n";
  return out;
}

TEST(BptReader, MalformedInputGetsAnExactMessage) {
  ASSERT_TRUE(std::holds_alternative<BptFile>(ParseBpt(OnePatch(), "t.bpt")));
  const std::string count = "expected the patch count, a whole number from 1 to 10000000, found ";
  const std::pair<std::string, std::string> cases[] = {
      {"", "t.bpt:1: " + count + "end of file"},
      {"# only a comment\n", "t.bpt:1: " + count + "end of file"},
      {WithLine(1, "-3"), "t.bpt:1: " + count + "'-3'"},
      {WithLine(1, "0"), "t.bpt:1: " + count + "'0'"},
      {WithLine(1, "99999999999"), "t.bpt:1: " + count + "'99999999999'"},
      {WithLine(1, "1.5"), "t.bpt:1: " + count + "'1.5'"},
      {WithLine(1, "abc"), "t.bpt:1: " + count + "'abc'"},
      {WithLine(1, "2"),
       "t.bpt:18: expected patch dimensions '3 3' or '4 4' of patch 2, found end of file"},
      {WithLine(2, "2 2"),
       "t.bpt:2: expected patch dimensions '3 3' or '4 4' of patch 1, found '2'"},
      {WithLine(2, "3 4"),
       "t.bpt:2: expected patch dimensions '3 3' or '4 4' of patch 1, found '4'"},
      {WithLine(2, "3"),
       "t.bpt:2: expected 2 numbers (patch dimensions of patch 1) alone on this line, found 1"},
      {WithLine(4, "1 0"),
       "t.bpt:4: expected 3 numbers (x y z of control point 2 of patch 1) alone on this line, "
       "found 2"},
      {WithLine(4, "1 0 0 7"),
       "t.bpt:4: expected 3 numbers (x y z of control point 2 of patch 1) alone on this line, "
       "found 4"},
      {WithLine(5, "2 x1 0"),
       "t.bpt:5: expected a number, the y coordinate of control point 3 of patch 1, found 'x1'"},
      {WithLine(5, "2 0 nan"),
       "t.bpt:5: expected a finite number, the z coordinate of control point 3 of patch 1, "
       "found 'nan'"},
      {WithLine(5, "-inf 0 0"),
       "t.bpt:5: expected a finite number, the x coordinate of control point 3 of patch 1, "
       "found '-inf'"},
      {WithLine(5, "1e999 0 0"),
       "t.bpt:5: expected a finite number, the x coordinate of control point 3 of patch 1, "
       "found '1e999'"},
      {WithLine(5, "2,0 0 0"),
       "t.bpt:5: expected a number, the x coordinate of control point 3 of patch 1, found '2,0'"},
      {WithLine(6, "\x01\x02 0 0"),
       "t.bpt:6: expected a number, the x coordinate of control point 4 of patch 1, found '?" "?'"},
      {OnePatch().substr(0, OnePatch().find("2 2 0")),
       "t.bpt:12: expected the x coordinate of control point 11 of patch 1, found end of file"},
      {OnePatch() + "7\n", "t.bpt:19: expected end of file after 1 patch, found '7'"},
      {"1 3 3 0 0 0 1 0", "t.bpt:1: expected the z coordinate of control point 2 of patch 1, "
                          "found end of file"},
      {"1 3 3 0 0 0 1 0 q", "t.bpt:1: expected a number, the z coordinate of control point 2 "
                            "of patch 1, found 'q'"},
  };
  for (const auto& [text, message] : cases) {
    auto r = ParseBpt(text, "t.bpt");
    ASSERT_TRUE(std::holds_alternative<SourceError>(r)) << "accepted:\n" << text;
    EXPECT_EQ(std::get<SourceError>(r).What(), message) << "input:\n" << text;
  }
}

TEST(BptReader, AbsurdCountIsRefusedBeforeAnyAllocation) {
  // A count within the limit but with no data behind it fails at the first missing patch,
  // having read (and stored) only what is there.
  auto r = ParseBpt("10000000\n", "big.bpt");
  EXPECT_EQ(std::get<SourceError>(r).What(),
            "big.bpt:1: expected patch dimensions '3 3' or '4 4' of patch 1, found end of file");
}

TEST(BptReader, UnreadableFiles) {
  auto r = ReadBpt("/nonexistent/teapot.bpt");
  EXPECT_EQ(std::get<SourceError>(r).What(),
            "/nonexistent/teapot.bpt: cannot open: No such file or directory");
  auto d = ReadBpt(PATCHSCAN_SURFACES_DIR);
  EXPECT_EQ(std::get<SourceError>(d).What(), std::string(PATCHSCAN_SURFACES_DIR) + ": is a directory");
}

}  // namespace
}  // namespace patchscan
