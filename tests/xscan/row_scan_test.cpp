// The exact scan split by rows between threads (RowScan, sort-first: Molnar et al. 1994)
// must give the very image one scan gives, bit for bit in every channel, for any number of
// threads, whether the back end drives its batches (every thread resolving and shading) or
// a wrapping source asks row by row (the scan ahead on a thread of its own); and it must
// do the very same work: every count of the scan equal to one scan's (no Newton solve
// twice, no sample another surface hides solved: occlusion culling kept).
#include <gtest/gtest.h>

#include <cstring>
#include <string>
#include <vector>

#include "raster/scanline_renderer.h"
#include "render/options.h"
#include "xscan/exact_scan.h"
#include "xscan/polygon_feed.h"
#include "xscan/render_settings.h"
#include "xscan/row_scan.h"
#include "xscan/small_scenes.h"

namespace patchscan {
namespace {

using test::KeepRows;
using test::SceneCase;
using test::SettingsFor;
using test::SmallScenes;

// The first differing float of two renders, as "pixel (x, y) channel c"; empty if none.
std::string FirstDifference(const KeepRows& got, const KeepRows& want, int width) {
  if (got.rows.size() != want.rows.size()) return "a different number of rows";
  const std::size_t perRow = static_cast<std::size_t>(width) * raster::kChannels;
  for (std::size_t k = 0; k < want.rows.size(); ++k)
    if (std::memcmp(&got.rows[k], &want.rows[k], sizeof(float)) != 0)
      return "pixel (" + std::to_string((k % perRow) / raster::kChannels) + ", " + std::to_string(k / perRow) +
             ") channel " + std::to_string(k % raster::kChannels);
  return {};
}

class SameImageAndWorkForAnyNumberOfThreads : public ::testing::TestWithParam<int> {};

TEST_P(SameImageAndWorkForAnyNumberOfThreads, InEveryScene) {
  const int aa = GetParam();
  render::RenderOptions options;
  options.mode = render::RenderMode::Exact;
  const ExactScanOptions o = render::ScanOptionsFor(options, aa);
  ASSERT_TRUE(RowScan::Splits(o));
  ASSERT_GT(o.adoptRows, 1) << "batches of several rows, or the test proves little";
  long compared = 0;
  for (const SceneCase& c : SmallScenes()) {
    raster::TriangleMesh polygons = render::PolygonTriangles(c.scene, c.camera);
    raster::RenderSettings s = SettingsFor(c.camera, aa);
    ExactScan alone(c.scene.surfaces, c.camera, o);
    PolygonFeed aloneFed(alone, polygons);
    KeepRows want(c.camera.width);
    ASSERT_TRUE(raster::RenderFragments(aloneFed, s, want)) << c.name;
    const Counters a = alone.Stats();
    for (const int threads : {2, 3, 7}) {
      // The back end on the threads takes the rows in batches; on one thread it asks for
      // them row by row (the scan's threads fill a ring ahead of it).
      for (const bool rowByRow : {false, true}) {
        const std::string what = c.name + ", aa " + std::to_string(aa) + ", " + std::to_string(threads) +
                                 " threads, " + (rowByRow ? "asked row by row" : "batches");
        s.threads = rowByRow ? 1 : threads;
        RowScan rows(c.scene.surfaces, c.camera, o, threads);
        PolygonFeed fed(rows, polygons);
        KeepRows got(c.camera.width);
        ASSERT_TRUE(raster::RenderFragments(fed, s, got)) << what;
        EXPECT_EQ(FirstDifference(got, want, c.camera.width), "") << what;
        const Counters b = rows.Stats();
        for (const CounterInfo& info : kCounterTable)
          EXPECT_EQ(a[info.counter], b[info.counter]) << what << ": " << info.key;
        // The X scans ran on the threads (each thread's seconds), the Y scans on one.
        const DirectScanSource::Timing t = rows.Times();
        EXPECT_GE(t.workerSeconds.size(), 1u) << what;
        ++compared;
      }
    }
  }
  EXPECT_EQ(compared, 15 * 3 * 2);  // every scene, each thread count both ways
}

INSTANTIATE_TEST_SUITE_P(RowScan, SameImageAndWorkForAnyNumberOfThreads, ::testing::Values(1, 3, 4),
                         [](const ::testing::TestParamInfo<int>& info) { return "aa" + std::to_string(info.param); });

// A batch ends on the rows that take up what the X scans found, and only there: the same
// rows for any number of threads, whole pixel rows, about kBatchSampleRows apart.
TEST(RowScan, BatchesAreWholePixelRowsWhateverTheThreads) {
  for (const int aa : {1, 2, 3, 4, 8}) {
    render::RenderOptions options;
    const ExactScanOptions o = render::ScanOptionsFor(options, aa);
    const int perPixel = aa == 1 ? 1 : aa - 1;  // new sample rows a pixel row
    EXPECT_EQ(o.adoptRows % perPixel, 0) << "aa " << aa;
    EXPECT_GE(o.adoptRows, 4) << "aa " << aa;
    EXPECT_LE(o.adoptRows, 16) << "aa " << aa;
    // A pixel row p's last sample row: (p + 1) perPixel (aa > 1; its bottom edge) or p.
    for (long p = 0; p < 64; ++p) {
      const long last = aa == 1 ? p : (p + 1) * perPixel;
      const bool ends = (p + 1) % (o.adoptRows / perPixel) == 0;
      EXPECT_EQ(o.AdoptsOn(last), ends) << "aa " << aa << ", pixel row " << p;
    }
  }
}

}  // namespace
}  // namespace patchscan
