// libFuzzer target: the .obj reader reads any bytes as a cage, in each scheme, or refuses
// them with file:line.
#include <cstddef>
#include <cstdint>
#include <string_view>
#include <variant>

#include "fuzz_checks.h"
#include "scene/obj_reader.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  const std::string name = "fuzz.obj";
  for (const auto scheme :
       {patchscan::SubdivScheme::CatmullClark, patchscan::SubdivScheme::Loop, patchscan::SubdivScheme::Bilinear}) {
    const auto read = patchscan::ParseObj(text, name, {scheme});
    if (const auto* e = std::get_if<patchscan::SourceError>(&read)) patchscan::fuzz::CheckError(*e, name, text);
  }
  return 0;
}
