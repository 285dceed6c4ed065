// The scene readers' hostile-input tests: a corpus of malformed files with the exact
// message each must produce, and a deterministic mutation harness.
#pragma once

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <variant>

#include "scene/source_error.h"

#include <algorithm>
#include <cctype>
#include <cstdint>
#include <cstdlib>
#include <random>
#include <string>
#include <vector>

namespace patchscan::test {

inline std::string Slurp(const std::filesystem::path& p) {
  std::ifstream f(p, std::ios::binary);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

// Every file with extension `ext` in `dir` is listed once in dir/expected.txt (rows
// FILE<TAB>LINE<TAB>MESSAGE, '#' comments), and `read(path)` refuses it with exactly
// "path:LINE: MESSAGE".
template <class Read>
void ExpectCorpusMessages(const std::filesystem::path& dir, const std::string& ext, Read&& read) {
  std::ifstream manifest(dir / "expected.txt");
  ASSERT_TRUE(manifest) << dir;
  int n = 0;
  for (std::string row; std::getline(manifest, row);) {
    if (row.empty() || row[0] == '#') continue;
    const auto tab1 = row.find('\t'), tab2 = row.find('\t', tab1 + 1);
    ASSERT_NE(tab2, std::string::npos) << row;
    const std::string name = row.substr(0, tab1);
    const std::string path = (dir / name).string();
    const std::string expected = path + ":" + row.substr(tab1 + 1, tab2 - tab1 - 1) + ": " + row.substr(tab2 + 1);
    auto r = read(path);
    ASSERT_TRUE(std::holds_alternative<SourceError>(r)) << name << " was accepted";
    EXPECT_EQ(std::get<SourceError>(r).What(), expected);
    ++n;
  }
  long files = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir)) files += e.path().extension() == ext;
  EXPECT_EQ(n, files);
}

// Mutations that reach a reader's corners: bytes flipped, inserted from an alphabet of the
// format's own characters, deleted and duplicated; numbers swapped for extreme ones; the
// text cut short.
class Mutator {
 public:
  // alphabet: characters of the format to insert; tokens: whole tokens to swap in.
  Mutator(std::uint64_t seed, std::string alphabet, std::vector<std::string> tokens)
      : rng_(seed), alphabet_(std::move(alphabet)), tokens_(std::move(tokens)) {}

  std::string Mutate(std::string s) {
    const int n = 1 + Uniform(3);
    for (int i = 0; i < n; ++i) s = Once(std::move(s));
    return s;
  }

 private:
  int Uniform(int n) { return std::uniform_int_distribution<int>(0, n)(rng_); }
  std::size_t Pos(const std::string& s) { return s.empty() ? 0 : std::uniform_int_distribution<std::size_t>(0, s.size() - 1)(rng_); }

  std::string Once(std::string s) {
    switch (Uniform(6)) {
      case 0:  // flip a byte
        if (!s.empty()) s[Pos(s)] = static_cast<char>(Uniform(255));
        break;
      case 1:  // insert a character of the format
        s.insert(s.begin() + static_cast<std::ptrdiff_t>(Pos(s)), alphabet_[static_cast<std::size_t>(Uniform(static_cast<int>(alphabet_.size()) - 1))]);
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
        s.replace(at, end - at, tokens_[static_cast<std::size_t>(Uniform(static_cast<int>(tokens_.size()) - 1))]);
        break;
      }
      default:  // cut short
        s.resize(Pos(s));
        break;
    }
    return s;
  }

  std::mt19937_64 rng_;
  std::string alphabet_;
  std::vector<std::string> tokens_;
};

// The fixed budget of mutants per run (CI runs exactly this many, in both builds);
// PATCHSCAN_FUZZ_MUTANTS raises it for a longer search.
inline long FuzzBudget() {
  if (const char* e = std::getenv("PATCHSCAN_FUZZ_MUTANTS")) return std::max(1L, std::atol(e));
  return 100000;
}

}  // namespace patchscan::test
