// How the library says a call failed: what kind of failure (so that a program can pick its
// exit code) and the message for the user. Only src/cli turns these into exit codes.
#pragma once

#include <string>
#include <utility>
#include <variant>

namespace patchscan::render {

enum class Outcome {
  BadOption,     // an option's value, or options that do not fit together
  InputError,    // a scene file (or a file it names) unreadable or malformed
  OutputError,   // an output file could not be written
  Interrupted,   // stopped by the program (render/interrupt.h)
};

// A failed call: its kind and the message, which names file:line where there is one.
struct Failure {
  Outcome outcome;
  std::string message;
};

// A value, or why there is none.
template <class T>
using Result = std::variant<T, Failure>;

}  // namespace patchscan::render
