// Tessellation: exact vertices and normals, finite normals at collapsed edges, and
// patches that share a boundary sharing their boundary vertices (no cracks).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "scene/scene.h"
#include "patch/tessellate.h"
#include "all_surfaces.h"

namespace patchscan {
namespace {

TEST(Tessellate, SphereVerticesAndNormalsAreExact) {
  constexpr double kExactTol = 1e-12;  // unit-sized trigonometry: rounding ~1e-15
  const Surface sphere{Sphere(2.0, -2, 2, 360), Affine3(Eigen::Translation3d(1, 2, 3))};
  for (int rate : {1, 3, 8}) {
    TessMesh m;
    TessellateUniform(sphere, rate, 7, &m);
    EXPECT_EQ(m.triangles.size(), 2u * rate * rate);
    EXPECT_EQ(m.vertices.size(), static_cast<size_t>((rate + 1) * (rate + 1)));
    for (const TessVertex& v : m.vertices) {
      const Vec3 r = v.position - Vec3(1, 2, 3);
      EXPECT_NEAR(r.norm(), 2.0, kExactTol);
      EXPECT_NEAR(v.normal.norm(), 1.0, kExactTol);
      // Parallel to the radius everywhere, the poles (collapsed edges) included.
      EXPECT_NEAR(std::abs(v.normal.dot(r / 2.0)), 1.0, 1e-6) << "uv " << v.uv.transpose();
    }
    for (std::uint32_t s : m.surfaceOf) EXPECT_EQ(s, 7u);
  }
}

TEST(Tessellate, TeapotIsCrackFree) {
  // Every patch-boundary vertex of the teapot that lies on another patch's boundary
  // coincides with a vertex of that patch: neighbours share their edge points exactly
  // (equal rates on shared edges). Counted by exact position.
  auto loaded = LoadScene(PATCHSCAN_SURFACES_DIR "/teapot.bpt");
  const Scene& scene = std::get<Scene>(loaded);
  TessMesh m;
  for (size_t k = 0; k < scene.surfaces.size(); ++k)
    TessellateUniform(scene.surfaces[k], 6, static_cast<std::uint32_t>(k), &m);
  const std::size_t moved = WeldBoundaryVertices(&m, kWeldRelTol * scene.WorldBounds().Diagonal().norm());
  EXPECT_GT(moved, 0u);  // without the weld, shared edges differ in their last bits
  std::map<std::tuple<double, double, double>, int> seen;
  for (const TessVertex& v : m.vertices)
    if (v.uv.x() == 0 || v.uv.x() == 1 || v.uv.y() == 0 || v.uv.y() == 1)
      ++seen[{v.position.x(), v.position.y(), v.position.z()}];
  int lonely = 0;
  for (const auto& [p, n] : seen) lonely += n == 1;
  RecordProperty("lonely_boundary_points", lonely);
  // The teapot's open boundaries: the spout tip, the handle ends and the lid-body gap
  // are free edges; everything else is shared. At rate 6 each free patch edge has 7
  // points; measured: 80 after welding, 654 without.
  EXPECT_LE(lonely, 96) << "boundary points found on one patch only";
  for (const TessVertex& v : m.vertices) EXPECT_TRUE(v.normal.allFinite());
}

}  // namespace
}  // namespace patchscan

