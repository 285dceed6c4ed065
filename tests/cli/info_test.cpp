// patchscan info: whole kind names, the file that defines each surface (an archive's), and
// the same facts as JSON.
#include <gtest/gtest.h>

#include <cctype>
#include <filesystem>
#include <fstream>
#include <string>

#include "cli/run_program.h"

namespace {

const std::string kSurfaces = PATCHSCAN_SURFACES_DIR;

// A JSON value parsed and dropped: true when `text` holds exactly one well-formed value
// (RFC 8259's grammar, numbers loosely).
class JsonCheck {
 public:
  explicit JsonCheck(const std::string& text) : t_(text) {}
  bool Whole() {
    const bool ok = Value();
    Space();
    return ok && i_ == t_.size();
  }

 private:
  void Space() {
    while (i_ < t_.size() && std::isspace(static_cast<unsigned char>(t_[i_]))) ++i_;
  }
  bool Eat(char c) {
    Space();
    if (i_ < t_.size() && t_[i_] == c) return ++i_, true;
    return false;
  }
  bool Word(const char* w) {
    const std::string s(w);
    if (t_.compare(i_, s.size(), s) != 0) return false;
    i_ += s.size();
    return true;
  }
  bool String() {
    if (!Eat('"')) return false;
    while (i_ < t_.size() && t_[i_] != '"') {
      if (static_cast<unsigned char>(t_[i_]) < 0x20) return false;
      i_ += t_[i_] == '\\' ? 2 : 1;
    }
    return i_ < t_.size() && t_[i_++] == '"';
  }
  bool Value() {
    Space();
    if (i_ >= t_.size()) return false;
    const char c = t_[i_];
    if (c == '"') return String();
    if (c == '{' || c == '[') {
      ++i_;
      const char close = c == '{' ? '}' : ']';
      if (Eat(close)) return true;
      do {
        if (c == '{' && !(String() && Eat(':'))) return false;
        if (!Value()) return false;
      } while (Eat(','));
      return Eat(close);
    }
    if (Word("true") || Word("false") || Word("null")) return true;
    const std::size_t start = i_;
    while (i_ < t_.size() && (std::isdigit(static_cast<unsigned char>(t_[i_])) || std::string("+-.eE").find(t_[i_]) != std::string::npos)) ++i_;
    return i_ > start;
  }
  const std::string& t_;
  std::size_t i_ = 0;
};

TEST(Info, KindsAreWholeAndArchivesNamed) {
  // still_life.rib reads its objects from an archive: their lines name the archive.
  const Result r = Patchscan("info " + kSurfaces + "/still_life.rib --frame 2");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("archives/still_life_world.rib:62  "), std::string::npos) << r.out;
  // A kind longer than the old 16-character column, whole.
  const Result q = Patchscan("info " + kSurfaces + "/quadrics.rib");
  ASSERT_EQ(q.code, 0) << q.err;
  EXPECT_NE(q.out.find("| hyperboloid from"), std::string::npos) << q.out;
  EXPECT_NE(q.out.find("thetamax"), std::string::npos) << q.out;
}

TEST(Info, JsonHoldsTheSameFacts) {
  const Result r = Patchscan("info " + kSurfaces + "/teapot.bpt --json");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(JsonCheck(r.out).Whole()) << r.out;
  for (const char* key : {"\"surfaces\": 32", "\"bicubic_patches\": 32", "\"control_points\": 512",
                          "\"distinct_control_points\": 290", "\"collapsed_edges\": 8", "\"from\": \"framed\"",
                          "\"surface_list\": [", "\"kind\": \"bicubic", "\"screen_bounds\": {\"x\": ["})
    EXPECT_NE(r.out.find(key), std::string::npos) << key << " in\n" << r.out;
  int surfaces = 0;
  for (std::size_t i = 0; (i = r.out.find("{\"surface\": ", i)) != std::string::npos; ++i) ++surfaces;
  EXPECT_EQ(surfaces, 32);
  // A scene with cages, archives and a camera of its own is well-formed too.
  for (const char* scene : {"/still_life.rib", "/cube_tags.obj", "/trimmed.rib"}) {
    const Result s = Patchscan("info " + kSurfaces + scene + " --json");
    ASSERT_EQ(s.code, 0) << scene << s.err;
    EXPECT_TRUE(JsonCheck(s.out).Whole()) << scene << "\n" << s.out;
  }
}

}  // namespace
