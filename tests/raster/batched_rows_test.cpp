// A mesh's rows resolved in batches on threads (raster/batched_rows.h) against the same mesh
// resolved row by row on one thread: every channel of every pixel bit for bit, and every
// count, for any number of threads.
#include <gtest/gtest.h>

#include <cstring>
#include <random>
#include <vector>

#include "raster/scanline_renderer.h"

namespace patchscan::raster {
namespace {

// Every channel of every row, in row order (rows come in order from one thread).
struct AllChannels : RowSink {
  int width;
  std::vector<float> pixels;
  std::vector<int> rows;
  explicit AllChannels(int w) : width(w) {}
  bool WriteRow(int y, const float* row) override {
    rows.push_back(y);
    pixels.insert(pixels.end(), row, row + static_cast<std::size_t>(width) * kChannels);
    return true;
  }
};

// A soup of triangles of several surfaces crossing each other at random depths, some
// reaching past the image, so that samples are hidden, ties of coverage resolved and
// triangles retired and their slots reused across many batches.
TriangleMesh Soup(int width, int height, int count, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> x(-10.0, width + 10.0), y(-10.0, height + 10.0), z(2.0, 9.0),
      d(-25.0, 25.0), n(-1.0, 1.0);
  TriangleMesh m;
  for (int t = 0; t < count; ++t) {
    const double cx = x(rng), cy = y(rng);
    for (int k = 0; k < 3; ++k) {
      const double w = z(rng), px = cx + d(rng), py = cy + d(rng);
      RasterVertex v;
      v.h = Vec3(px * w, py * w, w);
      v.position = Vec3(px / 50.0, py / 50.0, w);
      v.normal = Vec3(n(rng), n(rng), -1.0);
      v.uv = Vec2(px / width, py / height);
      m.vertices.push_back(v);
    }
    const auto v0 = static_cast<std::uint32_t>(3 * t);
    m.triangles.push_back({{v0, v0 + 1, v0 + 2}, static_cast<std::uint32_t>(t % 5)});
  }
  return m;
}

struct Rendered {
  AllChannels sink;
  Counters counts;
};

Rendered Render(const TriangleMesh& mesh, RenderSettings s, int threads) {
  s.threads = threads;
  Rendered r{AllChannels(s.width), {}};
  const auto counts = RenderMesh(mesh, s, r.sink);
  EXPECT_TRUE(counts.has_value());
  if (counts) r.counts = *counts;
  return r;
}

TEST(BatchedRows, AMeshIsTheSameForAnyNumberOfThreads) {
  const int width = 97, height = 71;
  const TriangleMesh mesh = Soup(width, height, 400, 7);
  for (const int aa : {1, 2, 3, 4})
    for (const ShadingMode shading : {ShadingMode::Phong, ShadingMode::Gouraud})
      for (const double opacity : {1.0, 0.5}) {
        RenderSettings s;
        s.width = width;
        s.height = height;
        s.aa = aa;
        s.hither = 0.5;
        s.shading = shading;
        s.opacity = opacity;
        const Rendered one = Render(mesh, s, 1);
        ASSERT_EQ(one.sink.rows.size(), static_cast<std::size_t>(height));
        for (const int threads : {2, 3, 7}) {
          const Rendered many = Render(mesh, s, threads);
          const std::string what = "aa " + std::to_string(aa) + (shading == ShadingMode::Gouraud ? " Gouraud" : "") +
                                   " opacity " + std::to_string(opacity) + ", " + std::to_string(threads) + " threads";
          EXPECT_EQ(many.sink.rows, one.sink.rows) << what;
          ASSERT_EQ(many.sink.pixels.size(), one.sink.pixels.size()) << what;
          // Bit for bit (NaN-free channels: memcmp, so that -0 and 0 differ too).
          EXPECT_EQ(std::memcmp(many.sink.pixels.data(), one.sink.pixels.data(), one.sink.pixels.size() * sizeof(float)),
                    0)
              << what;
          for (const CounterInfo& c : kCounterTable)
            EXPECT_EQ(many.counts[c.counter], one.counts[c.counter]) << what << ": " << c.key;
        }
      }
}

}  // namespace
}  // namespace patchscan::raster
