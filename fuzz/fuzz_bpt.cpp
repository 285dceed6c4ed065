// libFuzzer target: the .bpt reader reads any bytes or refuses them with file:line.
#include <cstddef>
#include <cstdint>
#include <string_view>
#include <variant>

#include "fuzz_checks.h"
#include "scene/bpt_reader.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  const std::string name = "fuzz.bpt";
  const auto read = patchscan::ParseBpt(text, name);
  if (const auto* e = std::get_if<patchscan::SourceError>(&read)) patchscan::fuzz::CheckError(*e, name, text);
  return 0;
}
