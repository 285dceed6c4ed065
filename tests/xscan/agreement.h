// The exact X scan against the ray caster, sample by sample: the agreement test shared by
// the exact-scan tests and the extremes suite.
#pragma once

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <iostream>
#include <span>
#include <sstream>
#include <string>
#include <vector>

#include "xscan/exact_scan.h"
#include "xscan/ray_caster.h"

namespace patchscan::test {

// Depths (eye distance w) of the two methods agree to this, relative: both solve to
// 1e-7 px or better, which moves w by far less.
constexpr double kDepthRel = 1e-6;
// A sample may differ only within this distance of a true edge (a boundary, silhouette or
// occlusion edge): there the answer depends on the last bits of the solves.
constexpr double kEdgePx = 1e-3;
// Across an occlusion edge the nearest depth jumps; within a surface it changes by far
// less than this (relative) over kEdgePx.
constexpr double kDepthJumpRel = 1e-4;

struct Nearest {
  double w = INFINITY;
  std::uint32_t surface = 0;
  Vec3 normal = Vec3::Zero();  // the fragment's (world, unit); zero from the ray caster
  bool covered() const { return std::isfinite(w); }
};

// Collects the nearest fragment of each sample of a row.
class NearestRow final : public raster::FragmentRow {
 public:
  explicit NearestRow(std::vector<Nearest>* row) : row_(row) {}
  void Add(int column, const raster::Fragment& f) override {
    ASSERT_GE(column, 0);
    ASSERT_LT(column, static_cast<int>(row_->size()));
    EXPECT_TRUE(f.normal.allFinite() && f.position.allFinite() && std::isfinite(f.w));
    Nearest& n = (*row_)[column];
    if (f.w < n.w) n = {f.w, f.surfaceId, f.normal};
  }
  // Per-row θ chains and the exact scan hand over fragments only.
  void AddTriangle(const raster::RasterVertex&, const raster::RasterVertex&, const raster::RasterVertex&,
                   std::uint32_t) override {
    ADD_FAILURE() << "a triangle from a scan without slabs";
  }

