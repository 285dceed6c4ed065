// A command-line option taking one of a few names, parsed once into an enum.
#pragma once

#include <CLI/CLI.hpp>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace patchscan::cli {

template <class E>
using ChoiceNames = std::vector<std::pair<std::string, E>>;

// The name of `value` in `names` (empty if it has none).
template <class E>
std::string NameOf(const ChoiceNames<E>& names, E value) {
  for (const auto& [name, v] : names)
    if (v == value) return name;
  return {};
}

// Adds option `flag` to `cmd`: one of `names`, stored in *value (whose value on entry is
// the default shown in --help). Any other word is a usage error naming the choices.
template <class E>
CLI::Option* AddChoiceOption(CLI::App* cmd, const std::string& flag, E* value, ChoiceNames<E> names,
                             const std::string& help) {
  std::vector<std::string> words;
  std::string placeholder;  // "exact|theta|tess"
  for (const auto& n : names) {
    words.push_back(n.first);
    placeholder += (placeholder.empty() ? "" : "|") + n.first;
  }
  const std::string shown = NameOf(names, *value);
  return cmd
      ->add_option_function<std::string>(
          flag,
          [value, names](const std::string& word) {
            for (const auto& [name, v] : names)
              if (name == word) *value = v;
          },
          help)
      ->check(CLI::IsMember(words))
      ->type_name(placeholder)
      ->default_str(shown);
}

}  // namespace patchscan::cli