namespace patchscan {
namespace {

TEST(Tessellate, ScreenRatesAreEqualOnSharedEdges) {
  // Edges of two teapot patches with the same four control points (in either order) get
  // the same rate, so neighbours meet vertex to vertex. A collapsed edge (the lid's apex,
  // the bottom's centre: four equal points) takes its own patch's inner rate in chord-error
  // mode: all its vertices are the one point, where any rates meet.
  auto loaded = LoadScene(PATCHSCAN_SURFACES_DIR "/teapot.bpt");
  const Scene& scene = std::get<Scene>(loaded);
  Camera cam = FrameBounds(scene.WorldBounds(), Camera{}, DefaultViewDirection(Vec3(0, 0, 1)));
  using EdgeKey = std::array<std::tuple<double, double, double>, 4>;
  auto key = [](const BicubicPatch& p, int e) {
    // Bfr edge order v=0, u=1, v=1, u=0, points along the edge; sorted to ignore direction.
    EdgeKey k;
    for (int m = 0; m < 4; ++m) {
      const int i = e == 1 ? 3 : e == 3 ? 0 : m, j = e == 0 ? 0 : e == 2 ? 3 : m;
      const Vec3& q = p.BezierPoints()[4 * j + i];
      k[m] = {q.x(), q.y(), q.z()};
    }
    if (k[3] < k[0]) std::reverse(k.begin(), k.end());
    return k;
  };
  for (double pixels : {2.0, 7.5, 30.0, -0.05, -0.25, -1.0}) {  // < 0: chord error -pixels
    std::map<EdgeKey, int> rateOf;
    int shared = 0;
    for (const Surface& s : scene.surfaces) {
      std::array<int, 4> rates;
      if (pixels > 0) {
        rates = ScreenEdgeRates(s, cam, pixels);
      } else {
        const auto all = ChordErrorRates(s, cam, -pixels);
        std::copy(all.begin(), all.begin() + 4, rates.begin());
      }
      for (int e = 0; e < 4; ++e) {
        const EdgeKey k = key(std::get<BicubicPatch>(s.shape), e);
        if (pixels < 0 && k[0] == k[3] && k[1] == k[0] && k[2] == k[0]) continue;
        const auto [it, inserted] = rateOf.emplace(k, rates[e]);
        if (!inserted) {
          ++shared;
          EXPECT_EQ(it->second, rates[e]) << "pixels " << pixels;
        }
        EXPECT_GE(rates[e], 1);
      }
    }
    EXPECT_GE(shared, 40);  // the teapot's patches share most of their edges
  }
}

// The screen distance between the surface and the tessellation, at the midpoint of every
// triangle edge and at every triangle's centroid (in uv): the chord error, the part of the
// difference along the surface's normal there (a point of the triangle off the surface
// point of the same uv but along the surface, as on a cone's flat fan, is on the surface).
// Triangles with a vertex on a collapsed edge are left out: that vertex's uv is one of
// many for its point, so the uv midpoint says nothing.
double ChordErrorPx(const Surface& s, const TessMesh& m, const Camera& cam) {
  const Mat4 screenFromWorld = ScreenFromWorld(cam);
  auto screen = [&](const Vec3& p) {
    const Vec4 h = screenFromWorld * p.homogeneous();
    return Vec2(h.x() / h.w(), h.y() / h.w());
  };
  auto surfaceAt = [&](const Vec2& uv) {
    SurfaceDerivs d;
    EvaluateObject(s, uv.x(), uv.y(), DerivOrder::Position, &d);
    return Vec3(s.worldFromObject * d.p);
  };
  auto collapsed = [&](const Vec2& uv) {
    SurfaceDerivs d;
    EvaluateObject(s, uv.x(), uv.y(), DerivOrder::First, &d);
    const double scale = std::max(d.dpdu.norm(), d.dpdv.norm());
    return std::min(d.dpdu.norm(), d.dpdv.norm()) <= kCollapsedRel * scale;
  };
  auto offSurface = [&](const Vec2& uv, const Vec3& point) {
    const Vec3 onSurface = surfaceAt(uv), n = WorldNormal(s, uv.x(), uv.y());
    return (screen(onSurface + n * n.dot(point - onSurface)) - screen(onSurface)).norm();
  };
  double worst = 0.0;
  for (const auto& t : m.triangles) {
    const TessVertex *a = &m.vertices[t[0]], *b = &m.vertices[t[1]], *c = &m.vertices[t[2]];
    if (collapsed(a->uv) || collapsed(b->uv) || collapsed(c->uv)) continue;
    const std::pair<const TessVertex*, const TessVertex*> edges[] = {{a, b}, {b, c}, {c, a}};
    for (const auto& [p, q] : edges) {
      worst = std::max(worst, offSurface(0.5 * (p->uv + q->uv), 0.5 * (p->position + q->position)));
    }
    worst = std::max(worst, offSurface((a->uv + b->uv + c->uv) / 3.0, (a->position + b->position + c->position) / 3.0));
  }
  return worst;
}

TEST(Tessellate, ChordErrorFollowsTheScreen) {
  // The default tessellation keeps every triangle within half a pixel of the surface: a
  // sphere from its pole, its side and obliquely at 100 px radius, and the teapot's
  // patches framed at 1024x768. The rates are estimated from 16 segments of 7 curves per
  // surface: the bound allows a quarter more than asked.
  constexpr double kAskedPx = kDefaultChordErrorPx, kBoundPx = 1.25 * kAskedPx;
  static_assert(kBoundPx <= 0.5);
  Camera cam;
  cam.width = 480;
  cam.height = 360;
  cam.fovDeg = 40;
  cam.lookAt = Vec3::Zero();
  for (const Vec3& eye : {Vec3(0, 0, 5), Vec3(0, -5, 0), Vec3(3, -3, 2.5)}) {
    cam.eye = eye;
    cam.up = eye.x() == 0 && eye.y() == 0 ? Vec3(0, 1, 0) : Vec3(0, 0, 1);
    const Surface sphere{Sphere(1.0, -1.0, 1.0, 360.0), Affine3::Identity()};
    TessMesh m;
    TessellateToChordError(sphere, cam, kAskedPx, 0, &m);
    EXPECT_LE(ChordErrorPx(sphere, m, cam), kBoundPx) << "sphere from " << eye.transpose();
    // Not one segment around for want of rates on its collapsed edges (its poles): they
    // take the inner rate along them, so that each pole vertex carries its own u.
    const auto rates = ChordErrorRates(sphere, cam, kAskedPx);
    EXPECT_GE(rates[4], 30);
    EXPECT_EQ(rates[0], rates[4]);
    EXPECT_EQ(rates[2], rates[4]);
    TessMesh byLength;
    TessellateToScreen(sphere, cam, 4.0, 0, &byLength);
    // 4 px chords of a 100 px circle are 0.02 px off: only the inner rates keep it so.
    EXPECT_LE(ChordErrorPx(sphere, byLength, cam), 0.1) << "sphere by 4 px edges from " << eye.transpose();
  }
  // Every quadric, including those with straight iso-lines (rate 1 along them, which once
  // made Bfr fan every triangle to the domain's centre: a cylinder seen along its axis
  // became a disc), and collapsed edges (a cone's apex, a disk's centre).
  const Shape quadrics[] = {Cylinder(1.0, -0.5, 0.5, 360.0),  Cone(1.0, 1.0, 360.0),
                            Paraboloid(1.0, 0.0, 1.0, 360.0), Hyperboloid(Vec3(1, 0, -0.5), Vec3(0, 1, 0.5), 360.0),
                            Disk(0.0, 1.0, 360.0),            Torus(1.0, 0.4, 0.0, 360.0, 360.0),
                            Cylinder(1.0, -0.5, 0.5, 90.0)};
  for (const Vec3& eye : {Vec3(0, 0, 5), Vec3(0, 0, -5), Vec3(0, -5, 0), Vec3(3, -3, 2.5)}) {
    cam.eye = eye;
    cam.up = eye.x() == 0 && eye.y() == 0 ? Vec3(0, 1, 0) : Vec3(0, 0, 1);
    for (const Shape& shape : quadrics) {
      const Surface s{shape, Affine3::Identity()};
      TessMesh m;
      TessellateToChordError(s, cam, kAskedPx, 0, &m);
      EXPECT_LE(ChordErrorPx(s, m, cam), kBoundPx) << Describe(s) << " from " << eye.transpose();
    }
  }
  auto loaded = LoadScene(PATCHSCAN_SURFACES_DIR "/teapot.bpt");
  const Scene& scene = std::get<Scene>(loaded);
  Camera teapot;
  teapot.width = 1024;
  teapot.height = 768;
  teapot = FrameBounds(scene.WorldBounds(), teapot, DefaultViewDirection(Vec3(0, 0, 1)));
  double worst = 0.0;
  for (const Surface& s : scene.surfaces) {
    TessMesh m;
    TessellateToChordError(s, teapot, kAskedPx, 0, &m);
    worst = std::max(worst, ChordErrorPx(s, m, teapot));
  }
  EXPECT_LE(worst, kBoundPx);
  RecordProperty("teapot_chord_error_px", std::to_string(worst));
}

}  // namespace
}  // namespace patchscan

