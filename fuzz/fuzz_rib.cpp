// libFuzzer target: the RIB reader reads any bytes or refuses them with file:line. The
// scene is named in a directory that does not exist, so a relative ReadArchive finds nothing.
#include <cstddef>
#include <cstdint>
#include <string_view>
#include <variant>

#include "fuzz_checks.h"
#include "scene/rib/reader.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  const std::string name = "/nonexistent-fuzz-dir/fuzz.rib";
  const auto read = patchscan::ParseRib(text, name);
  if (const auto* e = std::get_if<patchscan::SourceError>(&read)) patchscan::fuzz::CheckError(*e, name, text);
  return 0;
}
