// The RIB tokenizer: RenderMan Interface Bytestream text (ASCII) split into requests, each
// with its arguments (numbers, strings, arrays) and the line of each, for rib_reader.
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "scene/source_error.h"

namespace patchscan::rib {

// One argument of a request: a number, a string, or an array of either.
struct Value {
  enum class Kind { Number, String, Numbers, Strings };
  Kind kind = Kind::Number;
  std::vector<double> numbers;       // Number: one element
  std::vector<std::string> strings;  // String: one element
  int line = 0;

  bool Numeric() const { return kind == Kind::Number || kind == Kind::Numbers; }
  bool Textual() const { return kind == Kind::String || kind == Kind::Strings; }
  size_t Size() const { return Numeric() ? numbers.size() : strings.size(); }
};

struct Request {
  std::string name;
  int line = 0;
  std::vector<Value> args;
};

inline bool IsSpace(char c) {
  return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\f' || c == '\v';
}
// Splits RIB text into requests, one at a time. On malformed text Next returns false and
// Error() says why.
class Lexer {
 public:
  Lexer(std::string_view text, const std::string& file) : text_(text), file_(file) {}

  // The next request; false at the end of the text or on an error (then Error() is set).
  bool Next(Request* r);
  const std::optional<SourceError>& Error() const { return error_; }

 private:
  bool Fail(int line, std::string message);
  void SkipSpace();
  // The run of non-space characters at i_, for messages.
  std::string_view Word() const;
  std::string_view Identifier();
  bool ReadNumber(double* out);
  bool ReadString(std::string* out);
  // One scalar (number or string) at i_ into v, which must be of `kind` if set.
  bool ReadScalar(Value* v, bool inArray);
  bool ReadValue(Value* v);

  std::string_view text_;
  std::string file_;
  size_t i_ = 0;
  int line_ = 1;
  std::optional<SourceError> error_;
};

}  // namespace patchscan::rib
