// Renders through the patchscan library:
//   render_sphere OUT.png           a sphere and a Bézier patch made here, in exact mode
//                                   (Blinn's scan-line algorithm, every sample found by Newton
//                                   iteration), through the scan and the back end directly;
//   render_sphere OUT.png SCENE     a scene file, whole pipeline in one call (render/frame.h).
#include <cstdio>
#include <iostream>
#include <memory>
#include <string>
#include <variant>
#include <vector>

#include "patch/camera.h"
#include "render/frame.h"
#include "render/load.h"
#include "raster/image_writer.h"
#include "raster/scanline_renderer.h"
#include "raster/shading.h"
#include "xscan/exact_scan.h"

using namespace patchscan;

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: %s OUT.png [SCENE]\n", argv[0]);
    return 2;
  }
  // A scene file: the whole pipeline in one call, as `patchscan render` runs it.
  if (argc > 2) {
    render::RenderOptions options;
    options.file = argv[2];
    options.output = argv[1];
    auto rendered = render::RenderFrame(options, std::cerr);
    if (const auto* failed = std::get_if<render::Failure>(&rendered)) {
      std::fprintf(stderr, "%s\n", failed->message.c_str());
      return failed->outcome == render::Outcome::OutputError ? 3 : 1;
    }
    return 0;
  }
  // Otherwise surfaces made here: a unit sphere and a bicubic Bézier patch beside it.
  std::vector<Surface> surfaces;
  surfaces.push_back(Surface{Sphere(1.0, -1.0, 1.0, 360.0), Affine3::Identity()});
  std::array<Vec3, 16> cv;
  for (int j = 0; j < 4; ++j)
    for (int i = 0; i < 4; ++i) cv[4 * j + i] = Vec3(1.5 + i / 1.5, -1.0 + j / 1.5, (i == 1 || i == 2) && (j == 1 || j == 2) ? 0.8 : -0.5);
  surfaces.push_back(Surface{BicubicPatch(cv), Affine3::Identity()});
  Bounds3 bounds;
  for (const Surface& s : surfaces) bounds.Extend(WorldBounds(s));

  // A camera framing them from the front, above and to the right (z up).
  Camera camera;
  camera.width = 640;
  camera.height = 480;
  camera = FrameBounds(bounds, camera, DefaultViewDirection(Vec3(0, 0, 1)));

  // The back end's settings: the default material and a light rig that moves with the eye.
  const raster::RenderSettings settings = render::SettingsFor(camera, 3);

  // Rows go straight to the file, which appears only when the image is complete.
  auto opened = raster::ImageWriter::Open(argv[1], camera.width, camera.height);
  if (const auto* why = std::get_if<std::string>(&opened)) {
    std::fprintf(stderr, "%s\n", why->c_str());
    return 3;
  }
  auto& writer = *std::get<std::unique_ptr<raster::ImageWriter>>(opened);
  struct Sink final : raster::RowSink {
    raster::ImageWriter* w;
    bool WriteRow(int y, const float* pixels) override { return w->WriteRow(y, pixels); }
  } sink;
  sink.w = &writer;

  ExactScan scan(surfaces, camera, ExactScanOptions{});
  const auto counts = raster::RenderFragments(scan, settings, sink);
  if (!counts || !std::holds_alternative<std::monostate>(writer.Commit())) {
    std::fprintf(stderr, "%s: the render failed\n", argv[1]);
    return 3;
  }
  std::printf("%s: %zu surfaces, %lld samples covered, %lld x-scan Newton iterations\n", argv[1], surfaces.size(),
              static_cast<long long>((*counts)[Counter::SamplesCovered]),
              static_cast<long long>(scan.Stats()[Counter::XscanNewtonIterations]));
  return 0;
}