 private:
  std::vector<Nearest>* row_;
};

inline Camera View(const Vec3& eye, int size = 96, const Vec3& up = Vec3(0, 0, 1)) {
  Camera c;
  c.width = c.height = size;
  c.eye = eye;
  c.lookAt = Vec3::Zero();
  c.up = up;
  c.fovDeg = 40;
  c.hither = 0.01;
  return c;
}

// An orthographic camera (RenderMan's Projection "orthographic") looking along the
// direction from `from` to the origin, `halfHeight` world units from the centre of the
// image to its top edge.
inline Camera Orthographic(const Vec3& from, double halfHeight, int size = 128, const Vec3& up = Vec3(0, 0, 1)) {
  const Camera persp = View(from, size, up);
  Camera c;
  c.width = c.height = size;
  // Camera space: x = right, y = up on the image, z = forward; the camera plane 10 units
  // back from the origin along the view axis.
  const Vec3 forward = (-from).normalized(), right = ViewRight(persp), upImage = right.cross(forward);
  Mat4 m = Mat4::Identity();
  m.block<1, 3>(0, 0) = right.transpose();
  m.block<1, 3>(1, 0) = upImage.transpose();
  m.block<1, 3>(2, 0) = forward.transpose();
  m(2, 3) = 10.0;
  c.cameraFromWorld = m;
  c.orthographic = true;
  c.screenWindow = Vec4(-halfHeight, halfHeight, -halfHeight, halfHeight);
  c.hither = 0.1;
  return c;
}

struct Agreement {
  long samples = 0, covered = 0, nearEdge = 0, mismatches = 0;
  double worstDepthRel = 0.0;
  Counters stats;
  std::string firstMismatches;
};

// Samples at pixel centres, one per pixel; or with `spacing` below 1, on the lattice of
// the back end's supersampling (sample rows and columns `spacing` apart from 0).
inline Agreement Compare(std::span<const Surface> surfaces, const Camera& camera, double spacing = 1.0) {
  Agreement a;
  ExactScan scan(surfaces, camera);
  const test::RayCaster caster(surfaces, camera);
  const double offset = spacing == 1.0 ? 0.5 : 0.0;
  const int nx = spacing == 1.0 ? camera.width : static_cast<int>(std::lround(camera.width / spacing)) + 1;
  const int ny = spacing == 1.0 ? camera.height : static_cast<int>(std::lround(camera.height / spacing)) + 1;
  const raster::SampleColumns cols{offset, spacing, nx};
  std::vector<Nearest> row(nx);
  auto reference = [&](double x, double y) {
    const auto hit = caster.Nearest(x, y);
    return hit ? Nearest{hit->w, static_cast<std::uint32_t>(hit->surface)} : Nearest{};
  };
  auto nearEdge = [&](double x, double y, const Nearest& at) {
    for (const auto& [dx, dy] : {std::pair{kEdgePx, 0.0}, {-kEdgePx, 0.0}, {0.0, kEdgePx}, {0.0, -kEdgePx}}) {
      const Nearest q = reference(x + dx, y + dy);
      if (q.covered() != at.covered() ||
          (q.covered() && std::abs(q.w - at.w) > kDepthJumpRel * at.w))
        return true;
    }
    return false;
  };
  for (int j = 0; j < ny; ++j) {
    const double y = offset + j * spacing;
    std::fill(row.begin(), row.end(), Nearest{});
    NearestRow out(&row);
    EXPECT_TRUE(scan.ScanRow(y, cols, out));
    for (int i = 0; i < nx; ++i) {
      const double x = cols.At(i);
      const Nearest want = reference(x, y);
      const Nearest& got = row[i];
      ++a.samples;
      a.covered += want.covered();
      bool differ = got.covered() != want.covered();
      if (!differ && got.covered()) {
        const double rel = std::abs(got.w - want.w) / want.w;
        differ = rel > kDepthRel;
        if (!differ) a.worstDepthRel = std::max(a.worstDepthRel, rel);
      }
      if (!differ) continue;
      if (nearEdge(x, y, want)) {
        ++a.nearEdge;
        continue;
      }
      if (++a.mismatches <= 5) {
        std::ostringstream m;
        m << " (" << x << ", " << y << "): exact " << (got.covered() ? std::to_string(got.w) : "-")
          << " s" << got.surface << ", reference " << (want.covered() ? std::to_string(want.w) : "-")
          << " s" << want.surface << ";";
        a.firstMismatches += m.str();
      }
    }
  }
  a.stats = scan.Stats();
  return a;
}

inline void ExpectAgree(std::span<const Surface> surfaces, const Camera& camera, const std::string& name,
                 long minCovered = 50) {
  const Agreement a = Compare(surfaces, camera);
  std::cout << name << ": " << a.samples << " samples, " << a.covered << " covered, "
            << a.nearEdge << " differ within " << kEdgePx << " px of an edge, worst depth "
            << a.worstDepthRel << " relative; walks " << a.stats[Counter::Walks] << ", silhouette points "
            << a.stats[Counter::SilhouettePoints] << ", repairs " << a.stats[Counter::UntrackedSilhouettes] << "+"
            << a.stats[Counter::UntrackedExits] << ", failures " << a.stats[Counter::Failures] << '\n';
  EXPECT_EQ(a.mismatches, 0) << name << a.firstMismatches;
  EXPECT_GE(a.covered, minCovered) << name << ": the view misses the surface";
  EXPECT_EQ(a.stats[Counter::Failures], 0) << name;
}

inline void ExpectAgree(const Surface& s, const Camera& camera, const std::string& name, long minCovered = 50) {
  ExpectAgree(std::span<const Surface>(&s, 1), camera, name, minCovered);
}

// A Bézier patch folded over itself, its silhouette running into its boundary: an arch
// about the x axis seen across it from above (the silhouette, where the view grazes the
// arch, runs from edge v = 0 to edge v = 1), turned so that the arch's axis and its fold
// run slantwise across the scan lines. Seen well from View(Vec3(0.8, -4.0, 2.5)).
inline Surface FoldedArch() {
  std::array<Vec3, 16> cv;
  for (int j = 0; j < 4; ++j)
    for (int i = 0; i < 4; ++i) {
      const double u = i / 3.0, v = j / 3.0;
      cv[4 * j + i] = Vec3(1.6 * (v - 0.5) + 0.3 * u, 2.4 * std::sin(3.0 * (u - 0.5)), 1.2 * std::cos(3.0 * (u - 0.5)));
    }
  Affine3 m = Affine3::Identity();
  m.rotate(Eigen::AngleAxisd(1.0, Vec3::UnitY()));
  return Surface{BicubicPatch(cv), m};
}

}  // namespace patchscan::test
