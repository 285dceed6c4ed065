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

#include "scene/bpt_reader.h"
#include "scene/mutator.h"

namespace patchscan {
namespace {

const std::filesystem::path kCorpus = PATCHSCAN_TESTS_DIR "/corpus/bpt";

TEST(BptCorpus, EveryMalformedFileGetsItsExactMessage) {
  test::ExpectCorpusMessages(kCorpus, ".bpt", [](const std::string& path) { return ReadBpt(path); });
}

// The format's own characters, and tokens at the edges of what it reads.
const std::string kBptAlphabet = "0123456789.-+eE \n\r\t#xnaif,\x01\xff";
const std::vector<std::string> kBptTokens = {"1e308", "-1e308", "1e-320", "4.9e-324", "nan", "inf", "-0", "0", "1",
                                             "99999999999", "10000000", "3", "4", "3 3", "4 4", "#", "\n", "\r\n",
                                             "0x10", "1e", "--1", ".", "1..2", "\xc3\xa9"};

TEST(BptFuzz, MutantsAreReadOrRefusedWithALocatedMessage) {
  // Three mutants in four start from a valid file (so that many stay valid and reach the
  // end of the reader), the rest from the malformed corpus.
  std::vector<std::string> valid, malformed;
  for (const char* f : {"teaspoon.bpt", "teacup.bpt", "sphere.bpt"})
    valid.push_back(test::Slurp(std::filesystem::path(PATCHSCAN_SURFACES_DIR) / f));
  for (const auto& e : std::filesystem::directory_iterator(kCorpus))
    if (e.path().extension() == ".bpt") malformed.push_back(test::Slurp(e.path()));
  ASSERT_GT(malformed.size(), 10u);

  test::Mutator mutate(20261122, kBptAlphabet, kBptTokens);
  long accepted = 0, refused = 0;
  const long budget = test::FuzzBudget();
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