namespace patchscan {
namespace {

// The normal of `s` at (u,v) from central differences of positions at a point kInside
// towards the domain's centre: independent of the derivative code and of WorldNormal's
// limit step. The normal turns at most ~100 rad per unit parameter on the test surfaces (the
// power-basis patch; ~1 rad at the teapot's lid apex), so kInside moves it by ~1e-3 rad:
// inside kLimitTolRad, which is far below the right angle a rounding-noise tangent gave.
// The paraboloid is left out: its radius grows as the square root of height, so its normal
// turns as the square root of v and no point inside is near its pole's limit.
constexpr double kInside = 1e-5, kDiffStep = 1e-7, kLimitTolRad = 1e-2;
Vec3 FiniteDifferenceNormal(const Surface& s, double u, double v) {
  auto inward = [](double t) { return t < 0.5 ? t + kInside : (t > 0.5 ? t - kInside : t); };
  const double ui = inward(u), vi = inward(v);
  auto at = [&](double a, double b) {
    SurfaceDerivs d;
    EvaluateObject(s, a, b, DerivOrder::Position, &d);
    return Vec3(s.worldFromObject * d.p);
  };
  const Vec3 pu = at(ui + kDiffStep, vi) - at(ui - kDiffStep, vi), pv = at(ui, vi + kDiffStep) - at(ui, vi - kDiffStep);
  return pu.cross(pv).normalized();
}

TEST(Tessellate, NormalsAtCollapsedEdgesAreTheLimitFromInside) {
  // The teapot's lid apex and bottom centre: four Bézier points of an edge equal, so the
  // tangent along it is rounding of the power form in any direction; a tessellated vertex
  // there took the cross product with that noise as its normal, and the lid's apex showed a
  // dark spot in tess mode. The quadrics' poles and a cone's apex too.
  auto loaded = LoadScene(PATCHSCAN_SURFACES_DIR "/teapot.bpt");
  std::vector<std::pair<std::string, Surface>> surfaces = test::AllSurfaceKinds();
  for (const Surface& s : std::get<Scene>(loaded).surfaces) surfaces.emplace_back("teapot patch", s);
  int onCollapsed = 0;
  for (const auto& [name, s] : surfaces) {
    if (std::holds_alternative<Paraboloid>(s.shape)) continue;
    const SurfaceHold hold(s);
    TessMesh m;
    TessellateUniform(s, 8, 0, &m);
    for (const TessVertex& v : m.vertices) {
      const Vec3 want = FiniteDifferenceNormal(s, v.uv.x(), v.uv.y());
      if (!want.allFinite()) continue;
      SurfaceDerivs d;
      EvaluateObject(s, v.uv.x(), v.uv.y(), DerivOrder::First, &d);
      onCollapsed += NormalVanishes(d.dpdu, d.dpdv);
      EXPECT_LT(std::acos(std::clamp(v.normal.dot(want), -1.0, 1.0)), kLimitTolRad)
          << name << " at uv " << v.uv.transpose() << ": " << v.normal.transpose() << " against " << want.transpose();
    }
  }
  EXPECT_GT(onCollapsed, 8 * 9);  // the teapot's 8 collapsed edges at rate 8, the poles and apexes besides
}

}  // namespace
}  // namespace patchscan
