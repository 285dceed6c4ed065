#include "cli/convert.h"

#include <ostream>

#include "cli/checks.h"
#include "cli/exit_codes.h"
#include "cli/file_output.h"
#include "render/load.h"
#include "scene/rib/writer.h"

namespace patchscan::cli {

CLI::App* AddConvertCommand(CLI::App* app, ConvertOptions* o) {
  CLI::App* cmd = app->add_subcommand(
      "convert",
      "Write a scene and its camera as a RenderMan RIB file (.rib) that renders the same "
      "image: Format, PixelSamples, Projection, Clipping, the world-to-camera Transform, the "
      "scene's lights, then each surface with its appearance (Color, Opacity, Sides, "
      "ReverseOrientation, Surface shader and parameters) as a Patch (bicubic patches in Bézier "
      "form), a NuPatch, its quadric or a SubdivisionMesh, and the polygons as PointsPolygons. "
      "The file is written to a temporary name and renamed into place.");
  cmd->add_option("FILE", o->file, "scene file: .bpt, .rib, .obj, .step, .stp, .iges, .igs or .brep")->type_name("FILE")->required();
  cmd->add_option("-o,--output", o->output, "the RIB file to write")->type_name("RIB")->required();
  cmd->add_option("--aa", o->aa, "PixelSamples to write, as the side of the grid (default: 3)")
      ->type_name("N")
      ->check(WholeNumber(1, 8));
  cmd->add_option("--display", o->display,
                  "the image file name to write in a Display request (default: none)")
      ->type_name("IMAGE");
  AddCameraOptions(cmd, &o->camera);
  return cmd;
}

int RunConvert(const ConvertOptions& o, std::ostream& err) {
  render::CameraOptions camera = o.camera;
  camera.cadAsNurbs = true;  // RenderMan trims NuPatches only
  auto loaded = render::LoadSceneAndCamera(o.file, camera, err);
  if (const auto* failed = std::get_if<render::Failure>(&loaded)) return Fail(*failed, err);
  const render::LoadedScene& ls = std::get<render::LoadedScene>(loaded);
  RibWriteOptions wo;
  wo.pixelSamples = o.aa.value_or(ls.scene.image.pixelSamples.value_or(render::kDefaultAa));
  wo.displayName = o.display;
  auto text = WriteRib(ls.scene, ls.view.camera, wo);
  if (auto* e = std::get_if<RibWriteError>(&text)) {
    err << "patchscan: " << o.file << ": " << e->message << '\n';
    return kExitInputError;
  }
  // Step 2: whole or not at all.
  if (const auto why = WriteFileWhole(o.output, std::get<std::string>(text))) {
    err << "patchscan: " << *why << '\n';
    return kExitOutputError;
  }
  return kExitOk;
}

}  // namespace patchscan::cli
