// libFuzzer target: the CAD reader (Open CASCADE's STEP, IGES and BRep parsers, then the
// conversion of every face) reads any bytes as a model or refuses them naming the file. The
// format follows the bytes as a user's file would carry it: STEP's "ISO-10303-21" header,
// a BRep's "DBRep_DrawableShape" or "CASCADE Topology", else IGES.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>
#include <variant>

#include "fuzz_checks.h"
#include "scene/cad_reader.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  const auto starts = [&](std::string_view head) { return text.find(head) < 64; };
  const char* ext = starts("ISO-10303-21") ? ".step" : starts("DBRep_DrawableShape") || starts("CASCADE Topology") ? ".brep" : ".igs";
  const std::string name =
      (std::filesystem::temp_directory_path() / ("patchscan_fuzz_cad_" + std::to_string(::getpid()) + ext)).string();
  std::ofstream(name, std::ios::binary).write(text.data(), static_cast<std::streamsize>(text.size()));
  const auto read = patchscan::ReadCad(name);
  std::filesystem::remove(name);
  if (const auto* e = std::get_if<patchscan::SourceError>(&read)) {
    patchscan::fuzz::Require(e->file == name && e->line == 0 && !e->message.empty());
  } else {
    const auto& scene = std::get<patchscan::Scene>(read);
    patchscan::fuzz::Require(scene.cad.has_value() && !scene.surfaces.empty());
  }
  return 0;
}
