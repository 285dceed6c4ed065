// Two renders of one scene compared the way a user weighs speed against accuracy: where the
// coverage edges lie (in pixels), depth and normal of the surfaces both see, and colour.
// The second image is the reference. Free functions on plain arrays, so a test can build
// images by hand; ReadComparable reads any image OpenImageIO reads.
#pragma once

#include <array>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "core/vec.h"

namespace patchscan::raster {

// One image's layers as floats, row-major, top row first. Empty vectors: the image has no
// such channel. `rgb` holds 3 floats per pixel (grey images are copied into all three).
struct ComparableImage {
  int width = 0, height = 0;
  std::vector<float> rgb;     // colour
  std::vector<float> alpha;   // coverage ("A" or the spec's alpha channel)
  std::vector<float> z;       // eye distance ("Z" or the spec's z channel); 0: no surface
  std::vector<float> normal;  // 3 floats per pixel: "N.x", "N.y", "N.z"
  std::vector<float> id;      // surface id ("id"), -1: no surface
};

// Reads `path` through OpenImageIO; the message (naming the file) when it cannot.
std::variant<ComparableImage, std::string> ReadComparable(const std::string& path);

// The alpha = 1/2 contour of a coverage image: marching squares over the pixel centres
// (pixel (x, y) has its centre at (x + 1/2, y + 1/2)), with alpha taken as 0 outside the
// image so that contours close. Segments in image coordinates; allocates.
struct CoverageContour {
  std::vector<Vec2> from, to;
};
CoverageContour CoverageEdges(const std::vector<float>& alpha, int width, int height);

// For each end point of each segment of `a`, its distance in pixels to the nearest segment
// of `b`: nothing when `b` has no segment. A grid of cells finds the nearest segment in
// time proportional to the distance searched.
std::vector<double> DistancesToContour(const CoverageContour& a, const CoverageContour& b, int width,
                                       int height);

// Maximum, 99th percentile (nearest rank) and mean of a set of errors; count 0 when empty.
struct ErrorStats {
  long count = 0;
  double max = 0, p99 = 0, mean = 0;
};
ErrorStats Summarize(std::vector<double> errors);

struct ImageComparison {
  // Coverage: distances between the two images' alpha = 1/2 contours, both ways (a
  // symmetric Hausdorff measure); `silhouette` empty when either image has no alpha, or
  // neither has any contour. `pixelsCoverageDiffers`: |alpha_a - alpha_b| > 1/2.
  std::optional<ErrorStats> silhouette;
  bool silhouetteMissing = false;  // one image has a contour and the other none
  bool noContours = false;         // both have alpha and neither a contour (the frame covered, or empty)
  Vec2 silhouetteWorst = Vec2::Zero();  // the contour point (pixel coordinates) farthest from the other
  bool silhouetteWorstInA = true;       // on a's contour, else on b's
  long pixelsCoverageDiffers = 0;
  double coverageAreaDifference = 0;  // sum of |alpha_a - alpha_b|, in pixels
  // On pixels both cover fully (alpha = 1) with the same surface id (when both carry ids):
  // |z_a - z_b| / z_b and the angle between the normals in degrees.
  std::optional<ErrorStats> depth, normalDegrees;
  // Colour over every pixel and channel; PSNR against a peak of 1 (infinite when equal).
  double rmse = 0, psnr = 0;
  double maxColourDifference = 0;
  // Where the largest colour difference is: the pixel, both colours there, and the box of
  // the pixels within kWorstRegionPx of it that differ by more than half as much (x0, y0,
  // x1, y1 inclusive) with their count.
  int colourWorstX = 0, colourWorstY = 0;
  std::array<double, 3> colourWorstA{}, colourWorstB{};
  std::array<int, 4> colourWorstRegion{};
  int colourWorstRegionPixels = 0;
};
constexpr int kWorstRegionPx = 8;

// Compares `a` with the reference `b`, which must have the same size.
ImageComparison CompareImages(const ComparableImage& a, const ComparableImage& b);

}  // namespace patchscan::raster
