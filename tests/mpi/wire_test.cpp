// patchscan-mpi's messages (mpi/wire.h): what one process encodes, another decodes to the
// same values, bit for bit (the processes' pixels must equal one process's); a malformed
// request is refused.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "mpi/wire.h"

namespace patchscan::mpi {
namespace {

FrameRequest Sample() {
  FrameRequest r;
  r.frame = 3;
  r.extrapolate = false;
  r.thetaSteps = 48;
  r.slabRows = 5;
  r.columns = raster::SampleColumns{0.125, 1.0 / 3.0, 1601};
  r.y0 = -0.375;
  r.dy = 0.2857142857142857;
  r.nRows = 4097;
  r.aa = 7;
  r.channels = 4;
  return r;
}

TEST(Wire, FrameRequestRoundTrips) {
  const FrameRequest in = Sample();
  const auto out = FrameRequest::Decode(in.Encode());
  ASSERT_TRUE(out.has_value());
  EXPECT_EQ(out->frame, in.frame);
  EXPECT_EQ(out->extrapolate, in.extrapolate);
  EXPECT_EQ(out->thetaSteps, in.thetaSteps);
  EXPECT_EQ(out->slabRows, in.slabRows);
  EXPECT_EQ(out->columns.x0, in.columns.x0);
  EXPECT_EQ(out->columns.dx, in.columns.dx);
  EXPECT_EQ(out->columns.n, in.columns.n);
  EXPECT_EQ(out->y0, in.y0);
  EXPECT_EQ(out->dy, in.dy);
  EXPECT_EQ(out->nRows, in.nRows);
  EXPECT_EQ(out->aa, in.aa);
  EXPECT_EQ(out->channels, in.channels);
  // And the defaults.
  const auto defaults = FrameRequest::Decode(FrameRequest{}.Encode());
  ASSERT_TRUE(defaults.has_value());
  EXPECT_TRUE(defaults->extrapolate);
  EXPECT_EQ(defaults->channels, raster::kChannels);
}

TEST(Wire, MalformedFrameRequestIsRefused) {
  std::vector<double> m = Sample().Encode();
  EXPECT_FALSE(FrameRequest::Decode({}).has_value());
  EXPECT_FALSE(FrameRequest::Decode(std::vector<double>(m.begin(), m.end() - 1)).has_value());
  std::vector<double> longer = m;
  longer.push_back(0.0);
  EXPECT_FALSE(FrameRequest::Decode(longer).has_value());
  for (const std::size_t k : {0u, 2u, 6u, 9u, 10u}) {  // counts: whole and finite
    std::vector<double> bad = m;
    bad[k] += 0.5;
    EXPECT_FALSE(FrameRequest::Decode(bad).has_value()) << k;
  }
  std::vector<double> nan = m;
  nan[7] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(FrameRequest::Decode(nan).has_value());
}

TEST(Wire, FragmentRoundTrips) {
  raster::Fragment f;
  f.w = 12.345678901234567;
  f.position = Vec3(1e-300, -2.5, 3.0 / 7.0);
  f.normal = Vec3(0.6, 0.0, -0.8);
  f.uv = Vec2(0.1, 0.9);
  f.duvdx = Vec2(1e-9, -3e-7);
  f.duvdy = Vec2(-0.0, 2.0);
  f.surfaceId = 4000000000u;
  f.colour = Vec3(0.25, 0.5, 0.75);
  std::vector<double> m;
  PutFragment(m, f);
  ASSERT_EQ(m.size(), kFragmentBody);
  const raster::Fragment g = GetFragment(m.data());
  EXPECT_EQ(g.w, f.w);
  EXPECT_EQ(g.position, f.position);
  EXPECT_EQ(g.normal, f.normal);
  EXPECT_EQ(g.uv, f.uv);
  EXPECT_EQ(g.duvdx, f.duvdx);
  EXPECT_EQ(g.duvdy, f.duvdy);
  EXPECT_EQ(g.surfaceId, f.surfaceId);
  EXPECT_EQ(g.colour, f.colour);
}

TEST(Wire, TriangleRoundTrips) {
  Layout layout;
  layout.nRows = 100;
  const std::vector<std::uint32_t> ranks = {2, 0, 1};
  RowEncoder encoder(ranks, layout);
  encoder.Begin(17);
  raster::RasterVertex v[3];
  for (int k = 0; k < 3; ++k) {
    v[k].h = Vec3(10.0 + k, 20.0 + 0.1 * k, 1.5);
    v[k].position = Vec3(k, -k, 0.5 * k);
    v[k].normal = Vec3(0.0, 0.0, 1.0 + k);
    v[k].uv = Vec2(0.25 * k, 1.0 / (k + 1));
    v[k].depth = 3.0 + k;
    v[k].colour = Vec3(1.0, 0.5, 0.125 * k);
  }
  encoder.AddTriangle(v[0], v[1], v[2], 1u);
  ASSERT_EQ(encoder.triangles.size(), kTriangle);
  EXPECT_EQ(encoder.triangles[0], 17.0);  // the row it was handed over on
  EXPECT_EQ(encoder.triangles[1], 0.0);   // its surface's rank
  EXPECT_EQ(encoder.triangles[2], 1.0);   // its surface
  for (int k = 0; k < 3; ++k) {
    const raster::RasterVertex w = DecodeVertex(encoder.triangles.data() + 3 + k * kVertex);
    EXPECT_EQ(w.h, v[k].h);
    EXPECT_EQ(w.position, v[k].position);
    EXPECT_EQ(w.normal, v[k].normal);
    EXPECT_EQ(w.uv, v[k].uv);
    EXPECT_EQ(w.depth, v[k].depth);
    EXPECT_EQ(w.colour, v[k].colour);
  }
  ASSERT_EQ(encoder.lastRows.size(), 1u);
  EXPECT_EQ(encoder.lastRows[0], 13);  // its lowest vertex at y = 20.2 / 1.5 px, rows 1 px apart from 0
}

TEST(Wire, TextRoundTrips) {
  const std::string why = "surfaces/teapot.bpt:12: cannot read";
  const std::vector<double> m = Text(why);
  EXPECT_EQ(TextOf(m.data(), m.size()), why);
}

}  // namespace
}  // namespace patchscan::mpi
