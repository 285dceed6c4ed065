// Checks of option values that say what is expected in the user's terms: "--aa: expected a
// whole number from 1 to 8, found '3.5'", not CLI11's "not in range" nor a bound of
// 1.8e308 written out in full.
#pragma once

#include <CLI/CLI.hpp>

#include <cmath>
#include <cstdlib>
#include <string>

namespace patchscan::cli {

namespace detail {
inline std::string Shown(double v) {
  std::string s = std::to_string(v);
  s.erase(s.find_last_not_of('0') + 1);
  if (!s.empty() && s.back() == '.') s.pop_back();
  return s;
}
// The whole text as a number, or NaN.
inline double Parsed(const std::string& text) {
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  return !text.empty() && end == text.c_str() + text.size() ? v : NAN;
}
}  // namespace detail

// A whole number from lo to hi.
inline CLI::Validator WholeNumber(long lo, long hi) {
  return CLI::Validator(
      [lo, hi](std::string& text) -> std::string {
        const double v = detail::Parsed(text);
        if (std::isfinite(v) && v == std::floor(v) && v >= static_cast<double>(lo) && v <= static_cast<double>(hi)) return {};
        return "expected a whole number from " + std::to_string(lo) + " to " + std::to_string(hi) + ", found '" + text + "'";
      },
      std::to_string(lo) + " to " + std::to_string(hi));
}

// A number from lo to hi.
inline CLI::Validator Number(double lo, double hi) {
  return CLI::Validator(
      [lo, hi](std::string& text) -> std::string {
        const double v = detail::Parsed(text);
        if (v >= lo && v <= hi) return {};
        return "expected a number from " + detail::Shown(lo) + " to " + detail::Shown(hi) + ", found '" + text + "'";
      },
      detail::Shown(lo) + " to " + detail::Shown(hi));
}

// A number of 0 or more (a threshold), or more than 0 (a scale).
inline CLI::Validator NonNegative() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        const double v = detail::Parsed(text);
        return v >= 0.0 && std::isfinite(v) ? std::string() : "expected a number of 0 or more, found '" + text + "'";
      },
      "0 or more");
}
inline CLI::Validator Positive() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        const double v = detail::Parsed(text);
        return v > 0.0 && std::isfinite(v) ? std::string() : "expected a number above 0, found '" + text + "'";
      },
      "above 0");
}

}  // namespace patchscan::cli
