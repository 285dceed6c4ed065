// The back end's settings for rendering what `camera` sees at `aa`, as `patchscan render`
// sets them (default material and lights), for the tests that render through the library.
#pragma once

#include "patch/camera.h"
#include "raster/scanline_renderer.h"

namespace patchscan::test {

inline raster::RenderSettings SettingsFor(const Camera& camera, int aa) {
  raster::RenderSettings s;
  s.width = camera.width;
  s.height = camera.height;
  s.aa = aa;
  s.hither = camera.hither;
  s.eye = EyePoint(camera);
  s.forward = ViewForward(camera);
  s.orthographic = camera.orthographic;
  return s;
}

}  // namespace patchscan::test
