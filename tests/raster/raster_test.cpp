// The back end: Olano-Greer setup against direct evaluation, coverage against exact
// areas, shared edges covered exactly once, all-or-nothing image output.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <limits>
#include <random>

#include <Eigen/SVD>
#include <OpenImageIO/imageio.h>

#include "raster/async_row_sink.h"
#include "raster/image_writer.h"
#include "raster/srgb.h"
#include "raster/scanline_renderer.h"
#include "raster/shadow_map.h"
#include "raster/triangle_setup.h"
#include "raster/triangle_store.h"

#include <unistd.h>

namespace patchscan::raster {
namespace {

// A simple pinhole for building test vertices: camera at the origin looking along +z,
// focal f pixels, centre (cx, cy): X = f x + cx z, Y = f y + cy z, W = z.
Vec3 Homogeneous(const Vec3& p, double f = 100, double cx = 64, double cy = 48) {
  return Vec3(f * p.x() + cx * p.z(), f * p.y() + cy * p.z(), p.z());
}

TEST(TriangleSetup, PerspectiveCorrectBarycentricsMatchWorldSpace) {
  // Interpolating with b_i = e_i / sum(e) at the projection of sum(b_i P_i) gives back b,
  // to the rounding of a 3x3 system of numbers near 1e2 (~1e-14) times its condition: a
  // thin random triangle's is in the hundreds (compilers that order the sums differently
  // then disagree at 3e-12).
  constexpr double kBaryTolPerCondition = 1e-14;
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> d(-1, 1), depth(0.5, 5);
  for (int n = 0; n < 200; ++n) {
    const Vec3 p[3] = {Vec3(d(rng), d(rng), depth(rng)), Vec3(d(rng), d(rng), depth(rng)),
                       Vec3(d(rng), d(rng), depth(rng))};
    const auto t = SetupTriangle(Homogeneous(p[0]), Homogeneous(p[1]), Homogeneous(p[2]), false, 128, 96);
    if (!t) continue;
    Eigen::Matrix3d m;
    m << Homogeneous(p[0]), Homogeneous(p[1]), Homogeneous(p[2]);
    const Vec3 sv = Eigen::JacobiSVD<Eigen::Matrix3d>(m).singularValues();
    const double kBaryTol = kBaryTolPerCondition * std::max(100.0, sv[0] / sv[2]);
    Vec3 b(d(rng) + 1, d(rng) + 1, d(rng) + 1);
    b /= b.sum();
    const Vec3 h = Homogeneous(b[0] * p[0] + b[1] * p[1] + b[2] * p[2]);
    const double x = h.x() / h.z(), y = h.y() / h.z();
    double e[3];
    Vec3 ev;
    for (int i = 0; i < 3; ++i) ev[i] = t->edge[i].dot(Vec3(x, y, 1));
    EXPECT_LE((ev / ev.sum() - b).norm(), kBaryTol) << "triangle " << n;
    if (b.minCoeff() > 1e-9) {
      EXPECT_TRUE(Inside(*t, x, y, e)) << "triangle " << n;
    }
    // 1/w interpolates as sum(e) |1/det|.
    EXPECT_NEAR(ev.sum() * std::abs(t->invDet), 1.0 / h.z(), kBaryTol / h.z());
  }
}

TEST(TriangleSetup, TriangleCrossingTheEyePlane) {
  // One vertex behind the eye: points of the triangle in front of the eye are inside,
  // the projections of points behind the eye are not.
  const Vec3 p[3] = {Vec3(-1, -0.5, 2), Vec3(1, -0.4, 3), Vec3(0.2, 0.6, -1)};
  const auto t = SetupTriangle(Homogeneous(p[0]), Homogeneous(p[1]), Homogeneous(p[2]), false, 128, 96);
  ASSERT_TRUE(t);
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<double> d(0.01, 1);
  int front = 0, behind = 0;
  for (int n = 0; n < 500; ++n) {
    Vec3 b(d(rng), d(rng), d(rng));
    b /= b.sum();
    const Vec3 q = b[0] * p[0] + b[1] * p[1] + b[2] * p[2];
    if (std::abs(q.z()) < 1e-3) continue;
    const Vec3 h = Homogeneous(q);
    double e[3];
    const bool in = Inside(*t, h.x() / h.z(), h.y() / h.z(), e);
    if (q.z() > 0) {
      EXPECT_TRUE(in) << "front point " << q.transpose();
      ++front;
    }
  }
  EXPECT_GT(front, 100);
  // A pixel whose ray meets the triangle's plane only behind the eye is outside: the
  // direction of the reflected vertex, (0.2, 0.6, -1) seen through the eye, hits the plane
  // at negative depth.
  const Vec3 h = Homogeneous(-p[2]);
  double e[3];
  EXPECT_FALSE(Inside(*t, h.x() / h.z(), h.y() / h.z(), e));
  (void)behind;
}

TEST(TriangleSetup, BackFacesAndDegenerates) {
  const Vec3 a(10, 10, 1), b(50, 10, 1), c(10, 40, 1);
  ASSERT_TRUE(SetupTriangle(a, b, c, true, 128, 96));
  EXPECT_TRUE(SetupTriangle(a, b, c, true, 128, 96)->frontFacing);
  EXPECT_FALSE(SetupTriangle(a, c, b, true, 128, 96));  // back-facing, culled
  EXPECT_TRUE(SetupTriangle(a, c, b, false, 128, 96));  // kept when two-sided
  EXPECT_FALSE(SetupTriangle(a, b, Vec3(30, 10, 1), false, 128, 96));  // zero area
}

TEST(TriangleSetup, FanCoversEverySampleExactlyOnce) {
  // Thin triangles around a vertex that lies on a sample, edges through samples: the tie
  // rule gives every sample inside the fan to exactly one triangle.
  const Vec3 centre(32, 32, 1);
  constexpr int kSpokes = 24;
  std::vector<TriangleSetup> fan;
  for (int k = 0; k < kSpokes; ++k) {
    auto spoke = [](int i) {
      const int dx[] = {20, 20, 20, 10, 0, -10, -20, -20, -20, -20, -20, -10, 0, 10, 20, 20};
      const int dy[] = {0, 10, 20, 20, 20, 20, 20, 10, 0, -10, -20, -20, -20, -20, -20, -10};
      return Vec3(32 + dx[i % 16], 32 + dy[i % 16], 1);
    };
    if (k >= 16) break;
    fan.push_back(*SetupTriangle(centre, spoke(k), spoke(k + 1), false, 64, 64));
  }
  // The fan's outer boundary belongs to its neighbours-to-be; test strictly inside it.
  for (int y = 13; y <= 51; ++y)
    for (int x = 13; x <= 51; ++x) {
      int owners = 0;
      double e[3];
      for (const TriangleSetup& t : fan) owners += Inside(t, x, y, e);
      EXPECT_EQ(owners, 1) << "sample (" << x << ", " << y << ")";
    }
}

// Collects rows, for coverage sums.
struct CaptureSink : RowSink {
  int width;
  std::vector<float> rgba;
  explicit CaptureSink(int w) : width(w) {}
  bool WriteRow(int, const float* row) override {
    for (int x = 0; x < width; ++x) rgba.insert(rgba.end(), row + x * kChannels, row + x * kChannels + 4);
    return true;
  }
  double Coverage() const {
    double sum = 0;
    for (size_t i = 3; i < rgba.size(); i += 4) sum += rgba[i];
    return sum;
  }
};

TriangleMesh Mesh(const std::vector<Vec2>& xy, const std::vector<std::array<int, 3>>& tris) {
  TriangleMesh m;
  for (const Vec2& p : xy) m.vertices.push_back({Vec3(p.x(), p.y(), 1), Vec3(p.x(), p.y(), 5), Vec3(0, 0, -1), Vec2(0, 0)});
  for (const auto& t : tris)
    m.triangles.push_back({{static_cast<std::uint32_t>(t[0]), static_cast<std::uint32_t>(t[1]),
                            static_cast<std::uint32_t>(t[2])}, 0});
  return m;
}

TEST(ScanlineRenderer, CoverageMatchesArea) {
  // Lattice-point counting error is bounded by the perimeter times the sample spacing.
  const std::vector<Vec2> xy = {Vec2(10.3, 7.7), Vec2(100.9, 20.2), Vec2(40.1, 80.6)};
  const double area = 0.5 * std::abs((xy[1] - xy[0]).x() * (xy[2] - xy[0]).y() -
                                     (xy[1] - xy[0]).y() * (xy[2] - xy[0]).x());
  const double perimeter = (xy[1] - xy[0]).norm() + (xy[2] - xy[1]).norm() + (xy[0] - xy[2]).norm();
  for (int aa : {1, 2, 3, 4, 8}) {
    RenderSettings s;
    s.width = 128;
    s.height = 96;
    s.aa = aa;
    s.hither = 0.01;
    CaptureSink sink(s.width);
    ASSERT_TRUE(RenderMesh(Mesh(xy, {{0, 1, 2}}), s, sink));
    const double spacing = aa == 1 ? 1.0 : 1.0 / (aa - 1);
    EXPECT_NEAR(sink.Coverage(), area, perimeter * spacing) << "aa " << aa;
  }
}

TEST(ScanlineRenderer, SharedEdgeLeavesNoGapAndNoOverlap) {
  // A square split along its diagonal, vertices on samples: every pixel inside is covered
  // exactly once (alpha 1), the total is the area exactly.
  const std::vector<Vec2> xy = {Vec2(8, 8), Vec2(72, 8), Vec2(72, 56), Vec2(8, 56)};
  for (int aa : {1, 3}) {
    RenderSettings s;
    s.width = 80;
    s.height = 64;
    s.aa = aa;
    s.hither = 0.01;
    CaptureSink sink(s.width);
    ASSERT_TRUE(RenderMesh(Mesh(xy, {{0, 1, 2}, {0, 2, 3}}), s, sink));
    for (int y = 9; y < 55; ++y)
      for (int x = 9; x < 71; ++x)
        EXPECT_FLOAT_EQ(sink.rgba[(static_cast<size_t>(y) * 80 + x) * 4 + 3], 1.0f) << x << "," << y;
  }
}

TEST(ScanlineRenderer, LevelSharedEdgeOnASampleRowLeavesNoGap) {
  // Two triangles sharing an edge that lies along sample row y = 36 in perspective (W other
  // than 1): X/W and Y/W round, so the shared edge's line has an x coefficient of rounding
  // and a value of rounding on the row. The row's span must not be clipped by it (-c / a is
  // noise over noise); the exact test gives each sample on it to exactly one triangle.
  // (A sphere's tessellated equator seen edge-on showed holes along its row.)
  int tried = 0;
  for (double w0 : {2.71817, 2.59903, 3.92301, 1.0 / 3.0, 7.1}) {
    for (double w1 : {2.73777, 2.61, 4.12349, 0.77}) {
      const auto vertex = [](double x, double y, double w) {
        return RasterVertex{Vec3(x * w, y * w, w), Vec3(x, y, 5), Vec3(0, 0, -1), Vec2(0, 0)};
      };
      TriangleMesh m;
      m.vertices = {vertex(10.3, 36.0, w0), vertex(70.7, 36.0, w1), vertex(40.1, 10.2, 0.5 * (w0 + w1)),
                    vertex(40.9, 61.4, 0.5 * (w0 + w1))};
      m.triangles = {{{0, 1, 2}, 0}, {{1, 0, 3}, 0}};
      RenderSettings s;
      s.width = 80;
      s.height = 72;
      s.aa = 2;  // sample rows on whole pixels: y = 36 is one
      s.hither = 0.01;
      CaptureSink sink(s.width);
      ASSERT_TRUE(RenderMesh(m, s, sink));
      // Pixels 35 and 36 both hold samples of row 36; away from the ends, all covered.
      for (int y : {35, 36})
        for (int x = 14; x < 66; ++x)
          EXPECT_FLOAT_EQ(sink.rgba[(static_cast<size_t>(y) * 80 + x) * 4 + 3], 1.0f)
              << "pixel (" << x << ", " << y << "), W " << w0 << " and " << w1;
      ++tried;
    }
  }
  EXPECT_EQ(tried, 20);
}

TEST(ScanlineRenderer, LinearTransparency) {
  // Two emissive squares at different depths with opacity 1/2: where both cover, the
  // front one gives 1/2 and the one behind 1/4 of its colour; alpha is 3/4.
  TriangleMesh m;
  auto square = [&](double x0, double y0, double depth, std::uint32_t id) {
    const auto base = static_cast<std::uint32_t>(m.vertices.size());
    for (auto [dx, dy] : {std::pair{0, 0}, {40, 0}, {40, 40}, {0, 40}})
      m.vertices.push_back({Vec3((x0 + dx) * depth, (y0 + dy) * depth, depth), Vec3(0, 0, depth),
                            Vec3(0, 0, -1), Vec2(0, 0)});
    m.triangles.push_back({{base, base + 1, base + 2}, id});
    m.triangles.push_back({{base, base + 2, base + 3}, id});
  };
  square(4.5, 4.5, 2.0, 0);    // behind
  square(24.5, 24.5, 1.0, 1);  // in front
  RenderSettings s;
  s.width = s.height = 72;
  s.aa = 1;
  s.hither = 0.01;
  s.opacity = 0.5;
  s.material.ka = s.material.kd = s.material.ks = 0;
  s.material.emission = Rgb(1, 1, 1);
  CaptureSink sink(s.width);
  ASSERT_TRUE(RenderMesh(m, s, sink));
  auto at = [&](int x, int y, int c) { return sink.rgba[(static_cast<size_t>(y) * 72 + x) * 4 + c]; };
  EXPECT_FLOAT_EQ(at(30, 30, 3), 0.75f);  // both
  EXPECT_FLOAT_EQ(at(30, 30, 0), 0.75f);
  EXPECT_FLOAT_EQ(at(10, 10, 3), 0.5f);   // the back one alone
  EXPECT_FLOAT_EQ(at(60, 60, 0), 0.5f);   // the front one alone
  EXPECT_FLOAT_EQ(at(70, 2, 3), 0.0f);    // nothing
}

// Hands a mesh's triangles to the back end as a direct render's source does with θ slabs:
// each triangle while the first sample row it reaches is scanned.
class StreamedMesh final : public FragmentSource {
 public:
  StreamedMesh(const TriangleMesh& m, double spacing, double offset) : m_(m) {
    for (std::uint32_t k = 0; k < m.triangles.size(); ++k) {
      double yMin = INFINITY;
      for (const std::uint32_t v : m.triangles[k].v) yMin = std::min(yMin, m.vertices[v].h.y() / m.vertices[v].h.z());
      order_.push_back({static_cast<long>(std::ceil((yMin - offset) / spacing)), k});
    }
    std::sort(order_.begin(), order_.end());
    spacing_ = spacing;
    offset_ = offset;
  }
  bool ScanRow(double y, const SampleColumns&, FragmentRow& out) override {
    const long j = std::lround((y - offset_) / spacing_);
    for (; next_ < order_.size() && order_[next_].first <= j; ++next_) {
      const RasterTriangle& t = m_.triangles[order_[next_].second];
      out.AddTriangle(m_.vertices[t.v[0]], m_.vertices[t.v[1]], m_.vertices[t.v[2]], t.surfaceId);
    }
    return true;
  }

