// The .bpt reader against hostile input: a corpus of malformed files with the exact message
// each must produce (tests/corpus/bpt/expected.txt), and a deterministic mutation harness
// that feeds the reader a fixed budget of mutants of the corpus and the Utah files. The
// harness also runs in the sanitizer build, where any memory error or undefined behaviour
// fails it.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

#include "patch/bpt_reader.h"

namespace patchscan {
namespace {

const std::filesystem::path kCorpus = PATCHSCAN_TESTS_DIR "/corpus/bpt";

std::string Slurp(const std::filesystem::path& p) {
  std::ifstream f(p, std::ios::binary);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

TEST(BptCorpus, EveryMalformedFileGetsItsExactMessage) {
  std::ifstream manifest(kCorpus / "expected.txt");
  ASSERT_TRUE(manifest) << kCorpus;
  int n = 0;
  for (std::string row; std::getline(manifest, row);) {
    if (row.empty() || row[0] == '#') continue;
    const auto tab1 = row.find('\t'), tab2 = row.find('\t', tab1 + 1);
    ASSERT_NE(tab2, std::string::npos) << row;
    const std::string name = row.substr(0, tab1);
    const std::string path = (kCorpus / name).string();
    const std::string expected = path + ":" + row.substr(tab1 + 1, tab2 - tab1 - 1) + ": " + row.substr(tab2 + 1);
    auto r = ReadBpt(path);
    ASSERT_TRUE(std::holds_alternative<SourceError>(r)) << name << " was accepted";
    EXPECT_EQ(std::get<SourceError>(r).What(), expected);
    ++n;
  }
  // Every file of the corpus is listed, and none twice.
  long files = 0;
  for (const auto& e : std::filesystem::directory_iterator(kCorpus)) files += e.path().extension() == ".bpt";
  EXPECT_EQ(n, files);
}

// Mutations that reach the reader's corners: bytes flipped, inserted from an alphabet of the
// format's own characters, deleted and duplicated; numbers swapped for extreme ones; the
// text cut short.
class Mutator {
 public:
  explicit Mutator(std::uint64_t seed) : rng_(seed) {}

  std::string Mutate(std::string s) {
    const int n = 1 + Uniform(3);
    for (int i = 0; i < n; ++i) s = Once(std::move(s));
    return s;
  }

 private:
  int Uniform(int n) { return std::uniform_int_distribution<int>(0, n)(rng_); }
  std::size_t Pos(const std::string& s) { return s.empty() ? 0 : std::uniform_int_distribution<std::size_t>(0, s.size() - 1)(rng_); }

  std::string Once(std::string s) {
    static const std::string kAlphabet = "0123456789.-+eE \n\r\t#xnaif,\x01\xff";
    static const char* kTokens[] = {"1e308", "-1e308", "1e-320", "4.9e-324", "nan", "inf", "-0", "0", "1",
                                    "99999999999", "10000000", "3", "4", "3 3", "4 4", "#", "\n", "\r\n",
                                    "0x10", "1e", "--1", ".", "1..2", "\xc3\xa9"};
    switch (Uniform(6)) {
      case 0:  // flip a byte
        if (!s.empty()) s[Pos(s)] = static_cast<char>(Uniform(255));
        break;
      case 1:  // insert a character of the format
        s.insert(s.begin() + static_cast<std::ptrdiff_t>(Pos(s)), kAlphabet[static_cast<std::size_t>(Uniform(static_cast<int>(kAlphabet.size()) - 1))]);
        break;
      case 2: {  // delete a run
        const std::size_t at = Pos(s);
        s.erase(at, static_cast<std::size_t>(1 + Uniform(8)));
        break;
      }
      case 3: {  // duplicate a run
        const std::size_t at = Pos(s);
        s.insert(Pos(s), s.substr(at, static_cast<std::size_t>(1 + Uniform(64))));
        break;
      }
      case 4: {  // replace the token at a position with an extreme one
        std::size_t at = Pos(s);
        while (at > 0 && !std::isspace(static_cast<unsigned char>(s[at - 1]))) --at;
        std::size_t end = at;
        while (end < s.size() && !std::isspace(static_cast<unsigned char>(s[end]))) ++end;
        s.replace(at, end - at, kTokens[Uniform(static_cast<int>(std::size(kTokens)) - 1)]);
        break;
      }
      default:  // cut short
        s.resize(Pos(s));
        break;
    }
    return s;
  }

  std::mt19937_64 rng_;
};

// The fixed budget of mutants per run (CI runs exactly this many, in both builds);
// PATCHSCAN_FUZZ_MUTANTS raises it for a longer search.
long Budget() {
  if (const char* e = std::getenv("PATCHSCAN_FUZZ_MUTANTS")) return std::max(1L, std::atol(e));
  return 100000;
}

TEST(BptFuzz, MutantsAreReadOrRefusedWithALocatedMessage) {
  // Three mutants in four start from a valid file (so that many stay valid and reach the
  // end of the reader), the rest from the malformed corpus.
  std::vector<std::string> valid, malformed;
  for (const char* f : {"teaspoon.bpt", "teacup.bpt", "sphere.bpt"})
    valid.push_back(Slurp(std::filesystem::path(PATCHSCAN_SURFACES_DIR) / f));
  for (const auto& e : std::filesystem::directory_iterator(kCorpus))
    if (e.path().extension() == ".bpt") malformed.push_back(Slurp(e.path()));
  ASSERT_GT(malformed.size(), 10u);

  Mutator mutate(20261122);
  long accepted = 0, refused = 0;
  const long budget = Budget();
  for (long k = 0; k < budget; ++k) {
    const auto& pool = k % 4 == 3 ? malformed : valid;
    const std::string text = mutate.Mutate(pool[static_cast<std::size_t>(k / 4) % pool.size()]);
    const long lines = 1 + std::count(text.begin(), text.end(), '\n');
    auto r = ParseBpt(text, "m.bpt");
    if (const auto* e = std::get_if<SourceError>(&r)) {
      ++refused;
      // A message locates the problem on a line of the text and says what was expected.
      ASSERT_EQ(e->file, "m.bpt") << "mutant " << k;
      ASSERT_GE(e->line, 1) << "mutant " << k;
      ASSERT_LE(e->line, lines) << "mutant " << k << ": " << e->What();
      ASSERT_EQ(e->message.rfind("expected ", 0), 0u) << "mutant " << k << ": " << e->What();
      continue;
    }
    ++accepted;
    const BptFile& f = std::get<BptFile>(r);
    ASSERT_FALSE(f.patches.empty()) << "mutant " << k;
    for (const BptPatch& p : f.patches) {
      ASSERT_GE(p.line, 1);
      ASSERT_LE(p.line, lines);
      for (const Vec3& c : p.cv) ASSERT_TRUE(c.allFinite()) << "mutant " << k;
    }
  }
  RecordProperty("mutants", std::to_string(budget));
  RecordProperty("accepted", std::to_string(accepted));
  // Both outcomes are exercised: the mutants are neither all fatal nor all harmless.
  EXPECT_GT(accepted, budget / 50);
  EXPECT_GT(refused, budget / 4);
}

}  // namespace
}  // namespace patchscan
