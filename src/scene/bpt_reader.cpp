#include "scene/bpt_reader.h"

#include <charconv>
#include <cmath>
#include <cstdlib>
#include <optional>

#include "scene/text_file.h"

namespace patchscan {
namespace {

struct Token {
  std::string_view text;
  int line;
};

bool IsSpace(char c) {
  return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\f' || c == '\v';
}

std::vector<Token> Tokenize(std::string_view text) {
  std::vector<Token> tokens;
  int line = 1;
  size_t i = 0;
  while (i < text.size()) {
    const char c = text[i];
    if (c == '\n') {
      ++line;
      ++i;
    } else if (IsSpace(c)) {
      ++i;
    } else if (c == '#') {
      while (i < text.size() && text[i] != '\n') ++i;
    } else {
      const size_t start = i;
      while (i < text.size() && !IsSpace(text[i]) && text[i] != '#') ++i;
      tokens.push_back({text.substr(start, i - start), line});
    }
  }
  return tokens;
}

std::optional<long long> ParseWhole(std::string_view t) {
  long long value = 0;
  const auto [end, ec] = std::from_chars(t.data(), t.data() + t.size(), value);
  if (ec != std::errc() || end != t.data() + t.size()) return std::nullopt;
  return value;
}

class Parser {
 public:
  Parser(std::string_view text, const std::string& name)
      : name_(name), tokens_(Tokenize(text)) {}

  std::variant<BptFile, SourceError> Parse();

 private:
  // Tokens on tokens_[i]'s line from i onwards.
  int RunOnLine(size_t i) const {
    size_t j = i;
    while (j < tokens_.size() && tokens_[j].line == tokens_[i].line) ++j;
    return static_cast<int>(j - i);
  }
  bool AloneOnLine(size_t i, int n) const {
    return (i == 0 || tokens_[i - 1].line != tokens_[i].line) && RunOnLine(i) == n;
  }
  int LastLine() const { return tokens_.empty() ? 1 : tokens_.back().line; }

  SourceError Error(int line, std::string message) const { return {name_, line, std::move(message)}; }
  SourceError Expected(const std::string& what) const {
    if (pos_ >= tokens_.size()) return Error(LastLine(), "expected " + what + ", found end of file");
    return Error(tokens_[pos_].line, "expected " + what + ", found " + Shown(tokens_[pos_].text));
  }
  // In line layout a record of n numbers must fill its line exactly.
  bool RecordFitsLine(int n) const {
    return !lineLayout_ || pos_ >= tokens_.size() || AloneOnLine(pos_, n);
  }
  SourceError RecordError(int n, const std::string& what) const {
    return Error(tokens_[pos_].line, "expected " + std::to_string(n) + " numbers (" + what +
                                         ") alone on this line, found " +
                                         std::to_string(RunOnLine(pos_)));
  }

  std::string name_;
  std::vector<Token> tokens_;
  size_t pos_ = 0;
  bool lineLayout_ = false;
};

std::variant<BptFile, SourceError> Parser::Parse() {
  // Layout: line by line when the count is alone on its line, the next line holds at most
  // a dimensions record (give or take one number), and the line after that fewer than two
  // points' worth of numbers; a free token stream otherwise.
  constexpr int kPointNumbers = 3;
  if (tokens_.size() >= 2 && AloneOnLine(0, 1)) {
    const int dimsRun = RunOnLine(1);
    const size_t firstPoint = 1 + static_cast<size_t>(dimsRun);
    lineLayout_ = dimsRun <= 3 &&
                  (firstPoint >= tokens_.size() || RunOnLine(firstPoint) < 2 * kPointNumbers);
  }

  // Step 1: the patch count, checked before anything is read on its strength.
  const std::string countWhat =
      "the patch count, a whole number from 1 to " + std::to_string(kMaxBptPatches);
  if (!RecordFitsLine(1)) return RecordError(1, "the patch count");
  if (pos_ >= tokens_.size()) return Expected(countWhat);
  const auto count = ParseWhole(tokens_[pos_].text);
  if (!count || *count < 1 || *count > kMaxBptPatches) return Expected(countWhat);
  ++pos_;

  // Step 2: the patches, each read only when its data is there.
  BptFile file;
  for (long long p = 1; p <= *count; ++p) {
    const std::string ofPatch = " of patch " + std::to_string(p);
    const std::string dimsWhat = "patch dimensions '3 3' or '4 4'" + ofPatch;
    if (!RecordFitsLine(2)) return RecordError(2, "patch dimensions" + ofPatch);
    // Both numbers 3 (degrees) or both 4 (point counts).
    if (pos_ >= tokens_.size()) return Expected(dimsWhat);
    const auto du = ParseWhole(tokens_[pos_].text);
    if (!du || (*du != 3 && *du != 4)) return Expected(dimsWhat);
    const int dimsLine = tokens_[pos_].line;
    ++pos_;
    const auto dv = pos_ < tokens_.size() ? ParseWhole(tokens_[pos_].text) : std::nullopt;
    if (!dv || *dv != *du) return Expected(dimsWhat);
    ++pos_;
    BptPatch patch;
    patch.line = dimsLine;
    for (int k = 0; k < 16; ++k) {
      // Messages are built only on failure: this loop runs 48 times a patch.
      auto pointWhat = [&] { return "control point " + std::to_string(k + 1) + ofPatch; };
      if (!RecordFitsLine(kPointNumbers)) return RecordError(kPointNumbers, "x y z of " + pointWhat());
      for (int c = 0; c < kPointNumbers; ++c) {
        auto what = [&] { return std::string(1, "xyz"[c]) + " coordinate of " + pointWhat(); };
        if (pos_ >= tokens_.size()) return Expected("the " + what());
        const auto n = ParseNumber(tokens_[pos_].text);
        if (!n) return Expected("a number, the " + what());
        if (!n->finite) return Expected("a finite number, the " + what());
        patch.cv[k][c] = n->value;
        ++pos_;
      }
    }
    file.patches.push_back(patch);
  }

  // Step 3: nothing may follow.
  if (pos_ < tokens_.size()) {
    const std::string n = std::to_string(*count);
    return Expected("end of file after " + n + (*count == 1 ? " patch" : " patches"));
  }
  return file;
}

}  // namespace

std::variant<BptFile, SourceError> ParseBpt(std::string_view text, const std::string& name) {
  return Parser(text, name).Parse();
}

std::variant<BptFile, SourceError> ReadBpt(const std::string& path) {
  auto text = ReadTextFile(path);
  if (auto* e = std::get_if<SourceError>(&text)) return *e;
  return ParseBpt(std::get<std::string>(text), path);
}

}  // namespace patchscan