 private:
  const TriangleMesh& m_;
  std::vector<std::pair<long, std::uint32_t>> order_;
  std::size_t next_ = 0;
  double spacing_ = 1, offset_ = 0.5;
};

// The frame of the pinhole above (Homogeneous), `aa` samples a side.
RenderSettings PinholeFrame(int aa) {
  RenderSettings s;
  s.width = 128;
  s.height = 96;
  s.aa = aa;
  s.hither = 0.01;
  return s;
}

TEST(ScanlineRenderer, TrianglesHandedOverByADirectSourceRenderAsAMesh) {
  // θ slabs reach the back end through the fragment path: the same triangles streamed
  // row by row cover exactly the samples the mesh path covers, and shade alike (a group
  // of samples is shaded at its centroid from one of its triangles: the first in the mesh
  // path, the nearest in the fragment path, so colours differ by the normal's change
  // across a triangle, a few 1e-3 on this coarse fan).
  constexpr double kColourTol = 0.02;
  TriangleMesh m;
  constexpr int kRing = 24;
  m.vertices.push_back({Homogeneous(Vec3(0, 0, 3)), Vec3(0, 0, 3), Vec3(0, 0, -1), Vec2(0.5, 0.5)});
  for (int k = 0; k < kRing; ++k) {
    const double a = 2 * M_PI * k / kRing;
    const Vec3 p(0.5 * std::cos(a), 0.4 * std::sin(a), 3 + 0.3 * std::sin(2 * a));
    m.vertices.push_back({Homogeneous(p), p, Vec3(std::cos(a), std::sin(a), -1.5), Vec2(0.5 + std::cos(a), 0.5)});
  }
  for (std::uint32_t k = 0; k < kRing; ++k) m.triangles.push_back({{0, 1 + k, 1 + (k + 1) % kRing}, 0});
  for (const int aa : {1, 4}) {
    const RenderSettings s = PinholeFrame(aa);
    CaptureSink mesh(s.width), streamed(s.width);
    ASSERT_TRUE(RenderMesh(m, s, mesh));
    const double spacing = aa == 1 ? 1.0 : 1.0 / (aa - 1);
    StreamedMesh source(m, spacing, aa == 1 ? 0.5 : 0.0);
    const auto stats = RenderFragments(source, s, streamed);
    ASSERT_TRUE(stats);
    EXPECT_EQ((*stats)[Counter::Triangles], kRing);
    ASSERT_EQ(mesh.rgba.size(), streamed.rgba.size());
    double worst = 0;
    for (std::size_t k = 0; k < mesh.rgba.size(); ++k) {
      if (k % 4 == 3) EXPECT_EQ(mesh.rgba[k], streamed.rgba[k]) << "alpha of pixel " << k / 4 << ", aa " << aa;
      else worst = std::max(worst, static_cast<double>(std::abs(mesh.rgba[k] - streamed.rgba[k])));
    }
    EXPECT_GT(mesh.Coverage(), 500.0);
    EXPECT_LT(worst, kColourTol) << "aa " << aa;
  }
}

// Two surfaces whose sections on every sample row are chains of chords, their depths
// crossing, the normal and depth slopes given at every other vertex: handed over as
// chords, or (`expand`) as one fragment per column made by the chord itself (what a back
// end that does not keep chords does).
class ChordSource final : public FragmentSource {
 public:
  explicit ChordSource(bool expand) : expand_(expand) {}
  bool ScanRow(double y, const SampleColumns& columns, FragmentRow& out) override {
    for (std::uint32_t id = 0; id < 2; ++id) {
      double xPrev = 0.0;
      Fragment fPrev;
      const double xs[] = {8.3, 21.0, 40.7, 41.2, 77.9, 110.5};
      const auto normal = [&](double x) { return Vec3(std::cos(0.05 * x + id), std::sin(0.05 * x), -1.5).normalized(); };
      Vec3 dn = Vec3::Constant(NAN);
      double dw = NAN;
      for (std::size_t k = 0; k < std::size(xs); ++k) {
        const double x = xs[k] + (id == 1 ? 6.0 * std::sin(0.1 * y) : 0.0);
        Fragment f;
        f.w = id == 0 ? 2.0 + 0.02 * x : 4.0 - 0.015 * x + 0.01 * y;
        f.position = Vec3((x - 64) * f.w / 100, (y - 48) * f.w / 100, f.w);
        f.normal = normal(x);
        f.uv = Vec2(x / 128, y / 96);
        f.duvdx = Vec2(1.0 / 128, 0.0);
        f.duvdy = Vec2(0.0, 1.0 / 96);
        f.surfaceId = id;
        const Vec3 dnb = k % 2 ? Vec3((normal(x + 1e-4) - normal(x - 1e-4)) / 2e-4) : Vec3::Constant(NAN);
        const double dwb = k % 2 ? (id == 0 ? 0.02 : -0.015) : NAN;
        // The first vertex's point chord, then each link.
        const Chord c = k == 0 ? Chord(x, f, false) : Chord(xPrev, fPrev, x, f, false, {dn, dw}, {dnb, dwb});
        dn = dnb;
        dw = dwb;
        xPrev = x;
        fPrev = f;
        if (expand_)
          c.ForEachColumn(columns, [&](int col) { out.Add(col, c.At(columns.At(col))); });
        else
          out.AddChord(c, columns);
      }
    }
    return true;
  }

