// A depth map pixel's depth from its samples by each of RenderMan's depth filters (Hider
// "hidden" "depthfilter"), on samples whose depths are set by hand.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "raster/pixel_shading.h"

namespace patchscan::raster {
namespace {

// One pixel of a 2 x 2 lattice (aa 2), two layers a sample: sample k's nearest fragment at
// depth near[k] (0: none), its second at far[k] (0: none).
std::vector<std::vector<Sample>> Pixel(const double (&near)[4], const double (&far)[4]) {
  std::vector<std::vector<Sample>> rows(2, std::vector<Sample>(4, kNoSample));
  for (int k = 0; k < 4; ++k) {
    Sample* keep = &rows[k / 2][static_cast<std::size_t>(k % 2) * 2];
    if (near[k] > 0) keep[0] = {1.0 / near[k], k};
    if (far[k] > 0) keep[1] = {1.0 / far[k], 10 + k};
  }
  return rows;
}

TEST(DepthFilter, EachFilterOfFourSamples) {
  // Three samples on a surface at depths 2, 3, 4 (the last sample sees nothing); behind
  // them at 4, 5 and nothing.
  const auto rows = Pixel({2, 3, 4, 0}, {4, 5, 0, 0});
  auto depth = [&](DepthFilter f) { return detail::FilteredDepth(rows, 0, 2, 2, f); };
  EXPECT_EQ(depth(DepthFilter::Min), 2.0f);
  EXPECT_EQ(depth(DepthFilter::Max), 4.0f);
  EXPECT_EQ(depth(DepthFilter::Average), 3.0f);
  // Midpoints 3, 4 and infinity (one surface only: nothing behind it to shadow).
  EXPECT_EQ(depth(DepthFilter::Midpoint), 3.0f);
  // One layer kept: no midpoint is known, the pixel shadows nothing.
  const auto lone = Pixel({2, 3, 4, 0}, {0, 0, 0, 0});
  EXPECT_TRUE(std::isinf(detail::FilteredDepth(lone, 0, 2, 2, DepthFilter::Midpoint)));
  EXPECT_EQ(detail::FilteredDepth(lone, 0, 2, 2, DepthFilter::Min), 2.0f);
}

TEST(DepthFilter, MidpointSkipsTheNearestSurfaceMetTwice) {
  // One sample (aa 1), three layers: a quadric's seam gives its front twice at depth 2
  // (the second a rounding apart); its back is at 6.
  std::vector<std::vector<Sample>> rows(1, std::vector<Sample>{{0.5, 0}, {0.5 * (1 - 1e-12), 1}, {1.0 / 6, 2}});
  EXPECT_EQ(detail::FilteredDepth(rows, 0, 1, 3, DepthFilter::Midpoint), 4.0f);
  rows[0][2] = kNoSample;  // the back not there: nothing behind the front to shadow
  EXPECT_TRUE(std::isinf(detail::FilteredDepth(rows, 0, 1, 3, DepthFilter::Midpoint)));
}

}  // namespace
}  // namespace patchscan::raster
