// Subdivision faces through the exact scan, against the independent ray caster, sample by
// sample (xscan/agreement.h): every cage of tests/patch/cages.h from two views, so that
// silhouettes cross regular faces, irregular ones and sub-faces, and no crack between
// faces lets a sample through.
#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <iostream>

#include "patch/cages.h"
#include "patch/surface.h"
#include "patch/tessellate.h"
#include "tracker/maxima.h"
#include "tracker/surface_scan.h"
#include "xscan/agreement.h"

namespace patchscan {
namespace {

// One test per cage, so that ctest runs them side by side (the ray caster is slow under
// the sanitizers).
class EveryCage : public ::testing::TestWithParam<std::size_t> {};

TEST_P(EveryCage, AgreesWithTheRayCaster) {
  const test::Cage c = test::Cages()[GetParam()];
  std::vector<Surface> surfaces;
  for (SubdivFace& f : PrepareSubdivFaces(c.mesh)) surfaces.push_back(Surface{std::move(f), Affine3::Identity()});
  for (const Vec3& eye : {Vec3(3.1, -4.2, 2.6), Vec3(-0.7, 1.3, -5.0)}) test::ExpectAgree(surfaces, test::View(eye, 40), c.name);
}

// Bfr's own tessellation of each base face at rate 32, rasterised at pixel centres by plain
// barycentric tests (perspective-correct depth): a reference that shares with the exact scan
// neither the trackers, the Newton solves nor SubdivFace's sub-face parameterisation.
constexpr int kReferenceRate = 64;
// The reference says something only if its chords stay this close to the surface: measured
// at rate 64, 0.006 px on the smooth cube and 0.29-0.32 px on the creased cube (its chord
// error only halves from rate 32, 0.74 px: the creases' sharp patches meet with a kink
// inside the faces), so rPx up to 0.63 px there.
constexpr double kMaxEdgePx = 1.0;

struct MeshSample {
  double w = INFINITY;
  double cosView = 1.0;  // |cos| of the angle between the nearest triangle and the view ray
  bool covered() const { return std::isfinite(w); }
};

std::vector<MeshSample> RasteriseReference(const CageTessellation& mesh, const Camera& camera) {
  const Mat4 screenFromWorld = ScreenFromWorld(camera);
  std::vector<Vec3> screen;  // x, y, w
  const Vec3 eye = EyePoint(camera);
  for (const Vec3& p : mesh.points) {
    const Vec4 h = screenFromWorld * p.homogeneous();
    screen.emplace_back(h.x() / h.w(), h.y() / h.w(), h.w());
  }
  std::vector<MeshSample> image(static_cast<std::size_t>(camera.width * camera.height));
  for (const auto& t : mesh.triangles) {
    const Vec3 &a = screen[static_cast<std::size_t>(t[0])], &b = screen[static_cast<std::size_t>(t[1])],
               &c = screen[static_cast<std::size_t>(t[2])];
    if (!(a.z() > 0 && b.z() > 0 && c.z() > 0)) continue;
    const double area = (b.x() - a.x()) * (c.y() - a.y()) - (c.x() - a.x()) * (b.y() - a.y());
    if (area == 0.0) continue;
    const Vec3& pa = mesh.points[static_cast<std::size_t>(t[0])];
    const Vec3 n = (mesh.points[static_cast<std::size_t>(t[1])] - pa).cross(mesh.points[static_cast<std::size_t>(t[2])] - pa);
    const double cosView = std::abs(n.normalized().dot((pa - eye).normalized()));
    const int x0 = std::max(0, static_cast<int>(std::floor(std::min({a.x(), b.x(), c.x()}) - 0.5)));
    const int x1 = std::min(camera.width - 1, static_cast<int>(std::ceil(std::max({a.x(), b.x(), c.x()}))));
    const int y0 = std::max(0, static_cast<int>(std::floor(std::min({a.y(), b.y(), c.y()}) - 0.5)));
    const int y1 = std::min(camera.height - 1, static_cast<int>(std::ceil(std::max({a.y(), b.y(), c.y()}))));
    for (int j = y0; j <= y1; ++j)
      for (int i = x0; i <= x1; ++i) {
        const double x = i + 0.5, y = j + 0.5;
        const double l0 = ((b.x() - x) * (c.y() - y) - (c.x() - x) * (b.y() - y)) / area;
        const double l1 = ((c.x() - x) * (a.y() - y) - (a.x() - x) * (c.y() - y)) / area;
        const double l2 = 1.0 - l0 - l1;
        if (l0 < 0 || l1 < 0 || l2 < 0) continue;
        const double w = 1.0 / (l0 / a.z() + l1 / b.z() + l2 / c.z());
        MeshSample& m = image[static_cast<std::size_t>(j * camera.width + i)];
        if (w < m.w) m = {w, cosView};
      }
  }
  return image;
}

class EveryCageAgainstBfr : public ::testing::TestWithParam<std::size_t> {};

TEST_P(EveryCageAgainstBfr, CoverageAndDepthAgreeAwayFromEdges) {
  // The exact scan's nearest surface at each pixel centre against the reference mesh's.
  // They may differ only within rPx of the mesh's own coverage edges (its silhouettes and
  // boundaries are chords of the surface's, rPx covering twice the largest chord error
  // measured, in pixels at the nearest point, plus kEdgePx of rounding); elsewhere both
  // cover or neither does, so an uncovered sample inside the mesh (a hole, a crack between
  // faces) fails. Along the view ray the surface and a chord differ by the chord error over
  // the cosine of the view's angle to the triangle: kDepthChordFactor of that, relative to
  // the depth; where the view grazes the triangle (cosine below kGrazingCos) the sample is
  // on a silhouette, an edge.
  constexpr double kDepthChordFactor = 2.0, kGrazingCos = 0.1;
  const test::Cage c = test::Cages()[GetParam()];
  std::vector<Surface> surfaces;
  for (SubdivFace& f : PrepareSubdivFaces(c.mesh)) surfaces.push_back(Surface{std::move(f), Affine3::Identity()});
  const CageTessellation mesh = TessellateCage(c.mesh, kReferenceRate);
  const Vec3 eyes[] = {Vec3(3.1, -4.2, 2.6), Vec3(-0.7, 1.3, -5.0)};
  for (int view = 0; view < 2; ++view) {
    const Camera camera = test::View(eyes[view], 96);
    double wMin = INFINITY;
    for (const Vec3& p : mesh.points) wMin = std::min(wMin, ViewDepthRow(camera).dot(p.homogeneous()));
    const double chordPx = mesh.maxChordError * FocalPixels(camera) / wMin;
    const double rPx = 2.0 * chordPx + test::kEdgePx;
    const std::vector<MeshSample> reference = RasteriseReference(mesh, camera);
    // Coverage of the reference within rPx of a pixel centre, by the mesh rasterised again
    // shifted by +-rPx in x and y.
    std::vector<std::vector<MeshSample>> shifted;
    for (const auto& [dx, dy] : {std::pair{rPx, 0.0}, {-rPx, 0.0}, {0.0, rPx}, {0.0, -rPx}}) {
      Camera moved = camera;
      CageTessellation m = mesh;
      // Moving the mesh by (-dx, -dy) px in screen is sampling it at (x + dx, y + dy).
      const Mat4 screenFromWorld = ScreenFromWorld(camera);
      const Mat4 worldFromScreen = screenFromWorld.inverse();
      for (Vec3& p : m.points) {
        Vec4 h = screenFromWorld * p.homogeneous();
        h.x() -= dx * h.w();
        h.y() -= dy * h.w();
        const Vec4 back = worldFromScreen * h;
        p = back.head<3>() / back.w();
      }
      shifted.push_back(RasteriseReference(m, moved));
    }
    ExactScan scan(surfaces, camera);
    const raster::SampleColumns cols{0.5, 1.0, camera.width};
    std::vector<test::Nearest> row(static_cast<std::size_t>(camera.width));
    long covered = 0, nearEdge = 0, mismatches = 0;
    double worstDepth = 0.0;
    std::string first;
    for (int j = 0; j < camera.height; ++j) {
      std::fill(row.begin(), row.end(), test::Nearest{});
      test::NearestRow out(&row);
      ASSERT_TRUE(scan.ScanRow(j + 0.5, cols, out));
      for (int i = 0; i < camera.width; ++i) {
        const std::size_t k = static_cast<std::size_t>(j * camera.width + i);
        const MeshSample& want = reference[k];
        const test::Nearest& got = row[static_cast<std::size_t>(i)];
        covered += want.covered();
        bool edge = false;
        for (const auto& s : shifted) edge = edge || s[k].covered() != want.covered();
        bool differ = got.covered() != want.covered();
        if (!differ && got.covered()) {
          const double rel = std::abs(got.w - want.w) / want.w;
          const double depthRel = kDepthChordFactor * mesh.maxChordError / (std::max(want.cosView, kGrazingCos) * want.w) + test::kDepthRel;
          edge = edge || want.cosView < kGrazingCos;
          // Across an occlusion edge the nearest depth jumps: an edge too.
          for (const auto& s : shifted) edge = edge || (s[k].covered() && std::abs(s[k].w - want.w) > 0.05 * want.w);
          differ = rel > depthRel;
          if (!edge) worstDepth = std::max(worstDepth, rel / depthRel);
        }
        if (!differ) continue;
        if (edge) {
          ++nearEdge;
          continue;
        }
        if (++mismatches <= 5)
          first += " (" + std::to_string(i) + ", " + std::to_string(j) + "): exact " +
                   (got.covered() ? std::to_string(got.w) : "-") + ", Bfr mesh " + (want.covered() ? std::to_string(want.w) : "-") + ";";
      }
    }
    std::cout << c.name << ": " << mesh.triangles.size() << " reference triangles, chord error " << chordPx << " px; "
              << covered << " covered, " << nearEdge << " differ within " << rPx << " px of an edge, worst depth difference "
              << worstDepth << " of its bound\n";
    EXPECT_EQ(mismatches, 0) << c.name << first;
    EXPECT_GE(covered, 200) << c.name << ": the view misses the cage";
    EXPECT_LT(rPx, kMaxEdgePx) << c.name << ": the reference is too coarse to say anything";
  }
}

INSTANTIATE_TEST_SUITE_P(SubdivScanBfr, EveryCageAgainstBfr, ::testing::Range<std::size_t>(0, test::Cages().size()));

TEST(SubdivScan, TheTopOfAKiteSeenAlmostEdgeOnIsFound) {
  // A kite of the Loop octahedron (a Gregory triangle of Bfr's) seen almost edge-on: its
  // screen y varies by 2 px over the whole domain, and its top is inside. With Bfr's own
  // second derivatives (53 % off) the climb's Newton steps ended where the gradient had not
  // vanished and the maximum was dropped; it must be found at the top that 2001 x 2001
  // samples of the kite find (kTopTolPx: their spacing's share).
  constexpr double kTopTolPx = 1e-4;
  const test::Cage c = test::Cages()[9];
  ASSERT_EQ(c.name, "octahedron, Loop, valence 4");
  std::vector<SubdivFace> faces = PrepareSubdivFaces(c.mesh);
  const Surface kite{faces[5], Affine3::Identity()};
  const Camera camera = test::View(Vec3(3.1, -4.2, 2.6), 96);
  const ScreenMap map(camera, kite.worldFromObject);
  double top = INFINITY;
  for (int i = 0; i <= 2000; ++i)
    for (int j = 0; j <= 2000; ++j) {
      ScreenDerivs d;
      EvaluateScreen(kite, map, i / 2000.0, j / 2000.0, DerivOrder::Position, &d);
      top = std::min(top, d.p.y());
    }
  Counters counters;
  const std::vector<Stationary> found = FindStationaryPoints(kite, map, &counters);
  ASSERT_FALSE(found.empty());
  EXPECT_EQ(found[0].kind, StationaryKind::StrictMaximum);
  EXPECT_NEAR(found[0].y, top, kTopTolPx);
}

TEST(SubdivScan, FacesArePreparedOnlyWhileTheScanHoldsThem) {
  // A 24x24 grid seen from above at an angle: rows of faces enter and leave the active set
  // as the scan goes down. At most the faces of a band of rows are prepared at once, none
  // at the end, and no face is prepared twice by the scan.
  std::vector<Surface> surfaces;
  const SubdivMesh grid = test::Grid(24, 1);
  for (SubdivFace& f : PrepareSubdivFaces(grid)) surfaces.push_back(Surface{std::move(f), Affine3::Identity()});
  const SubdivFace& any = std::get<SubdivFace>(surfaces[0].shape);
  ASSERT_EQ(any.PreparedNow(), 0);
  long covered = 0;
  {
    ExactScan scan(surfaces, test::View(Vec3(0.0, -2.2, 2.6), 128));
    const raster::SampleColumns cols{0.5, 1.0, 128};
    std::vector<test::Nearest> row(128);
    for (int j = 0; j < 128; ++j) {
      std::fill(row.begin(), row.end(), test::Nearest{});
      test::NearestRow out(&row);
      ASSERT_TRUE(scan.ScanRow(j + 0.5, cols, out));
      for (const auto& n : row) covered += n.covered();
    }
  }  // the faces still active on the last row are released with the scan
  std::cout << "24x24 grid: " << any.Preparations() << " preparations, at most " << any.PeakPrepared()
            << " faces prepared at once of " << surfaces.size() << "\n";
  EXPECT_GT(covered, 5000);
  EXPECT_EQ(any.PreparedNow(), 0);
  EXPECT_LE(any.Preparations(), static_cast<long>(surfaces.size()));
  EXPECT_LT(any.PeakPrepared(), static_cast<long>(surfaces.size()) / 3);
}

TEST(SubdivScan, FragmentsAndTessellationCarryTheTextureCoords) {
  // "vertex" st equal to the points' (x, y) is the limit surface's (x, y): every exact
  // fragment's uv is its world position's (x, y) (identity placement), and so is every
  // tessellation vertex's. Both sides evaluate the same Bfr weights; the exact scan's point
  // is solved to 1e-7 px, far below kStTol in st.
  constexpr double kStTol = 1e-9;
  SubdivMesh m = test::Pyramid(5);
  m.stClass = StClass::Vertex;
  for (const Vec3& p : m.points) m.st.emplace_back(p.x(), p.y());
  std::vector<Surface> surfaces;
  for (SubdivFace& f : PrepareSubdivFaces(m)) surfaces.push_back(Surface{std::move(f), Affine3::Identity()});
  class Check final : public raster::FragmentRow {
   public:
    void Add(int, const raster::Fragment& f) override {
      ++n;
      worst = std::max(worst, (f.uv - f.position.head<2>()).norm());
    }
    void AddTriangle(const raster::RasterVertex&, const raster::RasterVertex&, const raster::RasterVertex&, std::uint32_t) override {}
    long n = 0;
    double worst = 0.0;
  } check;
  const Camera camera = test::View(Vec3(3.1, -4.2, 2.6), 64);
  ExactScan scan(surfaces, camera);
  const raster::SampleColumns cols{0.5, 1.0, 64};
  for (int j = 0; j < 64; ++j) ASSERT_TRUE(scan.ScanRow(j + 0.5, cols, check));
  EXPECT_GT(check.n, 200);
  EXPECT_LT(check.worst, kStTol);
  TessMesh tess;
  for (std::size_t k = 0; k < surfaces.size(); ++k) TessellateUniform(surfaces[k], 4, static_cast<std::uint32_t>(k), &tess);
  double worst = 0.0;
  for (const TessVertex& v : tess.vertices) worst = std::max(worst, (v.st - v.position.head<2>()).norm());
  EXPECT_LT(worst, kStTol);
}

TEST(SubdivScan, AFaceIsScannedOnlyBetweenItsFirstAndLastLines) {
  // A face's screen box (its hull's: the ring of cage points around it) is several times
  // its height, and the scan skips its rows above SurfaceScan::FirstY (its topmost maximum
  // or edge piece top) and drops it once Done (no tracker alive, none left to be born),
  // however tall its box: both must bracket the face as its points do. Against the face
  // sampled on a 129 x 129 grid: FirstY at or above the sampled top (within the grid's
  // miss of it, kGridMissPx) and Done first true on the first line past the sampled bottom,
  // or one line later (a tracker dies on the line after its piece's bottom).
  constexpr double kGridMissPx = 0.05;
  constexpr int kGrid = 128;
  for (const SubdivMesh& mesh : {test::Pyramid(5), test::Pyramid(8)}) {
    const Camera camera = test::View(Vec3(3.1, -4.2, 2.6), 96);
    long boxRows = 0, faceRows = 0;
    for (SubdivFace& f : PrepareSubdivFaces(mesh)) {
      const Surface s{std::move(f), Affine3::Identity()};
      const ScreenMap map(camera, s.worldFromObject);
      double top = INFINITY, bottom = -INFINITY;
      for (int i = 0; i <= kGrid; ++i)
        for (int j = 0; j <= kGrid; ++j) {
          ScreenDerivs d;
          EvaluateScreen(s, map, static_cast<double>(i) / kGrid, static_cast<double>(j) / kGrid, DerivOrder::Position, &d);
          top = std::min(top, d.p.y()), bottom = std::max(bottom, d.p.y());
        }
      const auto box = ScreenBounds(s, map);
      ASSERT_TRUE(box.has_value());
      Counters counters;
      SurfaceScan scan(s, camera, true, counters);
      EXPECT_LE(scan.FirstY(), top + 1e-9) << Describe(s);
      EXPECT_GT(scan.FirstY(), top - kGridMissPx) << Describe(s);
      // Lines half a pixel apart from the box's top: the first on which Done holds.
      double doneAt = NAN;
      scan.StartAt(box->lo.y(), 0.5);
      for (double y = box->lo.y(); y <= box->hi.y() + 1.0; y += 0.5) {
        scan.AdvanceTo(y);
        if (scan.Done()) {
          doneAt = y;
          break;
        }
        EXPECT_TRUE(y >= scan.FirstY() || scan.Trackers().edgePoints.empty()) << Describe(s) << " at y " << y;
      }
      EXPECT_GT(doneAt, bottom) << Describe(s);
      EXPECT_LE(doneAt, bottom + 1.0 + kGridMissPx) << Describe(s);
      boxRows += std::lround(box->hi.y() - box->lo.y());
      faceRows += std::lround(bottom - top);
    }
    std::cout << mesh.faceSizes.size() << " faces: their boxes " << boxRows << " rows, the faces " << faceRows << "\n";
    EXPECT_GT(boxRows, 2 * faceRows);
  }
}

TEST(SubdivScan, ThetaChainsDoNotDependOnTheTextureCoords) {
  // The θ scan's trackers, crawls and repairs work in each face's (u,v); "st" only rides
  // along to the fragments. Texture coordinates unrelated to (u,v) (each face mapped onto
  // one small triangle of the map, as surfaces/cages.rib's tetrahedron) must leave every
  // chain, counter and sample of the scan as they are without them.
  auto scanOf = [](const SubdivMesh& m) {
    std::vector<Surface> surfaces;
    for (SubdivFace& f : PrepareSubdivFaces(m)) surfaces.push_back(Surface{std::move(f), Affine3::Identity()});
    ExactScanOptions options;
    options.thetaSteps = 8;
    options.exactWhereCheaper = false;  // θ's chains on every face, however small
    ExactScan scan(surfaces, test::View(Vec3(3.1, -4.2, 2.6), 64), options);
    const raster::SampleColumns cols{0.5, 1.0, 64};
    std::vector<double> depths;
    std::vector<test::Nearest> row(64);
    for (int j = 0; j < 64; ++j) {
      std::fill(row.begin(), row.end(), test::Nearest{});
      test::NearestRow out(&row);
      EXPECT_TRUE(scan.ScanRow(j + 0.5, cols, out));
      for (const auto& n : row) depths.push_back(n.w);
    }
    return std::pair(scan.Stats(), depths);
  };
  SubdivMesh plain = test::Pyramid(5), textured = plain;
  textured.stClass = StClass::FaceVarying;
  // Every face corner its own st: the face's k-th corner at the k-th corner of a small
  // triangle of the map.
  const Vec2 kCorners[3] = {Vec2(0.0, 1.0), Vec2(1.0, 1.0), Vec2(0.5, 0.0)};
  for (int size : textured.faceSizes)
    for (int k = 0; k < size; ++k) {
      textured.stIndices.push_back(static_cast<int>(textured.st.size()));
      textured.st.push_back(0.1 * kCorners[k % 3] + Vec2(0.3, 0.6));
    }
  const auto [plainStats, plainDepths] = scanOf(plain);
  const auto [texturedStats, texturedDepths] = scanOf(textured);
  // Rows above a face's first line or below its last are not visited (43 advanced here;
  // over 100 when every row of a face's box was, most of them with no chain).
  EXPECT_GT(plainStats[Counter::ThetaRowsAdvanced], 30);
  for (const Counter c : {Counter::Walks, Counter::ThetaRowsAdvanced, Counter::ThetaLineRepairs,
                          Counter::ThetaLinkRepairs, Counter::ThetaTrackers, Counter::ThetaTrackerIterations,
                          Counter::ThetaTrackersLost, Counter::ThetaCrawlIterations, Counter::Fragments})
    EXPECT_EQ(texturedStats[c], plainStats[c]) << kCounterTable[static_cast<std::size_t>(c)].key;
  EXPECT_EQ(texturedDepths, plainDepths);  // the same samples covered, at the same depths
}

INSTANTIATE_TEST_SUITE_P(SubdivScan, EveryCage, ::testing::Range<std::size_t>(0, test::Cages().size()),
                         [](const ::testing::TestParamInfo<std::size_t>& info) {
                           const std::vector<test::Cage> cages = test::Cages();
                           std::string name;
                           for (const char ch : cages[info.param].name)
                             name += std::isalnum(static_cast<unsigned char>(ch)) != 0 ? ch : '_';
                           return name;
                         });

}  // namespace
}  // namespace patchscan
