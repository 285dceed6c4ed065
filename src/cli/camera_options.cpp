#include "cli/camera_options.h"

#include "cli/choice_option.h"

namespace patchscan::cli {

void AddCameraOptions(CLI::App* cmd, render::CameraOptions* o) {
  cmd->option_defaults()->group("Camera");
  cmd->add_option("--size", o->size,
                  "image size in pixels, WIDTHxHEIGHT (default: a RIB scene's Format, else 640x480)")
      ->type_name("WxH");
  cmd->add_option("--eye", o->eye,
                  "eye position X,Y,Z in world space (default: framed automatically)")
      ->type_name("X,Y,Z");
  cmd->add_option("--look-at", o->lookAt,
                  "point X,Y,Z the camera looks at (default: the centre of the scene's bounds)")
      ->type_name("X,Y,Z");
  cmd->add_option("--up", o->up, "up direction X,Y,Z (default: 0,0,1, z up as in .bpt files)")->type_name("X,Y,Z");
  cmd->add_option("--fov", o->fovDeg,
                  "field of view in degrees: vertical (default 30), or for a RIB scene's camera "
                  "that of the image's shorter side (default: its Projection's)")
      ->type_name("DEG");
  cmd->add_option("--hither", o->hither,
                  "distance of the hither (near clipping) plane from the eye (default: half "
                  "the distance to the scene's bounding sphere when framed, else 1/1000 of "
                  "the distance to the look-at point; a RIB scene's Clipping)")
      ->type_name("DIST");
  cmd->add_option("--frame", o->frame,
                  "RIB scenes: the one frame to read, by its FrameBegin number (default: the first; "
                  "render runs every frame, or those of --frames)")
      ->type_name("N");
  AddChoiceOption(cmd, "--obj-scheme", &o->objScheme,
                  {{"catmull-clark", SubdivScheme::CatmullClark},
                   {"loop", SubdivScheme::Loop},
                   {"bilinear", SubdivScheme::Bilinear}},
                  ".obj scenes: the cage's subdivision rules (RenderMan's names): catmull-clark, loop (a cage of "
                  "triangles), or bilinear to render the cage itself, flat");
  cmd->option_defaults()->group("Options");
}

}  // namespace patchscan::cli
