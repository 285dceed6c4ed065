// Molnar's object partition on threads (1990): the scene's surfaces dealt out to
// workers and their rows composited must give the very image one scan of all surfaces
// gives, bit for bit in every channel, for any number of workers and threads, in every
// direct mode; and the partition covers every surface once, in scan order, balanced.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <string>
#include <variant>
#include <vector>

#include "scene/scene.h"
#include "raster/scanline_renderer.h"
#include "xscan/exact_scan.h"
#include "xscan/partitioned_scan.h"
#include "xscan/polygon_feed.h"
#include "xscan/render_settings.h"
#include "xscan/small_scenes.h"

namespace patchscan {
namespace {

using test::KeepRows;

using test::SceneCase;
using test::SmallScenes;

struct Mode {
  std::string name;
  int thetaSteps, slabRows, aa;
};
const Mode kModes[] = {{"exact", 0, 0, 3},          {"theta per row", 16, 0, 2}, {"theta per row aa 4", 16, 0, 4},
                       {"theta slabs 1 px", 16, 2, 3}, {"theta slabs 3 px", 8, 9, 4}};

using test::SettingsFor;

// One test per mode, so that ctest runs them side by side.
class SameImageForAnyNumberOfWorkers : public ::testing::TestWithParam<std::size_t> {};

TEST_P(SameImageForAnyNumberOfWorkers, InEveryScene) {
  long compared = 0;
  const Mode& m = kModes[GetParam()];
  for (const SceneCase& c : SmallScenes()) {
    ExactScanOptions o;
    o.thetaSteps = m.thetaSteps;
    o.slabRows = m.slabRows;
    const raster::RenderSettings s = SettingsFor(c.camera, m.aa);
    // The scene's polygons join every render's rows the same way.
    raster::TriangleMesh polygons = render::PolygonTriangles(c.scene, c.camera);
    ExactScan alone(c.scene.surfaces, c.camera, o);
    PolygonFeed aloneFed(alone, polygons);
    KeepRows want(c.camera.width);
    ASSERT_TRUE(raster::RenderFragments(aloneFed, s, want)) << c.name << ", " << m.name;
    for (const auto& [workers, threads] : {std::pair{1, 1}, {2, 2}, {3, 2}, {7, 2}, {7, 7}}) {
      PartitionedScan parts(c.scene.surfaces, c.camera, o, workers, threads);
      PolygonFeed partsFed(parts, polygons);
      KeepRows got(c.camera.width);
      // The back end on as many threads (θ: in batches, raster/batched_rows.h).
      raster::RenderSettings on = s;
      on.threads = threads;
      ASSERT_TRUE(raster::RenderFragments(partsFed, on, got)) << c.name << ", " << m.name;
      ASSERT_EQ(got.rows.size(), want.rows.size());
      std::size_t differ = 0, first = 0;
      for (std::size_t k = 0; k < want.rows.size(); ++k)
        if (std::memcmp(&got.rows[k], &want.rows[k], sizeof(float)) != 0 && differ++ == 0) {
          first = k;
        }
      const std::size_t perRow = static_cast<std::size_t>(c.camera.width) * raster::kChannels;
      EXPECT_EQ(differ, 0u) << c.name << ", " << m.name << ", " << workers << " workers on " << threads
                            << " threads: first at pixel (" << (first % perRow) / raster::kChannels << ", "
                            << first / perRow << ") channel " << first % raster::kChannels;
      // The counts too (the most surfaces active at once is per worker).
      const Counters a = alone.Stats(), b = parts.Stats();
      for (const CounterInfo& info : kCounterTable) {
        if (info.counter == Counter::MaxActiveSurfaces) continue;
        EXPECT_EQ(a[info.counter], b[info.counter]) << c.name << ", " << m.name << ", " << workers << " workers: "
                                                    << info.key;
      }
      ++compared;
    }
  }
  EXPECT_EQ(compared, 15 * 5);  // scenes, worker counts
}

INSTANTIATE_TEST_SUITE_P(Partition, SameImageForAnyNumberOfWorkers, ::testing::Range<std::size_t>(0, std::size(kModes)),
                         [](const ::testing::TestParamInfo<std::size_t>& info) {
                           std::string name;
                           for (const char ch : kModes[info.param].name) name += ch == ' ' ? '_' : ch;
                           return name;
                         });

TEST(Partition, ThetaInBatchesIsTheRowsOneByOne) {
  // The back end on threads takes θ rows in batches (the workers scan a batch, the slabs'
  // and the scene's polygons' triangles join the store, then every thread merges and
  // resolves rows); on one thread it
  // takes them one by one from the scan-ahead. The same workers give the same pixels and
  // counts either way, at any supersampling (a batch's rows are whole pixel rows: at aa 4,
  // three sample rows a pixel row, a batch may run past its block of rows).
  long compared = 0;
  for (const SceneCase& c : SmallScenes()) {
    const raster::TriangleMesh polygons = render::PolygonTriangles(c.scene, c.camera);
    for (const int slabRows : {0, 2, 9}) {
      ExactScanOptions o;
      o.thetaSteps = 16;
      o.slabRows = slabRows;
      for (const int aa : {1, 3, 4}) {
        raster::RenderSettings s = SettingsFor(c.camera, aa);
        PartitionedScan byRow(c.scene.surfaces, c.camera, o, 2, 2);
        PolygonFeed byRowFed(byRow, polygons);
        KeepRows want(c.camera.width);
        const auto backEnd = raster::RenderFragments(byRowFed, s, want);  // the back end's counts
        ASSERT_TRUE(backEnd) << c.name;
        for (const int threads : {2, 7}) {
          const std::string what =
              c.name + ", slabs " + std::to_string(slabRows) + ", aa " + std::to_string(aa) + ", " + std::to_string(threads);
          PartitionedScan batched(c.scene.surfaces, c.camera, o, 2, threads);
          PolygonFeed batchedFed(batched, polygons);
          s.threads = threads;
          ASSERT_TRUE(batchedFed.ScansInBatches()) << what;
          KeepRows got(c.camera.width);
          const auto batchedBackEnd = raster::RenderFragments(batchedFed, s, got);
          ASSERT_TRUE(batchedBackEnd) << what;
          ASSERT_EQ(got.rows.size(), want.rows.size());
          EXPECT_EQ(std::memcmp(got.rows.data(), want.rows.data(), want.rows.size() * sizeof(float)), 0) << what;
          Counters a = byRow.Stats(), b = batched.Stats();
          a.Merge(*backEnd);
          b.Merge(*batchedBackEnd);
          // Except the back end's samples tested: the scan-ahead drops a fragment the merged
          // row hides before the back end sees it (DepthFilter), a batch's back end tests it.
          for (const CounterInfo& info : kCounterTable) {
            if (info.counter != Counter::SamplesTested) {
              EXPECT_EQ(a[info.counter], b[info.counter]) << what << ": " << info.key;
            }
          }
          ++compared;
        }
      }
    }
  }
  EXPECT_GE(compared, 60);
}

TEST(Partition, EverySurfaceOnceInScanOrderAndBalanced) {
  for (const SceneCase& c : SmallScenes()) {
    const std::vector<ScanEntry> order = ScanOrder(c.scene.surfaces, c.camera);
    for (int workers : {1, 2, 3, 7, 64}) {
      const auto shares = PartitionSurfaces(order, c.camera, workers);
      ASSERT_EQ(shares.size(), static_cast<std::size_t>(workers));
      std::vector<int> seen(c.scene.surfaces.size(), 0);
      double biggest = 0.0, lo = INFINITY, hi = 0.0;
      const double image = static_cast<double>(c.camera.width) * c.camera.height;
      for (const auto& share : shares) {
        double load = 0.0;
        for (std::size_t k = 0; k < share.size(); ++k) {
          ++seen[share[k].index];
          // In scan order: by the top of the screen box, then by index.
          if (k > 0) {
            EXPECT_TRUE(share[k - 1].yMin < share[k].yMin ||
                        (share[k - 1].yMin == share[k].yMin && share[k - 1].index < share[k].index))
                << c.name;
          }
          const double work = std::min(share[k].area, image);
          load += work;
          biggest = std::max(biggest, work);
        }
        lo = std::min(lo, load);
        hi = std::max(hi, load);
      }
      for (const ScanEntry& e : order) EXPECT_EQ(seen[e.index], 1) << c.name << " surface " << e.index;
      // Largest first to the least loaded: no worker ends more than one surface's work
      // (and its set-up) above another.
      constexpr double kSetUpSlack = 256.0 * 64;  // the set-up allowance of each surface, generously
      if (workers <= static_cast<int>(order.size())) {
        EXPECT_LE(hi - lo, biggest + kSetUpSlack) << c.name;
      }
      EXPECT_EQ(shares, PartitionSurfaces(order, c.camera, workers)) << "deterministic";
    }
  }
}

}  // namespace
}  // namespace patchscan