 private:
  bool expand_;
};

// Every channel of every row.
struct AllChannels : RowSink {
  std::vector<float> values;
  int width;
  explicit AllChannels(int w) : width(w) {}
  bool WriteRow(int, const float* row) override {
    values.insert(values.end(), row, row + static_cast<std::ptrdiff_t>(width) * kChannels);
    return true;
  }
};

// Renders `source` with settings `s`: every channel of every pixel.
std::vector<float> RenderAll(FragmentSource& source, const RenderSettings& s) {
  AllChannels all(s.width);
  EXPECT_TRUE(RenderFragments(source, s, all));
  return all.values;
}

// How many values of a and b differ (bit for bit), of channel `channel` only if >= 0.
long Differ(const std::vector<float>& a, const std::vector<float>& b, int channel = -1) {
  EXPECT_EQ(a.size(), b.size());
  long n = 0;
  for (std::size_t k = 0; k < std::min(a.size(), b.size()); ++k)
    if (channel < 0 || static_cast<int>(k % kChannels) == channel) n += std::memcmp(&a[k], &b[k], sizeof(float)) != 0;
  return n;
}

TEST(ScanlineRenderer, ChordsKeptWholeShadeAsTheirFragments) {
  // The back end keeps a chord whole and makes a sample's fragment only when shading it:
  // at one sample a pixel, every channel of every pixel is the same as from the chord's
  // fragments added one by one, with the depth test alone deciding (two-sided) and with
  // culling (where the back end makes each sample to ask its side).
  for (const bool cull : {false, true}) {
    RenderSettings s = PinholeFrame(1);
    s.cullBackFaces = cull;
    ChordSource chords(false), fragments(true);
    const std::vector<float> kept = RenderAll(chords, s), made = RenderAll(fragments, s);
    long covered = 0;
    for (std::size_t k = 3; k < made.size(); k += kChannels) covered += made[k] > 0.0f;
    EXPECT_GT(covered, 5000);
    EXPECT_EQ(Differ(kept, made), 0) << (cull ? "culling" : "two-sided");
  }
}

TEST(ScanlineRenderer, ARunOfOneChordIsShadedAtItsMeanColumn) {
  // With several samples a pixel, a pixel's samples of one chord on one sample row are
  // shaded as one fragment, the chord at their mean column, weighted by their number
  // (not each made and averaged): the same coverage and surface ids as the fragments one
  // by one, and a shading fragment (the Z, N and uv channels) within kRunDifference of
  // their mean (the two differ at second order in the sample spacing; measured at aa 3,
  // the normal turning 0.05 rad a pixel: 1.1e-4 in N, 1.9e-5 in Z). Culling makes each
  // sample to ask its side and keeps the chord as well: where no fragment faces away (the
  // chords' fragments with and without culling agree), the same image bit for bit.
  constexpr double kRunDifference = 1e-3;
  RenderSettings s = PinholeFrame(3);
  ChordSource chords(false), fragments(true);
  const std::vector<float> kept = RenderAll(chords, s), made = RenderAll(fragments, s);
  EXPECT_EQ(Differ(kept, made, 3), 0) << "coverage";
  EXPECT_EQ(Differ(kept, made, kChannelId), 0) << "surface ids";
  double worst = 0.0;
  for (std::size_t k = 0; k < made.size(); ++k)
    if (std::isfinite(made[k]) || std::isfinite(kept[k]))
      worst = std::max(worst, static_cast<double>(std::abs(kept[k] - made[k])));
  EXPECT_LE(worst, kRunDifference);
  EXPECT_GT(Differ(kept, made, kChannelN), 0) << "the runs are not shaded at their mean columns";
  s.cullBackFaces = true;
  ASSERT_EQ(Differ(RenderAll(fragments, s), made), 0) << "a fragment faces away";
  EXPECT_EQ(Differ(RenderAll(chords, s), kept), 0) << "culling";
}

// Two surfaces' fragments on every sample of a band of rows, their attributes smooth in
// x and y and their depths crossing (surface 1 nearer left of x = 64): `Nearest` is the
// fragment the depth test keeps.
class CrossingFragments final : public FragmentSource {
 public:
  static Fragment Of(std::uint32_t id, double x, double y) {
    Fragment f;
    f.w = id == 0 ? 3.0 : 2.0 + x / 64.0;
    f.position = Vec3((x - 64) * f.w / 100, (y - 48) * f.w / 100, f.w);
    f.normal = Vec3(std::sin(0.03 * x + id), std::cos(0.04 * y), -1.2).normalized();
    f.uv = Vec2(x / 128 + 0.1 * id, y / 96);
    f.duvdx = Vec2(1.0 / 128, 0.0);
    f.duvdy = Vec2(0.0, 1.0 / 96);
    f.surfaceId = id;
    return f;
  }
  static bool Covers(double y) { return y > 20 && y < 70; }
  static Fragment Nearest(double x, double y) {
    const Fragment a = Of(0, x, y), b = Of(1, x, y);
    return b.w < a.w ? b : a;
  }
  bool ScanRow(double y, const SampleColumns& columns, FragmentRow& out) override {
    if (!Covers(y)) return true;
    for (std::uint32_t id = 0; id < 2; ++id)
      for (int c = 0; c < columns.n; ++c) out.Add(c, Of(id, columns.At(c), y));
    return true;
  }
};

TEST(ScanlineRenderer, OneSamplePixelsAreTheirFragmentShaded) {
  // At one sample a pixel and one layer a pixel is shaded without the grouping of its
  // samples: every channel must be that of the nearest fragment, computed here: colour
  // ShadeFragment's (lit), alpha 1, Z the eye distance, N the unit normal, uv, and the id.
  RenderSettings s = PinholeFrame(1);
  s.lights = DefaultLightRig(Vec3(0, 0, 1), Vec3(0, -1, 0), Vec3(1, 0, 0));
  CrossingFragments source;
  const std::vector<float> got = RenderAll(source, s);
  ASSERT_EQ(got.size(), static_cast<std::size_t>(s.width) * s.height * kChannels);
  long covered = 0, wrong = 0;
  for (int py = 0; py < s.height; ++py)
    for (int px = 0; px < s.width; ++px) {
      const float* p = &got[(static_cast<std::size_t>(py) * s.width + px) * kChannels];
      const double x = px + 0.5, y = py + 0.5;
      if (!CrossingFragments::Covers(y)) {
        wrong += p[3] != 0.0f;
        continue;
      }
      ++covered;
      const Fragment f = CrossingFragments::Nearest(x, y);
      std::atomic<bool> failed = false;
      const Rgb rgb = ShadeFragment(f, s, &failed);
      const Vec3 n = f.normal.normalized();
      const float want[kChannels] = {static_cast<float>(rgb[0]), static_cast<float>(rgb[1]),
                                     static_cast<float>(rgb[2]), 1.0f, static_cast<float>(f.w),
                                     static_cast<float>(n.x()), static_cast<float>(n.y()),
                                     static_cast<float>(n.z()), static_cast<float>(f.uv.x()),
                                     static_cast<float>(f.uv.y()), static_cast<float>(f.surfaceId)};
      wrong += std::memcmp(p, want, sizeof(want)) != 0;
    }
  EXPECT_GT(covered, 5000);
  EXPECT_EQ(wrong, 0);
}

TEST(ScanlineRenderer, WithoutAovsColourAndAlphaAreTheSame) {
  // An output that keeps no AOV channels (PNG, TIFF, JPEG, EXR without --aov) is rendered
  // without them: colour and alpha the same bit for bit at one sample a pixel and at
  // several, and every AOV channel the background's.
  for (const int aa : {1, 3}) {
    RenderSettings s = PinholeFrame(aa);
    s.lights = DefaultLightRig(Vec3(0, 0, 1), Vec3(0, -1, 0), Vec3(1, 0, 0));
    CrossingFragments source;
    const std::vector<float> with = RenderAll(source, s);
    s.aovs = false;
    const std::vector<float> without = RenderAll(source, s);
    long covered = 0, notBackground = 0;
    for (std::size_t k = 3; k < with.size(); k += kChannels) covered += with[k] > 0.0f;
    for (std::size_t k = 0; k < without.size(); k += kChannels)
      notBackground += without[k + kChannelZ] != INFINITY || without[k + kChannelN] != 0.0f ||
                       without[k + kChannelN + 1] != 0.0f || without[k + kChannelN + 2] != 0.0f ||
                       without[k + kChannelUv] != 0.0f || without[k + kChannelUv + 1] != 0.0f ||
                       without[k + kChannelId] != -1.0f;
    EXPECT_GT(covered, 5000) << "aa " << aa;
    for (int c = 0; c < 4; ++c) EXPECT_EQ(Differ(with, without, c), 0) << "aa " << aa << " channel " << c;
    EXPECT_EQ(notBackground, 0) << "aa " << aa;
  }
}

// A circular section seen by a pinhole at the origin looking along +z (focal f pixels):
// the circle x² + (z - 5)² = 1 in the plane y = 0, its near side, at angle φ from the
// view axis; its point, outward unit normal, screen x and their derivatives in φ.
struct CircleSection {
  static constexpr double kF = 100.0, kZ = 5.0;
  static Vec3 Point(double phi) { return Vec3(std::sin(phi), 0.0, kZ - std::cos(phi)); }
  static Vec3 Normal(double phi) { return Vec3(std::sin(phi), 0.0, -std::cos(phi)); }
  static double X(double phi) { return kF * Point(phi).x() / Point(phi).z(); }
  static double DxDphi(double phi) {
    const Vec3 p = Point(phi);
    return kF * (std::cos(phi) * p.z() - p.x() * std::sin(phi)) / (p.z() * p.z());
  }
  // φ at screen x by bisection (x rises with φ on the near side for |φ| < 1.3).
  static double PhiAt(double x, double lo, double hi) {
    for (int k = 0; k < 200; ++k) {
      const double mid = 0.5 * (lo + hi);
      (X(mid) < x ? lo : hi) = mid;
    }
    return 0.5 * (lo + hi);
  }
  // The chord from φa to φb, with its ends' slopes per pixel or without.
  static Chord Of(double pa, double pb, bool slopes) {
    Fragment a, b;
    for (auto [end, phi] : {std::pair{&a, pa}, {&b, pb}}) {
      end->w = Point(phi).z();
      end->position = Point(phi);
      end->normal = Normal(phi);
    }
    if (!slopes) return Chord(X(pa), a, X(pb), b, false);
    // dN/dφ = (cos φ, 0, sin φ) = dP/dφ; dw/dφ = sin φ.
    const auto slope = [](double phi) {
      return Chord::Slope{Vec3(Vec3(std::cos(phi), 0.0, std::sin(phi)) / DxDphi(phi)), std::sin(phi) / DxDphi(phi)};
    };
    return Chord(X(pa), a, X(pb), b, false, slope(pa), slope(pb));
  }
  // The largest normal angle (radians) and eye-distance error over 101 points of the chord.
  static std::pair<double, double> Errors(const Chord& c, double pa, double pb) {
    double angle = 0.0, depth = 0.0;
    for (int k = 0; k <= 100; ++k) {
      const double x = c.xa() + (c.xb() - c.xa()) * k / 100.0, phi = PhiAt(x, pa, pb);
      const Fragment f = c.At(x);
      angle = std::max(angle, std::acos(std::clamp(f.normal.dot(Normal(phi)), -1.0, 1.0)));
      depth = std::max(depth, std::abs(f.w - Point(phi).z()));
      EXPECT_EQ(f.w, c.DepthAt(x));  // one rule for the depth test and the fragment
    }
    return {angle, depth};
  }
};

TEST(Chord, SlopesMakeTheSectionFourthOrder) {
  // Blended, the normal's and the depth's errors fall as the square of the chord's turn;
  // with the ends' slopes (cubics), as its fourth power: halving the turn divides them by
  // about 4 and 16. Turns of 2π/16 and 2π/32 on a unit circle 5 away, 100 px focal.
  constexpr double kSecondOrderMin = 3.0, kSecondOrderMax = 5.0;  // around 4
  // Towards 16 as the turn shrinks: 10-11 measured from 2π/16 to 2π/32, 14 from 2π/64 to
  // 2π/128 (the blend's 3.2-3.7 and 3.8).
  constexpr double kFourthOrderMin = 8.0;
  constexpr double kGainAt16Min = 10.0;  // slopes cut the error at N = 16 at least this much
  const double start = -0.6;
  double blend[2][2], cubic[2][2];
  for (int k = 0; k < 2; ++k) {
    const double turn = 2.0 * M_PI / (k == 0 ? 16 : 32);
    const auto [ba, bd] = CircleSection::Errors(CircleSection::Of(start, start + turn, false), start, start + turn);
    const auto [ca, cd] = CircleSection::Errors(CircleSection::Of(start, start + turn, true), start, start + turn);
    blend[k][0] = ba, blend[k][1] = bd, cubic[k][0] = ca, cubic[k][1] = cd;
  }
  std::cout << "chord error, normal (rad) and depth, blend: N=16 " << blend[0][0] << ", " << blend[0][1] << "; N=32 "
            << blend[1][0] << ", " << blend[1][1] << "; cubic: N=16 " << cubic[0][0] << ", " << cubic[0][1] << "; N=32 "
            << cubic[1][0] << ", " << cubic[1][1] << '\n';
  for (int m = 0; m < 2; ++m) {
    SCOPED_TRACE(m == 0 ? "normal" : "depth");
    EXPECT_GT(blend[0][m] / blend[1][m], kSecondOrderMin);
    EXPECT_LT(blend[0][m] / blend[1][m], kSecondOrderMax);
    EXPECT_GT(cubic[0][m] / cubic[1][m], kFourthOrderMin);
    EXPECT_GT(blend[0][m] / cubic[0][m], kGainAt16Min);
  }
}

// A section from a dome's flat crown outwards, seen from above by the pinhole of
// CircleSection: the curve z = kZ + kA s⁶ in the plane y = 0, s from 0 to kS. Its
// curvature grows as s⁴, so across the chord the normal turns slowly at the crown and fast
// at the far end, with no silhouette near (the far end faces the eye within 0.4 rad).
struct DomeSection {
  static constexpr double kF = CircleSection::kF, kZ = CircleSection::kZ, kA = 2.24, kS = 0.5;
  static double Z(double s) { return kZ + kA * std::pow(s, 6); }
  static double Dz(double s) { return 6.0 * kA * std::pow(s, 5); }
  static double Dz2(double s) { return 30.0 * kA * std::pow(s, 4); }
  static Vec3 Point(double s) { return Vec3(s, 0.0, Z(s)); }
  static Vec3 Normal(double s) { return Vec3(Dz(s), 0.0, -1.0).normalized(); }  // towards the eye
  static double X(double s) { return kF * s / Z(s); }
  static double DxDs(double s) { return kF * (Z(s) - s * Dz(s)) / (Z(s) * Z(s)); }
  static Chord::Slope SlopeAt(double s) {
    const Vec3 v(Dz(s), 0.0, -1.0), dv(Dz2(s), 0.0, 0.0), n = v.normalized();
    const Vec3 dn = (dv - n * n.dot(dv)) / v.norm();
    return {Vec3(dn / DxDs(s)), Dz(s) / DxDs(s)};
  }
  static Fragment At(double s) {
    Fragment f;
    f.w = Z(s), f.position = Point(s), f.normal = Normal(s);
    return f;
  }
  // The largest normal angle (radians) and eye-distance error over 101 points of a chord
  // from s = 0 to kS.
  static std::pair<double, double> Errors(const Chord& c) {
    double angle = 0.0, depth = 0.0;
    for (int k = 0; k <= 100; ++k) {
      const double x = c.xa() + (c.xb() - c.xa()) * k / 100.0;
      double lo = 0.0, hi = kS;  // x rises with s
      for (int i = 0; i < 200; ++i) (X(0.5 * (lo + hi)) < x ? lo : hi) = 0.5 * (lo + hi);
      const double s = 0.5 * (lo + hi);
      const Fragment f = c.At(x);
      angle = std::max(angle, std::acos(std::clamp(f.normal.dot(Normal(s)), -1.0, 1.0)));
      depth = std::max(depth, std::abs(f.w - Z(s)));
    }
    return {angle, depth};
  }
};

TEST(Chord, ANormalTurningFasterAtOneEndKeepsItsSlope) {
  // The far end's tangent (the chord's span times its normal's turn per pixel) is about
  // five times the turn across the chord: the normal's slope is kept up to
  // kNormalTurnRatio times the turn (the depth's up to kSlopeTurnRatio), and the normal
  // is a cubic, well under the error of the quadratic the crown's slope alone gives, and
  // of the blend. Measured: normal error 0.033 rad, the quadratic's 0.128, the blend's 0.21.
  constexpr double kGainOverQuadraticMin = 2.0;
  const double span = DomeSection::X(DomeSection::kS) - DomeSection::X(0.0);
  const Chord::Slope crown = DomeSection::SlopeAt(0.0), far = DomeSection::SlopeAt(DomeSection::kS);
  const double turn = (DomeSection::Normal(DomeSection::kS) - DomeSection::Normal(0.0)).norm();
  const double ratio = span * far.normal.norm() / turn;
  ASSERT_GT(ratio, Chord::kSlopeTurnRatio);
  ASSERT_LT(ratio, Chord::kNormalTurnRatio);
  const Fragment a = DomeSection::At(0.0), b = DomeSection::At(DomeSection::kS);
  const double xa = DomeSection::X(0.0), xb = DomeSection::X(DomeSection::kS);
  const Chord cubic(xa, a, xb, b, false, crown, far), quadratic(xa, a, xb, b, false, crown, {}),
      blend(xa, a, xb, b, false);
  const auto [ca, cd] = DomeSection::Errors(cubic);
  const auto [qa, qd] = DomeSection::Errors(quadratic);
  const auto [ba, bd] = DomeSection::Errors(blend);
  std::cout << "dome chord, far tangent " << ratio << " times the turn " << turn << ": normal error cubic " << ca
            << ", crown's quadratic " << qa << ", blend " << ba << " rad; depth " << cd << ", " << qd << ", " << bd
            << '\n';
  EXPECT_LT(ca * kGainOverQuadraticMin, qa);
  EXPECT_LT(ca * kGainOverQuadraticMin, ba);
  EXPECT_LE(cd, qd);  // the depth: the same quadratic (its far tangent is left out)
}

TEST(Chord, ADepthSlopeFarSteeperThanTheChordIsLeftOut) {
  // A link of the teapot's body, θ16 at 1024x768 (row 573.5, surface 8): from a table
  // vertex to a turn point all but on a silhouette (θ 0.007 rad from it, standing still
  // there), whose eye distance changes by 1.29 per pixel where the chord's changes by 0.08:
  // its normal's slope fits the chord, its depth's is 16 times the change across it. Kept,
  // the cubic in 1/w put the chord's middle 0.25 behind both ends (the column at 573.5 at
  // w 13.652, exact 13.396), and the bottom, 13.617 away, showed through the body. Left out,
  // the chord stays between its ends' depths, nearer the surface than the ends' blend.
  Fragment a, b;
  a.w = 13.426562669558088, b.w = 13.294929942047412;
  a.position = Vec3(1.2739970387071056, -0.82143667586133784, 0.17270547179050888);
  b.position = Vec3(1.299852470773261, -0.9302715856976298, 0.24727841952688678);
  a.normal = Vec3(0.66534615026798949, -0.4246262919265778, -0.61400896779139202);
  b.normal = Vec3(0.5152298889256135, -0.365903293727457, -0.77501802636912809);
  const double xa = 574.474906, xb = 572.820767;
  const Chord::Slope sa{Vec3(0.081945934571399662, -0.040548592621047423, 0.11683935314945386), 0.021980748049581996};
  const Chord::Slope sb{Vec3(0.21790398752203316, 0.13976846211402669, 0.078874173968653261), 1.2858660819660497};
  const Chord c(xa, a, xb, b, false, sa, sb), blend(xa, a, xb, b, false);
  constexpr double kExactAtMiddle = 13.396255;  // the exact scan's eye distance at x = 573.5
  for (int k = 0; k <= 20; ++k) {
    const double x = xa + (xb - xa) * k / 20.0;
    EXPECT_GE(c.At(x).w, b.w) << x;
    EXPECT_LE(c.At(x).w, a.w) << x;
  }
  EXPECT_LT(std::abs(c.At(573.5).w - kExactAtMiddle), std::abs(blend.At(573.5).w - kExactAtMiddle));
}

TEST(Chord, SlopeAtASilhouetteIsLeftOut) {
  // Towards the silhouette (φ → atan(1/√24) here, where the ray grazes the circle) x stops
  // and the slopes per pixel grow without bound: an end's slope that would turn the normal
  // by more than twice the chord's own turn is left out, and the chord is no worse than
  // the blend, and finite, whichever end's slope is huge or infinite.
  const double graze = M_PI / 2.0 - std::atan(1.0 / std::sqrt(CircleSection::kZ * CircleSection::kZ - 1.0));
  for (const double gap : {1e-3, 1e-9}) {
    const double pb = graze - gap, pa = pb - 2.0 * M_PI / 16;
    const auto [ba, bd] = CircleSection::Errors(CircleSection::Of(pa, pb, false), pa, pb);
    const auto [ca, cd] = CircleSection::Errors(CircleSection::Of(pa, pb, true), pa, pb);
    EXPECT_TRUE(std::isfinite(ca) && std::isfinite(cd)) << gap;
    EXPECT_LE(ca, ba) << gap;
    EXPECT_LE(cd, bd) << gap;
  }
  const Chord blend = CircleSection::Of(0.1, 0.3, false);
  const Chord c(blend.xa(), blend.a(), blend.xb(), blend.b(), false, {Vec3::Constant(INFINITY), INFINITY}, {});
  for (int k = 0; k <= 10; ++k) {
    const double x = c.xa() + (c.xb() - c.xa()) * k / 10.0;
    EXPECT_EQ(c.At(x).normal, blend.At(x).normal);
    EXPECT_EQ(c.DepthAt(x), blend.DepthAt(x));
  }
}

// A chord to a silhouette, its depth and normal as quadratics in the root of x, against the
// quadratic in x: at most this fraction of the error (1/12 to 1/84 measured at turns of 2π/8
// and 2π/16), and falling at least as the square of the turn (7.2 and 9.0 measured per
// halving; the quadratic in x, 2.0: first order).
constexpr double kRootGainMin = 0.2, kRootOrderMin = 4.0;
TEST(Chord, FromASilhouetteTheAttributesGoAsTheRootOfX) {
  // At the silhouette (the ray grazing the circle) x stands still: the depth and the normal
  // go as the square root of the distance in x from it, and no slope there fits a cubic in
  // x. A chord with that end marked takes them as quadratics in the root, with the other
  // end's slopes: second order in the root, where the quadratic in x with the other end's
  // slope alone is off by a fixed fraction of what changes across the chord.
  const double graze = M_PI / 2.0 - std::atan(1.0 / std::sqrt(CircleSection::kZ * CircleSection::kZ - 1.0));
  const auto end = [](double phi) {
    Fragment f;
    f.w = CircleSection::Point(phi).z();
    f.position = CircleSection::Point(phi);
    f.normal = CircleSection::Normal(phi);
    return f;
  };
  const auto slope = [](double phi) {
    const double dx = CircleSection::DxDphi(phi);
    return Chord::Slope{Vec3(Vec3(std::cos(phi), 0.0, std::sin(phi)) / dx), std::sin(phi) / dx};
  };
  const Chord::Slope onSilhouette{Vec3::Constant(NAN), NAN, 0.0};
  double root[2][2];
  for (int k = 0; k < 2; ++k) {
    const double pa = graze - 2.0 * M_PI / (k == 0 ? 8 : 16), pb = graze;
    const Fragment a = end(pa), b = end(pb);
    const Chord quadratic(CircleSection::X(pa), a, CircleSection::X(pb), b, false, slope(pa), {});
    const Chord fromB(CircleSection::X(pa), a, CircleSection::X(pb), b, false, slope(pa), onSilhouette);
    const Chord fromA(CircleSection::X(pb), b, CircleSection::X(pa), a, false, onSilhouette, slope(pa));
    const auto [qa, qd] = CircleSection::Errors(quadratic, pa, pb);
    const auto [ra, rd] = CircleSection::Errors(fromB, pa, pb);
    const auto [sa, sd] = CircleSection::Errors(fromA, pa, pb);
    std::cout << "chord to a silhouette, turn 2pi/" << (k == 0 ? 8 : 16) << ": normal (rad) and depth error, quadratic in x "
              << qa << ", " << qd << "; in the root " << ra << ", " << rd << " (reversed " << sa << ", " << sd << ")\n";
    EXPECT_NEAR(ra, sa, 1e-12);  // the same curve whichever end comes first
    EXPECT_NEAR(rd, sd, 1e-12);
    EXPECT_LT(ra, kRootGainMin * qa) << k;
    EXPECT_LT(rd, kRootGainMin * qd) << k;
    root[k][0] = ra, root[k][1] = rd;
  }
  // Halving the turn divides the root's errors by about 4 or more.
  EXPECT_GT(root[0][0] / root[1][0], kRootOrderMin);
  EXPECT_GT(root[0][1] / root[1][1], kRootOrderMin);
}

// A chord whose end lies a gap short of a silhouette, its attributes as cubics in the root
// of the distance from the silhouette (told the gap), against the cubic or quadratic in x
// from the same slopes: at most this fraction of the error (measured: 0.004-0.008 for gaps
// of 1e-4 to 0.1 rad at a turn of 2π/8), and the same curve whichever end comes first.
constexpr double kNearRootGainMax = 0.05;
TEST(Chord, NearASilhouetteTheAttributesGoAsTheRootOfTheDistanceFromIt) {
  // Short of the silhouette the slope there is finite but huge (it grows as the inverse
  // root of the gap): no tangent for a cubic in x, which then falls back to the quadratic
  // with the far end's tangent. Told where the silhouette lies, the chord takes both
  // tangents in the root of the distance from it, exact for the parabola the section is
  // near a silhouette.
  const double graze = M_PI / 2.0 - std::atan(1.0 / std::sqrt(CircleSection::kZ * CircleSection::kZ - 1.0));
  const double xs = CircleSection::X(graze);
  for (const double gapAngle : {1e-4, 1e-2, 0.1}) {
    const double pb = graze - gapAngle, pa = pb - 2.0 * M_PI / 8;
    const Chord inX = CircleSection::Of(pa, pb, true);
    Chord::Slope sa, sb;
    for (auto [slope, phi] : {std::pair{&sa, pa}, {&sb, pb}}) {
      const double dx = CircleSection::DxDphi(phi);
      *slope = Chord::Slope{Vec3(Vec3(std::cos(phi), 0.0, std::sin(phi)) / dx), std::sin(phi) / dx};
    }
    Chord::Slope nearB = sb;
    nearB.silhouette = xs - CircleSection::X(pb);  // > 0: past b, away from a
    ASSERT_GT(nearB.silhouette, 0.0);
    const Chord inRoot(inX.xa(), inX.a(), inX.xb(), inX.b(), false, sa, nearB);
    const Chord reversed(inX.xb(), inX.b(), inX.xa(), inX.a(), false, nearB, sa);
    ASSERT_NE(inRoot.cubics(), nullptr);
    const auto [xa, xd] = CircleSection::Errors(inX, pa, pb);
    const auto [ra, rd] = CircleSection::Errors(inRoot, pa, pb);
    const auto [va, vd] = CircleSection::Errors(reversed, pa, pb);
    std::cout << "chord " << gapAngle << " rad short of a silhouette: normal (rad) and depth error, in x " << xa << ", "
              << xd << "; in the root " << ra << ", " << rd << '\n';
    EXPECT_LT(ra, kNearRootGainMax * xa) << gapAngle;
    EXPECT_LT(rd, kNearRootGainMax * xd) << gapAngle;
    EXPECT_NEAR(ra, va, 1e-12) << gapAngle;
    EXPECT_NEAR(rd, vd, 1e-12) << gapAngle;
  }
}

// The circle section's ends with texture coordinate u = φ, and their change per pixel
// along the row: the surface's own (dφ/dx), or a footprint clamped to 1 texture unit a
// pixel, as the front end's is at a silhouette (no slope).
Fragment TexturedEnd(double phi, bool slope) {
  Fragment f;
  f.w = CircleSection::Point(phi).z();
  f.position = CircleSection::Point(phi);
  f.normal = CircleSection::Normal(phi);
  f.uv = Vec2(phi, 0.0);
  f.duvdx = slope ? Vec2(1.0 / CircleSection::DxDphi(phi), 0.0) : Vec2(1.0, 0.0);
  f.duvdy = f.duvdx;
  return f;
}
// The largest error of u against φ over 101 points of a chord of the section.
double TextureError(const Chord& c, double pa, double pb) {
  double e = 0.0;
  for (int k = 0; k <= 100; ++k) {
    const double x = c.xa() + (c.xb() - c.xa()) * k / 100.0;
    e = std::max(e, std::abs(c.At(x).uv.x() - CircleSection::PhiAt(x, std::min(pa, pb), std::max(pa, pb))));
  }
  return e;
}

TEST(Chord, TextureCoordinatesFollowTheEndsSlopes) {
  // u = φ is not linear along the row (nor is 1/w's blend of it): blended, its error falls
  // as the square of the chord's turn; with the ends' own change per pixel (a Hermite
  // cubic in x), as the fourth power. Turns of 2π/16 and 2π/32 as in
  // SlopesMakeTheSectionFourthOrder; measured ratios per halving 3.1 (blend) and 10.7
  // (cubic, towards 16 as the turn shrinks, as the normal's), and the cubic 11.6 times
  // better at 2π/16.
  constexpr double kSecondOrderMin = 2.5, kSecondOrderMax = 5.0, kFourthOrderMin = 8.0, kGainAt16Min = 8.0;
  const double start = -0.6;
  double blend[2], cubic[2];
  for (int k = 0; k < 2; ++k) {
    const double pa = start, pb = start + 2.0 * M_PI / (k == 0 ? 16 : 32);
    for (const bool slopes : {false, true}) {
      const Chord c(CircleSection::X(pa), TexturedEnd(pa, slopes), CircleSection::X(pb), TexturedEnd(pb, slopes), false);
      (slopes ? cubic : blend)[k] = TextureError(c, pa, pb);
    }
  }
  std::cout << "chord texture error, blend: N=16 " << blend[0] << ", N=32 " << blend[1] << "; cubic: N=16 " << cubic[0]
            << ", N=32 " << cubic[1] << '\n';
  EXPECT_GT(blend[0] / blend[1], kSecondOrderMin);
  EXPECT_LT(blend[0] / blend[1], kSecondOrderMax);
  EXPECT_GT(cubic[0] / cubic[1], kFourthOrderMin);
  EXPECT_GT(blend[0] / cubic[0], kGainAt16Min);
}

TEST(Chord, NearASilhouetteTheTextureGoesAsTheRootAndItsFootprintGrows) {
  // A chord to a silhouette takes u as its root parameter, as the normal and the depth:
  // measured a thirty-second of the blend's error (the blend places the texture by the square of
  // the distance from the silhouette). Its footprint grows towards the silhouette as the
  // surface's (1/√ of the distance), from the far end's to at most the silhouette's own
  // clamped one: before, half the chord took the silhouette's and blurred the texture to
  // its mean.
  constexpr double kRootGainMax = 0.1;
  const double graze = M_PI / 2.0 - std::atan(1.0 / std::sqrt(CircleSection::kZ * CircleSection::kZ - 1.0));
  const double pa = graze - 2.0 * M_PI / 8, pb = graze;
  const Fragment a = TexturedEnd(pa, true), b = TexturedEnd(pb, false);
  const double dx = CircleSection::DxDphi(pa);
  const Chord::Slope slope{Vec3(Vec3(std::cos(pa), 0.0, std::sin(pa)) / dx), std::sin(pa) / dx};
  const Chord root(CircleSection::X(pa), a, CircleSection::X(pb), b, false, slope, {Vec3::Constant(NAN), NAN, 0.0});
  const Chord plain(CircleSection::X(pa), a, CircleSection::X(pb), b, false, slope, {});
  ASSERT_NE(root.cubics(), nullptr);
  const double eRoot = TextureError(root, pa, pb), ePlain = TextureError(plain, pa, pb);
  std::cout << "chord to a silhouette, texture error: in the root " << eRoot << ", blended " << ePlain << '\n';
  EXPECT_LT(eRoot, kRootGainMax * ePlain);
  double last = 0.0;
  for (int k = 0; k <= 100; ++k) {
    const double x = root.xa() + (root.xb() - root.xa()) * k / 100.0;
    const double footprint = root.At(x).duvdx.norm();
    if (k == 0) {
      EXPECT_NEAR(footprint, a.duvdx.norm(), 1e-12);
    }
    EXPECT_GE(footprint, last) << k;
    EXPECT_LE(footprint, b.duvdx.norm()) << k;
    last = footprint;
  }
}

// Keeps rows as they come, refusing from row `refuseAt` on.
class OrderedRows final : public RowSink {
 public:
  OrderedRows(int width, int refuseAt) : width_(width), refuseAt_(refuseAt) {}
  bool WriteRow(int y, const float* pixels) override {
    if (y >= refuseAt_) return false;
    ys.push_back(y);
    firsts.push_back(pixels[0]);
    lasts.push_back(pixels[static_cast<std::size_t>(width_) * kChannels - 1]);
    return true;
  }
  std::vector<int> ys;
  std::vector<float> firsts, lasts;

