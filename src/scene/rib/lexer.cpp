#include "scene/rib/lexer.h"

#include <cerrno>
#include <cstdlib>

#include "scene/text_file.h"

namespace patchscan::rib {
namespace {

bool IsLetter(char c) { return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z'); }
bool IsNumberChar(char c) {
  return (c >= '0' && c <= '9') || c == '-' || c == '+' || c == '.' || c == 'e' || c == 'E';
}

}  // namespace

bool Lexer::Next(Request* r) {
  r->args.clear();
  SkipSpace();
  if (i_ >= text_.size()) return false;
  if (!IsLetter(text_[i_])) return Fail(line_, "expected a request name, found " + Shown(Word()));
  r->line = line_;
  r->name = std::string(Identifier());
  for (;;) {
    SkipSpace();
    if (i_ >= text_.size() || IsLetter(text_[i_])) return true;
    Value v;
    if (!ReadValue(&v)) return false;
    r->args.push_back(std::move(v));
  }
}

bool Lexer::Fail(int line, std::string message) {
  error_ = SourceError{file_, line, std::move(message)};
  return false;
}

void Lexer::SkipSpace() {
  while (i_ < text_.size()) {
    const char c = text_[i_];
    if (c == '\n') {
      ++line_;
      ++i_;
    } else if (IsSpace(c)) {
      ++i_;
    } else if (c == '#') {
      while (i_ < text_.size() && text_[i_] != '\n') ++i_;
    } else {
      return;
    }
  }
}

std::string_view Lexer::Word() const {
  size_t j = i_;
  while (j < text_.size() && !IsSpace(text_[j])) ++j;
  return text_.substr(i_, j - i_);
}

std::string_view Lexer::Identifier() {
  const size_t start = i_;
  while (i_ < text_.size() && (IsLetter(text_[i_]) || (text_[i_] >= '0' && text_[i_] <= '9') ||
                               text_[i_] == '_'))
    ++i_;
  return text_.substr(start, i_ - start);
}

bool Lexer::ReadNumber(double* out) {
  const size_t start = i_;
  while (i_ < text_.size() && IsNumberChar(text_[i_])) ++i_;
  const std::string_view t = text_.substr(start, i_ - start);
  const auto n = ParseNumber(t);
  // A number ends at a delimiter: space, a bracket, a quote or a comment.
  const bool delimited = i_ >= text_.size() || IsSpace(text_[i_]) || text_[i_] == '[' ||
                         text_[i_] == ']' || text_[i_] == '"' || text_[i_] == '#';
  if (!n || !delimited) {
    i_ = start;
    return Fail(line_, "expected a number, found " + Shown(Word()));
  }
  if (!n->finite) return Fail(line_, "number " + Shown(t) + " is not finite");
  *out = n->value;
  return true;
}

bool Lexer::ReadString(std::string* out) {
  const int opened = line_;
  ++i_;  // the opening quote
  out->clear();
  while (i_ < text_.size() && text_[i_] != '"') {
    char c = text_[i_++];
    if (c == '\n') ++line_;
    if (c == '\\' && i_ < text_.size()) {
      c = text_[i_++];
      c = c == 'n' ? '\n' : c == 't' ? '\t' : c == 'r' ? '\r' : c;
    }
    out->push_back(c);
  }
  if (i_ >= text_.size()) return Fail(opened, "the string opened here is not closed");
  ++i_;  // the closing quote
  return true;
}

bool Lexer::ReadScalar(Value* v, bool inArray) {
  const char c = text_[i_];
  if (static_cast<unsigned char>(c) >= 0x80)
    return Fail(line_, "binary RIB is not supported (a byte above 0x7f)");
  if (c == '"') {
    if (inArray && v->kind == Value::Kind::Numbers && !v->numbers.empty())
      return Fail(line_, "an array mixes numbers and strings");
    std::string s;
    if (!ReadString(&s)) return false;
    v->strings.push_back(std::move(s));
    if (inArray) v->kind = Value::Kind::Strings;
    return true;
  }
  if (IsNumberChar(c)) {
    if (inArray && v->kind == Value::Kind::Strings && !v->strings.empty())
      return Fail(line_, "an array mixes numbers and strings");
    double x = 0;
    if (!ReadNumber(&x)) return false;
    v->numbers.push_back(x);
    return true;
  }
  if (c == '[') return Fail(line_, "arrays do not nest");
  return Fail(line_, "unexpected " + Shown(Word()));
}

bool Lexer::ReadValue(Value* v) {
  v->line = line_;
  if (text_[i_] == ']') return Fail(line_, "']' without '['");
  if (text_[i_] != '[') {
    if (!ReadScalar(v, false)) return false;
    v->kind = v->strings.empty() ? Value::Kind::Number : Value::Kind::String;
    return true;
  }
  const int opened = line_;
  ++i_;
  v->kind = Value::Kind::Numbers;
  for (;;) {
    SkipSpace();
    if (i_ >= text_.size()) return Fail(opened, "the array opened here is not closed");
    if (text_[i_] == ']') {
      ++i_;
      return true;
    }
    if (IsLetter(text_[i_])) return Fail(opened, "the array opened here is not closed before " + Shown(Word()));
    if (!ReadScalar(v, true)) return false;
  }
}

}  // namespace patchscan::rib
