// A surface whose highest point lies exactly on a sample row: an orthographic view of a
// RenderMan sphere along its axis puts its top at y = 12.5 px, a pixel row's centre. The
// silhouette trackers born there once started at the maximum itself, where their system is
// singular, died on the next row, and the direct modes drew nothing.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <numbers>
#include <string>
#include <vector>

#include "cli/folder.h"

namespace {

TEST(MaximumOnARow, OrthographicSphereAlongItsAxisCoversItsDisc) {
  Folder dir("maximum_on_row");
  // 200 x 150 px over a 3.2 x 2.4 window: the unit sphere is a disc of radius 62.5 px about
  // (100, 75), its top at y = 12.5.
  std::ofstream(dir.path / "o.rib") << "Format 200 150 1\nProjection \"orthographic\"\nScreenWindow -1.6 1.6 -1.2 1.2\n"
                                       "Translate 0 0 5\nWorldBegin\nSphere 1 -1 1 360\nWorldEnd\n";
  const double disc = std::numbers::pi * 62.5 * 62.5 / (200.0 * 150.0);  // its share of the image
  for (const char* mode : {"exact", "theta"})
    for (const char* aa : {"1", "3"}) {
      ASSERT_EQ(dir.Run(std::string("render o.rib -o o.exr --mode ") + mode + " --aa " + aa), 0) << dir.Err();
      const std::vector<float> px = Pixels((dir.path / "o.exr").string());
      ASSERT_EQ(px.size(), 200u * 150u * 4u);
      double alpha = 0.0;
      for (std::size_t k = 3; k < px.size(); k += 4) alpha += px[k];
      // One sample per pixel (aa 1) counts pixel centres inside the disc: within 0.3% of its
      // area for a disc this size; aa 3 averages 9 samples a pixel.
      EXPECT_NEAR(alpha / (200.0 * 150.0), disc, 0.003 * disc) << mode << " aa " << aa;
    }
}

}  // namespace
