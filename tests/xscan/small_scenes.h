// The scenes of surfaces/ at a small size, for the tests that render every one of them
// several ways and compare the images (the partition, the row split).
#pragma once

#include <gtest/gtest.h>

#include <string>
#include <variant>
#include <vector>

#include "patch/camera.h"
#include "scene/scene.h"

namespace patchscan::test {

struct SceneCase {
  std::string name;
  Scene scene;
  Camera camera;
};

// The scenes of surfaces/, each at a small size through its own camera or framed.
inline std::vector<SceneCase> SmallScenes() {
  std::vector<SceneCase> out;
  for (const char* file : {"teapot.bpt", "teacup.bpt", "teaspoon.bpt", "sphere.bpt", "quadrics.rib",
                           "patchmesh.rib", "teapot_lit.rib", "cages.rib", "cube_tags.obj", "nurbs.rib", "trimmed.rib",
                           "polygons.rib", "curves.rib", "still_life.rib"}) {
    auto loaded = LoadScene(std::string(PATCHSCAN_SURFACES_DIR) + "/" + file);
    EXPECT_TRUE(std::holds_alternative<Scene>(loaded)) << file;
    if (!std::holds_alternative<Scene>(loaded)) continue;
    Scene scene = std::get<Scene>(std::move(loaded));
    // Framed from the scene's bounds (RIB scenes too: their own cameras are not the point).
    const std::string f = file;
    const Vec3 up = f == "teacup.bpt" || f == "teaspoon.bpt" ? Vec3(0, 1, 0) : Vec3(0, 0, 1);
    Camera camera;
    camera.width = 120;
    camera.height = 90;
    camera.up = up;
    camera = FrameBounds(scene.WorldBounds(), camera, DefaultViewDirection(up));
    scene.FaceCamera(camera);
    out.push_back({file, std::move(scene), camera});
  }
  // The teapot twice over: every sample sees two fragments at exactly the same depth, and
  // which one is kept (the surface id written) rests on the order they reach the back end.
  SceneCase twice = out.front();
  twice.name = "teapot twice over";
  const std::size_t n = twice.scene.surfaces.size();
  for (std::size_t k = 0; k < n; ++k) twice.scene.surfaces.push_back(twice.scene.surfaces[k]);
  out.push_back(std::move(twice));
  return out;
}

}  // namespace patchscan::test
