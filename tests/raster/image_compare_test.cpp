// The image comparison of `patchscan compare` on images whose answers are known: discs and
// half-planes with exact box-filtered coverage, depth and normals offset by known amounts.
#include "raster/image_compare.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>

namespace patchscan::raster {
namespace {

// Box-filtered coverage of the region inside(x, y) on a width × height image, by a 32 × 32
// lattice per pixel: coverage is exact to 1/1024, far below the distances measured here.
ComparableImage CoverageImage(int width, int height, const std::function<bool(double, double)>& inside) {
  constexpr int kSub = 32;
  ComparableImage img;
  img.width = width;
  img.height = height;
  img.alpha.resize(static_cast<size_t>(width * height));
  img.rgb.resize(static_cast<size_t>(3 * width * height));
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      int n = 0;
      for (int j = 0; j < kSub; ++j)
        for (int i = 0; i < kSub; ++i) n += inside(x + (i + 0.5) / kSub, y + (j + 0.5) / kSub);
      const float a = static_cast<float>(n) / (kSub * kSub);
      const size_t k = static_cast<size_t>(y * width + x);
      img.alpha[k] = a;
      for (int c = 0; c < 3; ++c) img.rgb[3 * k + static_cast<size_t>(c)] = a;
    }
  return img;
}

auto Disc(double cx, double cy, double r) {
  return [=](double x, double y) { return (x - cx) * (x - cx) + (y - cy) * (y - cy) <= r * r; };
}

// The alpha = 1/2 contour of a box-filtered straight edge, interpolated linearly between
// pixel centres, lies within this distance of the edge. For an axis-aligned edge a fraction
// f < 1/2 into a pixel, the centres on either side hold 1 and f and the crossing lands
// 1/(2(1 − f)) − 1/2 − f off, worst 3/2 − √2 ≈ 0.086 px at f = 1 − 1/√2; oblique edges
// measured 0.021 (45°) to 0.085 px (7°).
constexpr double kEdgeLocationTol = 0.1;

TEST(ImageCompare, ContourOfAHalfPlaneLiesOnItsEdge) {
  for (double degrees : {0.0, 7.0, 30.0, 45.0, 62.0, 90.0}) {
    const double a = degrees * M_PI / 180, nx = std::cos(a), ny = std::sin(a), c = 20.3 * nx + 15.7 * ny;
    const ComparableImage img = CoverageImage(40, 32, [&](double x, double y) { return nx * x + ny * y <= c; });
    const CoverageContour contour = CoverageEdges(img.alpha, img.width, img.height);
    ASSERT_FALSE(contour.from.empty());
    double worst = 0;
    for (const auto& p : contour.from) {
      // Within the border pixels the padding (the nearest pixel's coverage continued) bends
      // the contour to meet the frame square: not the edge's own.
      if (p.x() < 1 || p.y() < 1 || p.x() > img.width - 1 || p.y() > img.height - 1) continue;
      worst = std::max(worst, std::abs(nx * p.x() + ny * p.y() - c));
    }
    EXPECT_LT(worst, kEdgeLocationTol) << degrees << " degrees";
  }
}

TEST(ImageCompare, DiscsOfDifferentRadiiAreTheirDifferenceApart) {
  // Radius 12 against 12.3: every point of either contour is 0.3 px from the other, up to
  // the edge-location tolerance of each contour.
  const ComparableImage a = CoverageImage(40, 40, Disc(20.2, 19.6, 12.0));
  const ComparableImage b = CoverageImage(40, 40, Disc(20.2, 19.6, 12.3));
  const ImageComparison c = CompareImages(a, b);
  ASSERT_TRUE(c.silhouette.has_value());
  EXPECT_NEAR(c.silhouette->max, 0.3, 2 * kEdgeLocationTol);
  EXPECT_NEAR(c.silhouette->mean, 0.3, 2 * kEdgeLocationTol);
  EXPECT_LE(c.silhouette->p99, c.silhouette->max);
  // The area between the circles: π (12.3² − 12²).
  EXPECT_NEAR(c.coverageAreaDifference, M_PI * (12.3 * 12.3 - 144.0), 0.5);
  EXPECT_GT(c.rmse, 0.0);

  const ImageComparison same = CompareImages(a, a);
  ASSERT_TRUE(same.silhouette.has_value());
  EXPECT_EQ(same.silhouette->max, 0.0);
  EXPECT_EQ(same.rmse, 0.0);
  EXPECT_TRUE(std::isinf(same.psnr));
}

TEST(ImageCompare, AMissingPieceIsFoundFarAway) {
  // A second disc only in a: its contour is ~15 px from the nearest contour of b.
  const auto one = Disc(10, 10, 5), two = Disc(30, 30, 5);
  const ComparableImage a = CoverageImage(40, 40, [&](double x, double y) { return one(x, y) || two(x, y); });
  const ComparableImage b = CoverageImage(40, 40, one);
  const ImageComparison c = CompareImages(a, b);
  ASSERT_TRUE(c.silhouette.has_value());
  // The far side of the second disc to the near side of the first: |(30,30)-(10,10)| + 5 − 5.
  EXPECT_NEAR(c.silhouette->max, std::hypot(20.0, 20.0), 0.5);
  EXPECT_GT(c.pixelsCoverageDiffers, 60);

  const ComparableImage empty = CoverageImage(40, 40, [](double, double) { return false; });
  EXPECT_TRUE(CompareImages(a, empty).silhouetteMissing);
}

TEST(ImageCompare, DepthAndNormalErrorsOnCommonFullPixels) {
  ComparableImage a = CoverageImage(8, 8, [](double x, double) { return x < 6; });
  ComparableImage b = a;
  const double turn = 10 * M_PI / 180;
  for (ComparableImage* img : {&a, &b}) {
    img->z.assign(64, 0.0f);
    img->normal.assign(3 * 64, 0.0f);
    img->id.assign(64, 0.0f);
  }
  for (size_t k = 0; k < 64; ++k) {
    a.z[k] = 2.02f;
    b.z[k] = 2.0f;
    a.normal[3 * k] = static_cast<float>(std::sin(turn));
    a.normal[3 * k + 2] = static_cast<float>(std::cos(turn));
    b.normal[3 * k + 2] = 1.0f;
  }
  b.id[0] = 1.0f;  // a different surface: not compared
  const ImageComparison c = CompareImages(a, b);
  ASSERT_TRUE(c.depth && c.normalDegrees);
  EXPECT_EQ(c.depth->count, 6 * 8 - 1);  // the full pixels of both, less the other surface's
  constexpr double kFloatTol = 1e-5;     // the inputs are floats
  EXPECT_NEAR(c.depth->max, 0.01, kFloatTol);
  EXPECT_NEAR(c.depth->p99, 0.01, kFloatTol);
  EXPECT_NEAR(c.normalDegrees->max, 10.0, 1e-3);
}

TEST(ImageCompare, TheFrameIsNoCoverageEdge) {
  // A full-frame background has no contour: not "0 px" over the frame's border, which would
  // say the silhouettes agree when none were measured.
  const ComparableImage full = CoverageImage(24, 16, [](double, double) { return true; });
  EXPECT_TRUE(CoverageEdges(full.alpha, full.width, full.height).from.empty());
  ComparableImage other = full;
  other.rgb[3 * 40] = 0.25f;  // a colour difference only
  const ImageComparison c = CompareImages(other, full);
  EXPECT_FALSE(c.silhouette.has_value());
  EXPECT_TRUE(c.noContours);
  EXPECT_FALSE(c.silhouetteMissing);
  // A disc cut by the frame: its contour ends at the frame, none runs along it.
  const ComparableImage cut = CoverageImage(24, 16, Disc(0.0, 8.0, 6.0));
  for (const Vec2& p : CoverageEdges(cut.alpha, cut.width, cut.height).from)
    EXPECT_NEAR((p - Vec2(0.0, 8.0)).norm(), 6.0, 0.15) << p.transpose();
}

TEST(ImageCompare, WhereTheLargestColourDifferenceIs) {
  ComparableImage a = CoverageImage(32, 24, Disc(16, 12, 8)), b = a;
  for (int dy = -1; dy <= 1; ++dy)  // a 3 x 3 blotch, strongest at (20, 9)
    for (int dx = -1; dx <= 1; ++dx) a.rgb[3 * static_cast<size_t>((9 + dy) * 32 + 20 + dx)] -= dx == 0 && dy == 0 ? 0.8f : 0.5f;
  const ImageComparison c = CompareImages(a, b);
  EXPECT_EQ(c.colourWorstX, 20);
  EXPECT_EQ(c.colourWorstY, 9);
  EXPECT_NEAR(c.maxColourDifference, 0.8, 1e-6);
  EXPECT_NEAR(c.colourWorstB[0] - c.colourWorstA[0], 0.8, 1e-6);
  EXPECT_EQ(c.colourWorstRegionPixels, 9);
  EXPECT_EQ(c.colourWorstRegion, (std::array<int, 4>{19, 8, 21, 10}));
}

TEST(ImageCompare, SummaryPercentileIsTheNearestRank) {
  std::vector<double> e;
  for (int i = 1; i <= 200; ++i) e.push_back(i);
  const ErrorStats s = Summarize(e);
  EXPECT_EQ(s.count, 200);
  EXPECT_EQ(s.max, 200.0);
  EXPECT_EQ(s.p99, 198.0);  // rank ceil(0.99 · 200) = 198
  EXPECT_DOUBLE_EQ(s.mean, 100.5);
}

}  // namespace
}  // namespace patchscan::raster