 private:
  int width_, refuseAt_;
};

TEST(AsyncRowSink, WritesEveryRowInOrderOnItsThread) {
  // More rows than the ring holds, each row's first and last value its own: the next sink
  // sees every row once, in order, with the values it was given (the ring's slots reused).
  constexpr int kWidth = 7, kRows = 5 * AsyncRowSink::kRowsQueued + 3;
  OrderedRows next(kWidth, kRows);
  {
    AsyncRowSink async(next, kWidth);
    std::vector<float> row(static_cast<std::size_t>(kWidth) * kChannels);
    for (int y = 0; y < kRows; ++y) {
      row.front() = static_cast<float>(y);
      row.back() = static_cast<float>(-y);
      ASSERT_TRUE(async.WriteRow(y, row.data()));
    }
    EXPECT_TRUE(async.Finish());
  }
  ASSERT_EQ(next.ys.size(), static_cast<std::size_t>(kRows));
  for (int y = 0; y < kRows; ++y) {
    EXPECT_EQ(next.ys[y], y);
    EXPECT_EQ(next.firsts[y], static_cast<float>(y));
    EXPECT_EQ(next.lasts[y], static_cast<float>(-y));
  }
}

TEST(AsyncRowSink, ARefusedRowStopsTheRender) {
  // The next sink refuses row 10 (a full disk): a later WriteRow or Finish says so, and
  // nothing after it reaches the next sink.
  constexpr int kWidth = 3;
  OrderedRows next(kWidth, 10);
  AsyncRowSink async(next, kWidth);
  std::vector<float> row(static_cast<std::size_t>(kWidth) * kChannels, 0.0f);
  bool refused = false;
  for (int y = 0; y < 10 * AsyncRowSink::kRowsQueued && !refused; ++y) refused = !async.WriteRow(y, row.data());
  EXPECT_TRUE(refused || !async.Finish());
  EXPECT_FALSE(async.Finish());
  EXPECT_EQ(next.ys.size(), 10u);
}

TEST(Shading, FastRenormalizationIsSecondOrder) {
  // |Renormalize(v)| - 1 = -(3/8) e^2 + O(e^3) for |v|^2 = 1 + e.
  for (double e : {-0.02, -0.005, 0.001, 0.01, 0.02}) {
    const Vec3 v = Vec3(0.3, -0.5, 0.8).normalized() * std::sqrt(1 + e);
    EXPECT_NEAR(Renormalize(v).norm(), 1.0, 0.375 * e * e * 1.1 + 1e-15) << "e " << e;
  }
}

TEST(Shading, IlluminationModelTerms) {
  // One point light straight above a surface facing up, eye above too: diffuse kd * (N.L)
  // attenuated by 1 / (1 + k d^2), plus full specular (R = V) and ambient.
  Material m;
  m.colour = Rgb(0.5, 0.25, 1.0);
  m.ka = 0.1;
  m.kd = 0.6;
  m.ks = 0.3;
  LightRig rig;
  rig.ambient = Rgb(1, 1, 1);
  rig.lights.push_back(Light::Of(Light::Kind::Point, Vec3(0, 0, 2), Rgb(1, 1, 1), 0.25));
  const Rgb c = Shade(Vec3::Zero(), Vec3(0, 0, 3), m.colour, Vec3(0, 0, 10), m, rig);
  const double fall = 1.0 / (1.0 + 0.25 * 4.0);
  for (int k = 0; k < 3; ++k)
    EXPECT_NEAR(c[k], 0.1 * m.colour[k] + fall * (0.6 * m.colour[k] + 0.3), 1e-12) << k;
  // A directional light from below does not light the top; the normal facing away from
  // the eye is turned towards it (two-sided), so the result is the same for -n.
  rig.lights = {Light::Of(Light::Kind::Directional, Vec3(0, 0, 1), Rgb(1, 1, 1))};
  const Rgb below = Shade(Vec3::Zero(), Vec3(0, 0, -1), m.colour, Vec3(0, 0, 10), m, rig);
  EXPECT_LE((below - 0.1 * m.colour).norm(), 1e-12);
}

// RenderMan's standard shaders (RenderMan Interface 3.2, appendix A) at a point lit by one
// inverse-square point light off to the side and an ambient light: each term by hand.
TEST(Shading, RenderManShadersTermByTerm) {
  const Vec3 p = Vec3::Zero(), n(0, 0, 1), eye(0, 0, 10), lightAt(3, 0, 4);  // distance 5
  LightRig rig;
  rig.ambient = Rgb(0.2, 0.2, 0.2);
  Light point;
  point.kind = Light::Kind::Point;
  point.vector = lightAt;
  point.intensity = Rgb(50, 25, 50);
  point.inverseSquare = true;
  rig.lights.push_back(point);
  const Rgb cl = point.intensity / 25.0;        // Cl = intensity / d^2
  const double ndotl = 4.0 / 5.0;               // N . L
  const Vec3 h = (lightAt.normalized() + Vec3(0, 0, 1)).normalized();
  const Rgb cs(0.5, 0.25, 1.0);
  Material m;
  m.ka = 0.7;
  m.kd = 0.6;
  m.ks = 0.4;
  m.roughness = 0.2;
  m.specularColour = Rgb(1, 0.5, 0);
  const double spec = std::pow(h.z(), 1.0 / m.roughness);  // N . H to the 1/roughness
  const Rgb ambient = m.ka * rig.ambient;
  struct Case {
    Material::Model model;
    Rgb want;
  } cases[] = {
      {Material::Model::Constant, cs},
      {Material::Model::Matte, cs.cwiseProduct(ambient + m.kd * ndotl * cl)},
      {Material::Model::Plastic, cs.cwiseProduct(ambient + m.kd * ndotl * cl) + m.ks * spec * m.specularColour.cwiseProduct(cl)},
      {Material::Model::Metal, cs.cwiseProduct(ambient + m.ks * spec * cl)},
  };
  for (const Case& c : cases) {
    m.model = c.model;
    const Rgb got = Shade(p, n, cs, eye, m, rig);
    EXPECT_LT((got - c.want).norm(), 1e-12) << static_cast<int>(c.model) << ": " << got.transpose() << " vs " << c.want.transpose();
  }
}

// RenderMan's spotlight: full inside the cone less its soft edge, smoothstep across the
// edge, nothing outside; cos^beamdistribution of the angle off the axis; 1 / d^2.
TEST(Shading, SpotLightCone) {
  LightRig rig;
  rig.ambient = Rgb::Zero();
  Light spot;
  spot.kind = Light::Kind::Spot;
  spot.vector = Vec3(0, 0, 10);
  spot.axis = Vec3(0, 0, -1);
  spot.inverseSquare = true;
  spot.intensity = Rgb(100, 100, 100);
  const double cone = 0.3, delta = 0.1;
  spot.cosOutside = std::cos(cone);
  spot.cosInside = std::cos(cone - delta);
  spot.beamDistribution = 2.0;
  rig.lights.push_back(spot);
  Material m;
  m.model = Material::Model::Matte;
  m.ka = 0;
  m.kd = 1;
  const Rgb white(1, 1, 1);
  auto lit = [&](double angle) {  // a surface point at `angle` off the axis, facing the light
    const Vec3 p = spot.vector + 10.0 / std::cos(angle) * Vec3(std::sin(angle), 0, -std::cos(angle));
    return Shade(p, spot.vector - p, white, Vec3(0, 0, 20), m, rig).x();
  };
  for (double angle : {0.0, 0.1, 0.19}) {
    const double d2 = std::pow(10.0 / std::cos(angle), 2);
    EXPECT_NEAR(lit(angle), 100.0 / d2 * std::pow(std::cos(angle), 2), 1e-12) << angle;
  }
  const double mid = cone - delta / 2;  // halfway across the edge in angle
  const double t = (std::cos(mid) - spot.cosOutside) / (spot.cosInside - spot.cosOutside);
  EXPECT_NEAR(lit(mid), 100.0 / std::pow(10.0 / std::cos(mid), 2) * std::pow(std::cos(mid), 2) * t * t * (3 - 2 * t), 1e-12);
  EXPECT_EQ(lit(cone + 0.01), 0.0);
}

// Per-surface materials: each surface's own opacity in the layers (a front square of
// opacity 1/4 over a back one of 1: 1/4 + 3/4 of their colours), and a one-sided surface
// drawn only from its front.
TEST(ScanlineRenderer, PerSurfaceOpacityAndSides) {
  TriangleMesh m;
  auto square = [&](double x0, double depth, std::uint32_t id, const Vec3& normal) {
    const auto base = static_cast<std::uint32_t>(m.vertices.size());
    for (auto [dx, dy] : {std::pair{0, 0}, {20, 0}, {20, 20}, {0, 20}})
      m.vertices.push_back({Vec3((x0 + dx) * depth, (4.5 + dy) * depth, depth), Vec3(0, 0, depth), normal, Vec2(0, 0)});
    m.triangles.push_back({{base, base + 1, base + 2}, id});
    m.triangles.push_back({{base, base + 2, base + 3}, id});
  };
  square(4.5, 2.0, 0, Vec3(0, 0, -1));   // behind, opaque, red
  square(4.5, 1.0, 1, Vec3(0, 0, -1));   // in front, opacity 1/4, green
  square(40.5, 1.0, 2, Vec3(0, 0, 1));   // one-sided, its front facing away from the eye
  square(40.5, 2.0, 3, Vec3(0, 0, -1));  // behind it, blue
  RenderSettings s;
  s.width = 72;
  s.height = 32;
  s.aa = 1;
  s.hither = 0.01;
  Material emissive;
  emissive.ka = emissive.kd = emissive.ks = 0;
  for (const Rgb& e : {Rgb(1, 0, 0), Rgb(0, 1, 0), Rgb(1, 1, 1), Rgb(0, 0, 1)}) {
    emissive.emission = e;
    s.materials.push_back(emissive);
  }
  s.materials[1].opacity = 0.25;
  s.materials[2].twoSided = false;
  s.materialOf = {0, 1, 2, 3};
  ASSERT_TRUE(s.AnyTransparency());
  CaptureSink sink(s.width);
  ASSERT_TRUE(RenderMesh(m, s, sink));
  auto at = [&](int x, int y, int c) { return sink.rgba[(static_cast<size_t>(y) * 72 + x) * 4 + c]; };
  EXPECT_FLOAT_EQ(at(14, 14, 0), 0.75f);
  EXPECT_FLOAT_EQ(at(14, 14, 1), 0.25f);
  EXPECT_FLOAT_EQ(at(14, 14, 3), 1.0f);
  EXPECT_FLOAT_EQ(at(50, 14, 2), 1.0f);  // the blue square shows through the culled one
  EXPECT_FLOAT_EQ(at(50, 14, 0), 0.0f);
  s.materials[2].reversed = true;        // now its front faces the eye
  CaptureSink again(s.width);
  ASSERT_TRUE(RenderMesh(m, s, again));
  EXPECT_FLOAT_EQ(again.rgba[(14 * 72 + 50) * 4 + 0], 1.0f);
}

// Orthographic triangles (W = 1) are ordered by the depth their vertices carry, and
// their fragments' w is that depth, linear across the triangle: two crossing squares, one
// tilted in depth, each nearer on its own side of the crossing.
TEST(ScanlineRenderer, OrthographicDepthComesFromTheVertices) {
  TriangleMesh m;
  auto square = [&](double dLeft, double dRight, std::uint32_t id) {
    const auto base = static_cast<std::uint32_t>(m.vertices.size());
    for (auto [x, y] : {std::pair{4.5, 4.5}, {60.5, 4.5}, {60.5, 28.5}, {4.5, 28.5}}) {
      const double d = x < 30 ? dLeft : dRight;
      m.vertices.push_back({Vec3(x, y, 1), Vec3(x, y, d), Vec3(0, 0, -1), Vec2(0, 0), d});
    }
    m.triangles.push_back({{base, base + 1, base + 2}, id});
    m.triangles.push_back({{base, base + 2, base + 3}, id});
  };
  square(2.0, 2.0, 0);  // flat at depth 2
  square(1.0, 3.0, 1);  // from depth 1 (left) to 3 (right): crosses depth 2 at x = 32.5
  RenderSettings s;
  s.width = 64;
  s.height = 32;
  s.aa = 1;
  s.hither = 0.5;
  s.orthographic = true;
  s.materials.resize(2);
  for (int k = 0; k < 2; ++k) {
    s.materials[static_cast<size_t>(k)].ka = s.materials[static_cast<size_t>(k)].kd = s.materials[static_cast<size_t>(k)].ks = 0;
    s.materials[static_cast<size_t>(k)].emission = k == 0 ? Rgb(1, 0, 0) : Rgb(0, 1, 0);
  }
  s.materialOf = {0, 1};
  struct Sink : RowSink {
    std::vector<float> px;
    bool WriteRow(int, const float* row) override {
      px.insert(px.end(), row, row + 64 * kChannels);
      return true;
    }
  } sink;
  ASSERT_TRUE(RenderMesh(m, s, sink));
  auto at = [&](int x, int c) { return sink.px[(static_cast<size_t>(16) * 64 + x) * kChannels + c]; };
  EXPECT_FLOAT_EQ(at(20, 1), 1.0f);  // left: the tilted square is nearer
  EXPECT_FLOAT_EQ(at(45, 0), 1.0f);  // right: the flat one
  EXPECT_NEAR(at(20, kChannelZ), 1.0 + 2.0 * (20.5 - 4.5) / 56.0, 1e-5);  // w: the depth, linear in x (pixel centre)
  EXPECT_NEAR(at(45, kChannelZ), 2.0, 1e-6);
}

TEST(ScanlineRenderer, TriangleCrossingTheEyePlaneRendersOnlyItsFrontPart) {
  // A ground-like triangle running from in front of the eye to far behind it: rendered
  // without clipping, every output finite, the part beyond the hither plane covered and
  // the hither plane respected (no sample nearer than it).
  auto h = [](const Vec3& p) { return Homogeneous(p, 100, 64, 48); };
  TriangleMesh m;
  const Vec3 p[3] = {Vec3(-3, 1, 10), Vec3(3, 1, 10), Vec3(0, 1, -5)};
  for (const Vec3& q : p) m.vertices.push_back({h(q), q, Vec3(0, -1, 0), Vec2(0, 0)});
  m.triangles.push_back({{0, 1, 2}, 0});
  struct AovSink : RowSink {
    std::vector<float> px;
    bool WriteRow(int, const float* row) override {
      px.insert(px.end(), row, row + 128 * kChannels);
      return true;
    }
  } sink;
  RenderSettings s;
  s.width = 128;
  s.height = 96;
  s.aa = 2;
  s.hither = 0.5;
  s.lights = DefaultLightRig(Vec3(0, 0, 1), Vec3(0, -1, 0), Vec3(1, 0, 0));
  ASSERT_TRUE(RenderMesh(m, s, sink));
  int covered = 0;
  for (size_t i = 0; i < sink.px.size(); i += kChannels) {
    // Every channel finite, but the depth of a pixel no surface covers: +inf (background).
    for (int c = 0; c < kChannels; ++c) {
      if (c != kChannelZ || sink.px[i + kChannelId] >= 0) {
        ASSERT_TRUE(std::isfinite(sink.px[i + c]));
      }
    }
    if (sink.px[i + kChannelId] < 0) {
      EXPECT_EQ(sink.px[i + kChannelZ], std::numeric_limits<float>::infinity());
    }
    if (sink.px[i + 3] > 0) {
      ++covered;
      EXPECT_GE(sink.px[i + kChannelZ], 0.5f * (1 - 1e-5f)) << "nearer than the hither plane";
    }
  }
  EXPECT_GT(covered, 500);
}

TEST(ImageWriter, FormatsAndChannels) {
  const auto dir = std::filesystem::temp_directory_path() / "patchscan_writer_formats";
  std::filesystem::create_directories(dir);
  std::vector<float> row(kChannels * 4);
  for (int x = 0; x < 4; ++x)
    for (int c = 0; c < kChannels; ++c) row[x * kChannels + c] = 0.25f * static_cast<float>(c % 4);
  const std::tuple<const char*, bool, int> cases[] = {
      {"a.png", false, 4}, {"a.tif", false, 4}, {"a.jpg", false, 3}, {"a.exr", false, 4}, {"b.exr", true, 11}};
  for (const auto& [name, aov, channels] : cases) {
    const std::string path = (dir / name).string();
    auto w = std::get<std::unique_ptr<ImageWriter>>(ImageWriter::Open(path, 4, 2, aov));
    ASSERT_TRUE(w->WriteRow(0, row.data()) && w->WriteRow(1, row.data()));
    ASSERT_TRUE(std::holds_alternative<std::monostate>(w->Commit()));
    auto in = OIIO::ImageInput::open(path);
    ASSERT_TRUE(in) << name;
    EXPECT_EQ(in->spec().nchannels, channels) << name;
    if (aov) {
      EXPECT_EQ(in->spec().channelindex("Z"), in->spec().z_channel) << name;
      EXPECT_GE(in->spec().channelindex("id"), 0);
      EXPECT_GE(in->spec().channelindex("N.x"), 0);
    }
  }
  EXPECT_NE(std::get<std::string>(ImageWriter::Open((dir / "c.png").string(), 4, 2, true)).find("need an .exr"),
            std::string::npos);
  std::filesystem::remove_all(dir);
}

TEST(ImageWriter, CompressionByFormat) {
  // Each format's methods are accepted and recorded in the file (PNG has no record: its
  // zlib level shows in the size), the pixels the same; other methods are refused by name.
  const auto dir = std::filesystem::temp_directory_path() / ("patchscan_writer_compression_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  constexpr int kWidth = 64, kHeight = 16;
  std::vector<float> row(kChannels * kWidth);
  auto fill = [&](int y) {
    for (int x = 0; x < kWidth; ++x)
      for (int c = 0; c < 4; ++c) row[x * kChannels + c] = c == 3 ? 1.0f : static_cast<float>((x * 7 + y * 3 + c) % 64) / 63;
  };
  auto write = [&](const std::string& name, const std::string& compression) {
    const std::string path = (dir / name).string();
    auto w = std::get<std::unique_ptr<ImageWriter>>(
        ImageWriter::Open(path, kWidth, kHeight, false, 1, ImageWindow(), compression));
    for (int y = 0; y < kHeight; ++y) {
      fill(y);
      EXPECT_TRUE(w->WriteRow(y, row.data()));
    }
    EXPECT_TRUE(std::holds_alternative<std::monostate>(w->Commit())) << name;
    return path;
  };
  auto pixels = [](const std::string& path) {
    auto in = OIIO::ImageInput::open(path);
    std::vector<float> px(static_cast<std::size_t>(in->spec().image_pixels() * in->spec().nchannels));
    in->read_image(0, 0, 0, in->spec().nchannels, OIIO::TypeDesc::FLOAT, px.data());
    return std::make_pair(in->spec().get_string_attribute("compression"), px);
  };
  const auto stored = std::filesystem::file_size(write("stored.png", "none"));
  const auto fast = std::filesystem::file_size(write("fast.png", "zip:1"));
  const auto small = std::filesystem::file_size(write("small.png", "zip:9"));
  const auto runs = std::filesystem::file_size(write("runs.png", "rle"));
  EXPECT_EQ(std::filesystem::file_size(write("default.png", "")), runs);  // the default is rle
  EXPECT_GT(stored, fast);
  EXPECT_GE(fast, small);
  EXPECT_GT(stored, runs);
  for (const char* name : {"fast.png", "small.png", "runs.png"})
    EXPECT_EQ(pixels((dir / "stored.png").string()).second, pixels((dir / name).string()).second) << name;
  for (const auto& [name, compression, recorded] :
       std::vector<std::tuple<std::string, std::string, std::string>>{
           {"d.tif", "", "zip"}, {"l.tif", "lzw", "lzw"}, {"p.tif", "packbits", "packbits"}, {"n.tif", "none", "none"},
           {"d.exr", "", "zip"}, {"p.exr", "piz", "piz"}, {"s.exr", "zips", "zips"}, {"w.exr", "dwaa:45", "dwaa"}}) {
    const auto [got, px] = pixels(write(name, compression));
    EXPECT_EQ(got.substr(0, got.find(':')), recorded) << name;
    // Lossless ones hold the default's pixels (the lossy DWA is only recorded).
    const std::filesystem::path reference = dir / std::filesystem::path(name).replace_filename("d").replace_extension(
                                                      std::filesystem::path(name).extension());
    if (name != "w.exr") {
      EXPECT_EQ(px, pixels(reference.string()).second) << name;
    }
  }
  for (const auto& [name, compression] : std::vector<std::pair<std::string, std::string>>{
           {"a.png", "lzw"}, {"a.png", "zip:10"}, {"a.png", "zip:"}, {"a.png", "rle:3"}, {"a.tif", "piz"}, {"a.tif", "zip:0"},
           {"a.exr", "lzw"}, {"a.exr", "zip:3"}, {"a.jpg", "zip"}, {"a.jpg", "jpeg:0"}, {"a.jpg", "jpeg:x"}}) {
    const auto why = ImageWriter::CheckFormat((dir / name).string(), false, compression);
    ASSERT_TRUE(why) << name << " " << compression;
    EXPECT_NE(why->find("compression '" + compression + "'"), std::string::npos) << *why;
  }
  EXPECT_FALSE(ImageWriter::CheckFormat((dir / "a.jpg").string(), false, "jpeg:80"));
  std::filesystem::remove_all(dir);
}

TEST(Srgb, EveryTableStepHoldsTheRoundedEncoding) {
  // The code table is built from its runs' first steps; each of its 65536 steps must still
  // hold round(255 SrgbFromLinear(i / 65535)), its definition, exactly. A float of i /
  // 65535 lands on step i (its rounding is ~1e-7 of a step's 65535).
  constexpr int kSteps = 65535;
  int wrong = 0;
  for (int i = 0; i <= kSteps; ++i) {
    const auto want = static_cast<int>(std::lround(255.0 * SrgbFromLinear(static_cast<double>(i) / kSteps)));
    const int got = SrgbCode(static_cast<float>(i) / static_cast<float>(kSteps));
    if (got != want && ++wrong <= 5) ADD_FAILURE() << "step " << i << ": code " << got << ", want " << want;
  }
  EXPECT_EQ(wrong, 0);
  EXPECT_EQ(SrgbCode(0.0f), 0);
  EXPECT_EQ(SrgbCode(1.0f), 255);
  EXPECT_EQ(SrgbCode(2.0f), 255);
  EXPECT_EQ(SrgbCode(-1.0f), 0);
  EXPECT_EQ(SrgbCode(std::numeric_limits<float>::quiet_NaN()), 0);
}

TEST(ImageWriter, EightBitOutputsAreSrgbOthersLinear) {
  // A ramp of linear values, half of it at alpha 0.5 (premultiplied): the PNG holds the
  // straight colour sRGB-encoded (and says so), the JPEG the colour over black encoded,
  // the 16-bit TIFF and the EXR the linear values.
  const auto dir = std::filesystem::temp_directory_path() / ("patchscan_writer_srgb_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  constexpr int kWidth = 64;
  std::vector<float> rows[2];
  for (int y = 0; y < 2; ++y) {
    rows[y].assign(kChannels * kWidth, 0.0f);
    const float alpha = y == 0 ? 1.0f : 0.5f;
    for (int x = 0; x < kWidth; ++x) {
      const float linear = static_cast<float>(x) / (kWidth - 1);
      for (int c = 0; c < 3; ++c) rows[y][x * kChannels + c] = alpha * linear;
      rows[y][x * kChannels + 3] = alpha;
    }
  }
  for (const char* name : {"s.png", "s.jpg", "s.tif", "s.exr"}) {
    const std::string path = (dir / name).string();
    auto w = std::get<std::unique_ptr<ImageWriter>>(ImageWriter::Open(path, kWidth, 2, false));
    ASSERT_TRUE(w->WriteRow(0, rows[0].data()) && w->WriteRow(1, rows[1].data()));
    ASSERT_TRUE(std::holds_alternative<std::monostate>(w->Commit()));
    OIIO::ImageSpec config;  // the stored values: OpenImageIO would premultiply a PNG's
    config.attribute("oiio:UnassociatedAlpha", 1);
    auto in = OIIO::ImageInput::open(path, &config);
    ASSERT_TRUE(in) << name;
    const int n = in->spec().nchannels;
    std::vector<float> got(static_cast<std::size_t>(kWidth) * 2 * n);
    ASSERT_TRUE(in->read_image(0, 0, 0, n, OIIO::TypeDesc::FLOAT, got.data()));
    const std::string ext = std::filesystem::path(name).extension().string();
    const bool srgb = ext == ".png" || ext == ".jpg";
    if (srgb) {
      EXPECT_EQ(in->spec().get_string_attribute("oiio:ColorSpace"), "sRGB") << name;
    }
    // One 8-bit code; JPEG's lossy coding of a smooth ramp a few more; 16-bit and half.
    const double tol = ext == ".png" ? 0.5 / 255 + 1e-6 : ext == ".jpg" ? 4.0 / 255 : ext == ".tif" ? 1.0 / 65535 : 1e-3;
    for (int y = 0; y < 2; ++y)
      for (int x = 0; x < kWidth; ++x) {
        const double linear = static_cast<double>(x) / (kWidth - 1), alpha = y == 0 ? 1.0 : 0.5;
        const double want = ext == ".png"   ? SrgbFromLinear(linear)           // straight alpha
                            : ext == ".jpg" ? SrgbFromLinear(alpha * linear)  // over black
                                            : alpha * linear;                 // premultiplied, linear
        EXPECT_NEAR(got[static_cast<std::size_t>((y * kWidth + x) * n)], want, tol) << name << " pixel " << x << ", " << y;
      }
  }
  std::filesystem::remove_all(dir);
}

TEST(ImageWriter, AllOrNothing) {
  const auto dir = std::filesystem::temp_directory_path() / "patchscan_writer_test";
  std::filesystem::create_directories(dir);
  const std::string path = (dir / "out.png").string();
  std::filesystem::remove(path);
  std::vector<float> row(kChannels * 8, 0.5f);
  {
    auto w = std::get<std::unique_ptr<ImageWriter>>(ImageWriter::Open(path, 8, 4));
    for (int y = 0; y < 2; ++y) w->WriteRow(y, row.data());
  }  // abandoned half way
  EXPECT_TRUE(std::filesystem::is_empty(dir)) << "a partial file was left behind";
  {
    auto w = std::get<std::unique_ptr<ImageWriter>>(ImageWriter::Open(path, 8, 4));
    for (int y = 0; y < 4; ++y) ASSERT_TRUE(w->WriteRow(y, row.data()));
    ASSERT_TRUE(std::holds_alternative<std::monostate>(w->Commit()));
  }
  EXPECT_TRUE(std::filesystem::exists(path));
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir), {}), 1);
  auto bad = ImageWriter::Open((dir / "out.xyz").string(), 8, 4);
  EXPECT_NE(std::get<std::string>(bad).find("unknown image format '.xyz'"), std::string::npos);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace patchscan::raster

namespace patchscan::raster {
namespace {

// A 2 x 2 depth map seen through a camera whose screen is world (x, y) and whose depth is
// world z: three texels far (5), the lower right near (1).
TEST(ShadowMap, PercentageCloserFiltering) {
  ShadowCamera c;
  c.worldToScreen = Mat4::Identity();
  c.worldToScreen(2, 2) = 0.0;  // screen depth unused
  const ShadowMap map(2, 2, {5, 5, 5, 1}, c);
  constexpr double kBias = 0.01;
  EXPECT_EQ(map.Visibility(Vec3(-0.5, 0.5, 3.0), kBias, 0.0, 1), 1.0);  // upper left: in front of 5
  EXPECT_EQ(map.Visibility(Vec3(0.5, -0.5, 3.0), kBias, 0.0, 1), 0.0);  // lower right: behind 1
  EXPECT_EQ(map.Visibility(Vec3(0.5, -0.5, 1.0), kBias, 0.0, 1), 1.0);  // on the occluder itself: the bias
  // Blurred over the whole map with 2 x 2 samples: one texel of four shadows.
  EXPECT_EQ(map.Visibility(Vec3(0.0, 0.0, 3.0), kBias, 1.0, 2), 0.75);
  // Outside the map, or behind the light: lit.
  EXPECT_EQ(map.Visibility(Vec3(3.0, 0.0, 3.0), kBias, 0.0, 1), 1.0);
  EXPECT_EQ(map.Visibility(Vec3(1e300, -1e300, 3.0), kBias, 0.0, 1), 1.0);  // no int overflow
  EXPECT_EQ(map.Visibility(Vec3(0.5, -0.5, -3.0), kBias, 0.0, 1), 1.0);
  EXPECT_TRUE(map.Holds(Vec3(0.5, -0.5, 3.0)));
  EXPECT_FALSE(map.Holds(Vec3(1.5, -0.5, 3.0)));
}

}  // namespace
}  // namespace patchscan::raster
