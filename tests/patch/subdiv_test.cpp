// Subdivision faces (OpenSubdiv Bfr) as surfaces: derivatives against finite differences,
// a regular face against the same face as a bicubic B-spline patch, neighbouring faces and
// sub-faces meeting exactly along their shared edges, the hull containing the surface, and
// cages that are not meshes refused with a reason.
#include <gtest/gtest.h>

#include <algorithm>
#include <iostream>
#include <stdexcept>

#include "core/check.h"
#include "patch/basis.h"
#include "patch/bicubic.h"
#include "patch/cages.h"
#include "scene/rib/reader.h"
#include "scene/rib/writer.h"
#include "patch/subdiv.h"

namespace patchscan {
namespace {

SurfaceDerivs At(const SubdivFace& f, double u, double v) {
  SurfaceDerivs d;
  f.Evaluate(u, v, DerivOrder::Second, &d);
  return d;
}

// The largest discrepancy between a face's derivatives and central differences of its
// positions, relative to the derivatives' size, over a grid of points inside the face.
struct FdError {
  double first = 0.0, second = 0.0;
};
FdError WorstFdError(const SubdivFace& f) {
  constexpr double h = 1e-5;
  FdError e;
  for (int i = 1; i < 16; ++i)
    for (int j = 1; j < 16; ++j) {
      // Off the dyadic lines where Bfr's pieces meet (the differences must not straddle one).
      const double u = (i + 0.37) / 16.0 - 0.02, v = (j + 0.61) / 16.0 - 0.03;
      const SurfaceDerivs d = At(f, u, v), pu = At(f, u + h, v), mu = At(f, u - h, v), pv = At(f, u, v + h),
                          mv = At(f, u, v - h);
      const double scale = d.dpdu.norm() + d.dpdv.norm();
      e.first = std::max({e.first, ((pu.p - mu.p) / (2 * h) - d.dpdu).norm() / scale,
                          ((pv.p - mv.p) / (2 * h) - d.dpdv).norm() / scale});
      const double scale2 = scale + d.d2pdu2.norm() + d.d2pduv.norm() + d.d2pdv2.norm();
      e.second = std::max({e.second, ((pu.dpdu - mu.dpdu) / (2 * h) - d.d2pdu2).norm() / scale2,
                           ((pv.dpdv - mv.dpdv) / (2 * h) - d.d2pdv2).norm() / scale2,
                           ((pu.dpdv - mu.dpdv) / (2 * h) - d.d2pduv).norm() / scale2});
    }
  return e;
}

TEST(Subdiv, DerivativesMatchFiniteDifferencesOnEveryCage) {
  // Regular faces and the regular pieces of irregular ones are polynomials: central
  // differences with step 1e-5 err by ~1e-10 in the first derivatives and, differenced from
  // them, ~1e-6 in the second; kFdRel covers both.
  // Near an extraordinary vertex Bfr (at its default approximation level 2) evaluates a
  // Gregory patch, a rational blend whose derivatives OpenSubdiv 3.5 computes without the
  // blend's own derivative: there position and first derivatives disagree, relative to
  // their size, by up to 1.0 % (measured over these cages; kGregoryRel bounds it), and
  // Bfr's second derivatives by 21 % (Loop's Gregory triangles: 2.6 % and 53 %,
  // kLoopGregoryRel). SubdivFace takes an irregular face's second derivatives from central
  // differences of the first instead (the silhouette Newton ran away on Bfr's own); what
  // remains against differences is the first derivatives' own disagreement (their mixed
  // partials differ): measured up to 3.4 % (Catmull-Clark) and 4.5 % (Loop), bounded by
  // kGregorySecondRel, which Bfr's own second derivatives fail. The trackers and the exact
  // scan converge with a Jacobian this close (the positions are Bfr's exactly); the shading
  // normal there is off by up to the first figure. Regular faces of either scheme, and
  // Loop's kites (a bilinear map into the triangle, its twist in the chain rule), are
  // within kFdRel.
  constexpr double kFdRel = 1e-5, kGregoryRel = 0.015, kGregorySecondRel = 0.06;
  constexpr double kLoopGregoryRel = 0.03, kLoopGregorySecondRel = 0.06;
  for (const test::Cage& c : test::Cages()) {
    const auto faces = PrepareSubdivFaces(c.mesh);
    ASSERT_FALSE(faces.empty()) << c.name;
    double worstFirst = 0.0, worstSecond = 0.0;
    for (const SubdivFace& f : faces) {
      const FdError e = WorstFdError(f);
      worstFirst = std::max(worstFirst, e.first);
      worstSecond = std::max(worstSecond, e.second);
      if (f.Regular()) {
        EXPECT_LT(e.first, kFdRel) << c.name << ", " << f.Describe();
        EXPECT_LT(e.second, kFdRel) << c.name << ", " << f.Describe();
      } else {
        const bool loop = c.mesh.scheme == SubdivScheme::Loop;
        EXPECT_LT(e.first, loop ? kLoopGregoryRel : kGregoryRel) << c.name << ", " << f.Describe();
        EXPECT_LT(e.second, loop ? kLoopGregorySecondRel : kGregorySecondRel) << c.name << ", " << f.Describe();
      }
    }
    std::cout << c.name << ": derivatives against differences, worst " << worstFirst << " (first), " << worstSecond
              << " (second), relative\n";
  }
}

TEST(Subdiv, ARegularFaceIsItsBicubicBSplinePatch) {
  // Face (1,1) of a 4x4 grid has the regular 4x4 neighbourhood of points (i, j), i, j in
  // 0..3: Catmull-Clark's limit there is the uniform bicubic B-spline patch of those points.
  // Both evaluate cubic polynomials of points of size ~1: kSameTol is rounding.
  constexpr double kSameTol = 1e-9;
  const SubdivMesh grid = test::Grid(4, 1);
  const auto faces = PrepareSubdivFaces(grid);
  const SubdivFace* face = nullptr;
  for (const SubdivFace& f : faces)
    if (f.Face() == 5) face = &f;  // (i, j) = (1, 1)
  ASSERT_NE(face, nullptr);
  EXPECT_TRUE(face->Regular());
  std::array<Vec3, 16> cv;
  for (int j = 0; j < 4; ++j)
    for (int i = 0; i < 4; ++i) cv[static_cast<std::size_t>(4 * j + i)] = grid.points[static_cast<std::size_t>(5 * j + i)];
  const BicubicPatch patch(cv, BSplineBasis(), BSplineBasis());
  for (double u : {0.0, 0.17, 0.5, 0.83, 1.0})
    for (double v : {0.0, 0.29, 0.5, 1.0}) {
      SurfaceDerivs a = At(*face, u, v), b;
      patch.Evaluate(u, v, DerivOrder::Second, &b);
      EXPECT_LT((a.p - b.p).norm(), kSameTol) << u << ", " << v;
      EXPECT_LT((a.dpdu - b.dpdu).norm(), kSameTol);
      EXPECT_LT((a.dpdv - b.dpdv).norm(), kSameTol);
      EXPECT_LT((a.d2pdu2 - b.d2pdu2).norm(), kSameTol);
      EXPECT_LT((a.d2pduv - b.d2pduv).norm(), kSameTol);
      EXPECT_LT((a.d2pdv2 - b.d2pdv2).norm(), kSameTol);
    }
}

TEST(Subdiv, BicubicPiecesAreBfrsOwnSurface) {
  // Once a scan's hold has fitted them, SubdivFace evaluates a regular Catmull-Clark or
  // bilinear quadrilateral, and the cells of an irregular Catmull-Clark face away from its
  // extraordinary corners, as bicubic patches fitted to Bfr's values: in every cell it covers it must be Bfr's surface, position and
  // derivatives (edges and corners too, where boundary faces extrapolate), to rounding of
  // points of size ~1 (kSameRel of the face's extent; Bfr and Horner's rule sum the same
  // cubic differently). Loop's regular triangles are quartic, and stay with Bfr; the
  // Gregory cells at an extraordinary corner are the next test's.
  constexpr double kSameRel = 1e-10;
  int whole = 0, partly = 0, cellsOfPartly = 0;
  for (const test::Cage& c : test::Cages()) {
    for (const SubdivFace& f : PrepareSubdivFaces(c.mesh)) {
      const bool loop = c.mesh.scheme == SubdivScheme::Loop;
      EXPECT_FALSE(f.BicubicAt(0.5, 0.5)) << "fitted before a hold that fits: " << c.name << ", " << f.Describe();
      f.Hold(/*fit=*/true);  // as a scan does
      int cells = 0;
      for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) cells += f.BicubicAt((i + 0.5) / 4.0, (j + 0.5) / 4.0);
      if (loop) {
        EXPECT_EQ(cells, 0) << c.name << ", " << f.Describe();
      }
      if (!loop && f.SubFace() < 0 && f.Regular()) {
        EXPECT_EQ(cells, 16) << c.name << ", " << f.Describe();
      }
      if (cells == 16) ++whole;
      if (cells > 0 && cells < 16) ++partly, cellsOfPartly += cells;
      double extent = 0.0;
      for (const Vec3& q : f.Hull()) extent = std::max(extent, q.cwiseAbs().maxCoeff());
      const double tol = kSameRel * std::max(extent, 1.0);
      for (int i = 0; i <= 16; ++i)
        for (int j = 0; j <= 16; ++j) {
          const double u = i / 16.0, v = j / 16.0 + (j % 2 ? 0.013 : 0.0);
          if (!f.BicubicAt(u, v)) continue;  // Evaluate is Bfr there
          SurfaceDerivs a, b;
          f.Evaluate(u, v, DerivOrder::Second, &a);
          f.EvaluateByBfr(u, v, DerivOrder::Second, &b);
          const std::string at = c.name + ", " + f.Describe() + " at " + std::to_string(u) + ", " + std::to_string(v);
          EXPECT_LT((a.p - b.p).cwiseAbs().maxCoeff(), tol) << at;
          EXPECT_LT((a.dpdu - b.dpdu).cwiseAbs().maxCoeff(), tol) << at;
          EXPECT_LT((a.dpdv - b.dpdv).cwiseAbs().maxCoeff(), tol) << at;
          EXPECT_LT((a.d2pdu2 - b.d2pdu2).cwiseAbs().maxCoeff(), tol) << at;
          EXPECT_LT((a.d2pduv - b.d2pduv).cwiseAbs().maxCoeff(), tol) << at;
          EXPECT_LT((a.d2pdv2 - b.d2pdv2).cwiseAbs().maxCoeff(), tol) << at;
        }
      f.Release();
    }
  }
  std::cout << whole << " faces evaluated wholly as bicubics, " << partly << " irregular ones in part ("
            << cellsOfPartly << " of their " << 16 * partly << " cells)\n";
  EXPECT_GT(whole, 0);
  EXPECT_GT(partly, 0);
}

TEST(Subdiv, GregoryPiecesAreBfrsOwnSurface) {
  // At an extraordinary corner Bfr's Catmull-Clark surface is a Gregory patch (a rational
  // blend), which a hold that fits fits as one: there Evaluate must be Bfr's position and
  // first derivatives (OpenSubdiv's, which hold the blend fixed) to rounding (kSameRel of
  // the face's extent; the fit is a least-squares solve of 36 positions), and its second
  // derivatives those of the first-derivative field: against central differences of
  // Evaluate's own first derivatives (step 1e-5: truncation ~1e-10 of their size, rounding
  // ~1e-11), within kFdRel. Every cell of an irregular Catmull-Clark face without creases
  // or sharp corners is one piece or the other, none left to Bfr (next to a sharp feature
  // Bfr's cells are other shapes: 3 cells of the creased cube's faces stay Bfr's).
  constexpr double kSameRel = 1e-10, kFdRel = 1e-6, h = 1e-5;
  int faces = 0, gregoryCells = 0, bfrCells = 0;
  for (const test::Cage& c : test::Cages()) {
    if (c.mesh.scheme != SubdivScheme::CatmullClark) continue;
    for (const SubdivFace& f : PrepareSubdivFaces(c.mesh)) {
      if (f.Regular()) continue;
      ++faces;
      f.Hold(/*fit=*/true);
      double extent = 0.0;
      for (const Vec3& q : f.Hull()) extent = std::max(extent, q.cwiseAbs().maxCoeff());
      const double tol = kSameRel * std::max(extent, 1.0);
      for (int ci = 0; ci < 4; ++ci)
        for (int cj = 0; cj < 4; ++cj) {
          if (!f.GregoryAt((ci + 0.5) / 4.0, (cj + 0.5) / 4.0)) {
            const bool bfr = !f.BicubicAt((ci + 0.5) / 4.0, (cj + 0.5) / 4.0);
            bfrCells += bfr;
            EXPECT_FALSE(bfr && c.mesh.creases.empty() && c.mesh.corners.empty()) << c.name << ", " << f.Describe();
            continue;
          }
          ++gregoryCells;
          for (const double a : {0.0, 0.23, 0.5, 0.77})
            for (const double b : {0.0, 0.31, 0.5, 0.88}) {
              const double u = (ci + a) / 4.0, v = (cj + b) / 4.0;
              const std::string at = c.name + ", " + f.Describe() + " at " + std::to_string(u) + ", " + std::to_string(v);
              SurfaceDerivs e, r;
              f.Evaluate(u, v, DerivOrder::Second, &e);
              f.EvaluateByBfr(u, v, DerivOrder::First, &r);
              EXPECT_LT((e.p - r.p).cwiseAbs().maxCoeff(), tol) << at;
              EXPECT_LT((e.dpdu - r.dpdu).cwiseAbs().maxCoeff(), tol) << at;
              EXPECT_LT((e.dpdv - r.dpdv).cwiseAbs().maxCoeff(), tol) << at;
              if (a == 0.0 || b == 0.0) continue;  // differences across a cell's edge
              SurfaceDerivs pu, mu, pv, mv;
              f.Evaluate(u + h, v, DerivOrder::First, &pu);
              f.Evaluate(u - h, v, DerivOrder::First, &mu);
              f.Evaluate(u, v + h, DerivOrder::First, &pv);
              f.Evaluate(u, v - h, DerivOrder::First, &mv);
              const double scale = e.dpdu.norm() + e.dpdv.norm() + e.d2pdu2.norm() + e.d2pduv.norm() + e.d2pdv2.norm();
              const Vec3 duu = (pu.dpdu - mu.dpdu) / (2 * h), dvv = (pv.dpdv - mv.dpdv) / (2 * h);
              const Vec3 duv = 0.5 * ((pu.dpdv - mu.dpdv) / (2 * h) + (pv.dpdu - mv.dpdu) / (2 * h));
              EXPECT_LT((duu - e.d2pdu2).norm() / scale, kFdRel) << at;
              EXPECT_LT((dvv - e.d2pdv2).norm() / scale, kFdRel) << at;
              EXPECT_LT((duv - e.d2pduv).norm() / scale, kFdRel) << at;
            }
        }
      f.Release();
    }
  }
  std::cout << faces << " irregular Catmull-Clark faces: " << gregoryCells << " cells as Gregory patches, " << bfrCells
            << " left to Bfr\n";
  EXPECT_GT(gregoryCells, 0);
}

TEST(Subdiv, NeighboursMeetAlongSharedEdges) {
  // Each surface's four boundary curves, sampled; every sample on an edge some other surface
  // also bounds must be a point of that surface's boundary too (to rounding: kSeamTol), or
  // the scans would show a crack. Checked as: each boundary sample has a partner sample on
  // another surface's boundary, found among all samples.
  constexpr double kSeamTol = 1e-9;
  constexpr int kPerEdge = 9;
  for (const test::Cage& c : test::Cages()) {
    const auto faces = PrepareSubdivFaces(c.mesh);
    std::vector<std::pair<Vec3, std::size_t>> samples;
    // A sub-face's outer edges are halves of its face's edges: a quadrilateral beside it
    // is sampled twice as finely, so that every sample on either side has its partner.
    for (std::size_t k = 0; k < faces.size(); ++k)
      for (int n = faces[k].SubFace() < 0 ? 2 * kPerEdge : kPerEdge, i = 0; i <= n; ++i) {
        const double t = static_cast<double>(i) / n;
        for (const auto& [u, v] : {std::pair{t, 0.0}, {t, 1.0}, {0.0, t}, {1.0, t}})
          samples.emplace_back(At(faces[k], u, v).p, k);
      }
    // The cubes', pyramids' and polyhedra's cages are closed: every boundary sample is shared.
    const bool closed = c.name.rfind("cube with a hole", 0) != 0 && c.name.find("open ") == std::string::npos;
    long shared = 0, alone = 0;
    for (const auto& [p, k] : samples) {
      bool found = false;
      for (const auto& [q, m] : samples)
        if (m != k && (p - q).norm() < kSeamTol) found = true;
      (found ? shared : alone) += 1;
    }
    if (closed) {
      EXPECT_EQ(alone, 0) << c.name;
    }
    EXPECT_GT(shared, 0) << c.name;
  }
}

TEST(Subdiv, HullContainsTheSurface) {
  // The surface lies in the convex hull of the face's patch points; checked against its
  // axis-aligned box, which contains the hull.
  constexpr double kBoxTol = 1e-12;
  for (const test::Cage& c : test::Cages())
    for (const SubdivFace& f : PrepareSubdivFaces(c.mesh)) {
      Vec3 lo = Vec3::Constant(INFINITY), hi = -lo;
      for (const Vec3& p : f.Hull()) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
      for (int i = 0; i <= 8; ++i)
        for (int j = 0; j <= 8; ++j) {
          const Vec3 p = At(f, i / 8.0, j / 8.0).p;
          EXPECT_TRUE((p.array() >= lo.array() - kBoxTol).all() && (p.array() <= hi.array() + kBoxTol).all())
              << c.name << ", " << f.Describe();
        }
    }
}

TEST(Subdiv, CountsAndSubFaces) {
  SubdivCounts n;
  const auto faces = PrepareSubdivFaces(test::Pyramid(8), &n);
  EXPECT_EQ(n.faces, 9);
  EXPECT_EQ(n.vertices, 9);
  EXPECT_EQ(n.surfaces, 8 * 3 + 8);  // each triangle 3 sub-faces, the octagon 8
  EXPECT_EQ(static_cast<int>(faces.size()), n.surfaces);
  EXPECT_EQ(n.extraordinaryVertices, 9);  // the apex (valence 8) and the base (valence 3)
  EXPECT_EQ(n.irregularFaces, 9);
  // RenderMan's interpolateboundary 0: the boundary faces of a 4x4 grid have no limit surface.
  PrepareSubdivFaces(test::Grid(4, 0), &n);
  EXPECT_EQ(n.surfaces, 4);
  PrepareSubdivFaces(test::Grid(4, 1), &n);
  EXPECT_EQ(n.surfaces, 16);
  SubdivMesh holed = test::Cube();
  holed.holes = {2, 4};
  PrepareSubdivFaces(holed, &n);
  EXPECT_EQ(n.surfaces, 4);
}

TEST(Subdiv, CagesThatAreNotMeshesAreRefused) {
  auto refused = [](SubdivMesh m) {
    try {
      PrepareSubdivFaces(m);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  SubdivMesh m = test::Cube();
  m.faceVertices[5] = 8;
  EXPECT_NE(refused(m).find("vertex index 8 is out of range (8 points)"), std::string::npos) << refused(m);
  m = test::Cube();
  m.faceSizes[0] = 2;
  m.faceSizes[1] = 6;
  EXPECT_NE(refused(m).find("face 0 has 2 vertices"), std::string::npos);
  m = test::Cube();
  m.faceVertices[1] = 0;
  EXPECT_NE(refused(m).find("uses vertex 0 twice"), std::string::npos);
  m = test::Cube();
  m.faceSizes.pop_back();
  EXPECT_NE(refused(m).find("add up to 20 vertices, but 24"), std::string::npos);
  m = test::Cube();
  m.holes = {6};
  EXPECT_NE(refused(m).find("hole face 6 is out of range"), std::string::npos);
  m = test::Cube();
  m.creases = {{{0, 9}, 2.0}};
  EXPECT_NE(refused(m).find("crease vertex index 9"), std::string::npos);
  // What OpenSubdiv's Bfr cannot be trusted with (a fuzzed cage crashed it): an edge of three
  // faces, faces whose orientations disagree, a vertex joining two fans; and a crease
  // between vertices that share no edge (OpenSubdiv printed a warning to stdout for it).
  m = test::Cube();
  m.faceSizes.push_back(3);
  m.faceVertices.insert(m.faceVertices.end(), {0, 1, 7});  // 0-1 is already two faces' edge
  EXPECT_NE(refused(m).find("is used by 3 or more faces (a non-manifold edge)"), std::string::npos) << refused(m);
  m = test::Cube();
  std::reverse(m.faceVertices.begin(), m.faceVertices.begin() + 4);  // face 0 turned inside out
  EXPECT_NE(refused(m).find("the same way (their orientations disagree)"), std::string::npos) << refused(m);
  SubdivMesh bowtie;
  bowtie.points = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {-1, 0, 0}, {-1, -1, 0}};
  bowtie.faceSizes = {3, 3};
  bowtie.faceVertices = {0, 1, 2, 0, 3, 4};
  EXPECT_NE(refused(bowtie).find("vertex 0 joins 2 separate fans of faces (a non-manifold vertex)"), std::string::npos)
      << refused(bowtie);
  m = test::Cube();
  m.creases = {{{0, 3}, 2.0}};  // a face's diagonal
  EXPECT_NE(refused(m).find("crease: vertices 0 and 3 are not the ends of an edge"), std::string::npos) << refused(m);
  m.creases = {{{2, 2}, 2.0}};
  EXPECT_NE(refused(m).find("crease: vertices 2 and 2"), std::string::npos) << refused(m);
  // Vertex 4 is interior with two edges: faces 0 and 1 fold over it. Without creases
  // OpenSubdiv evaluates the cage; with a crease anywhere near it, it read uninitialised
  // memory (and crashed on a fuzzed cage), so the pair is refused.
  SubdivMesh folded;
  folded.points = {{0, 0, 0}, {2, 0, 0}, {2, 2, 0}, {0, 2, 0}, {1, 1, 0.5}, {3, 0, 0}, {3, 2, 0}};
  folded.faceSizes = {4, 4, 4};
  folded.faceVertices = {0, 1, 4, 3, 1, 2, 3, 4, 1, 5, 6, 2};
  folded.interpolateBoundary = 1;  // every face is on the boundary
  EXPECT_EQ(PrepareSubdivFaces(folded).size(), 3U);
  folded.creases = {{{1, 2}, 10.0}};  // not itself at vertex 4
  EXPECT_NE(refused(folded).find("vertex 4 is an interior vertex of valence 2"), std::string::npos) << refused(folded);
}

TEST(Subdiv, RibSubdivisionMesh) {
  const std::string head = "WorldBegin\n";
  const std::string cube =
      "SubdivisionMesh \"catmull-clark\" [4 4 4 4 4 4]\n"
      "  [0 1 3 2  2 3 5 4  4 5 7 6  6 7 1 0  1 7 5 3  6 0 2 4]\n"
      "  [\"interpolateboundary\" \"crease\" \"hole\"] [0 0 2 1 1 0] [0 1 3] [10]\n"
      "  \"P\" [-1 -1 1  1 -1 1  -1 1 1  1 1 1  -1 1 -1  1 1 -1  -1 -1 -1  1 -1 -1]\n";
  const auto scene = ParseRib(head + cube + "WorldEnd\n", "cube.rib");
  ASSERT_TRUE(std::holds_alternative<Scene>(scene)) << std::get<SourceError>(scene).What();
  EXPECT_EQ(std::get<Scene>(scene).surfaces.size(), 5u);  // a hole in face 3
  // Errors name the file and line.
  const auto bad = ParseRib(head + "\nSubdivisionMesh \"catmull-clark\" [4] [0 1 2 7] \"P\" [0 0 0 1 0 0 1 1 0]\n",
                            "bad.rib");
  ASSERT_TRUE(std::holds_alternative<SourceError>(bad));
  EXPECT_NE(std::get<SourceError>(bad).What().find("bad.rib:3"), std::string::npos) << std::get<SourceError>(bad).What();
  const auto tags = ParseRib(head + "SubdivisionMesh \"catmull-clark\" [3] [0 1 2] [\"crease\"] [2 1] [0] [] \"P\" [0 0 0 1 0 0 1 1 0]\n",
                             "tags.rib");
  ASSERT_TRUE(std::holds_alternative<SourceError>(tags));
  EXPECT_NE(std::get<SourceError>(tags).What().find("more arguments"), std::string::npos) << std::get<SourceError>(tags).What();
  // Loop: a triangle is three surfaces (its corners' kites); its boundary kept with
  // interpolateboundary. An unknown scheme is skipped with a warning, the rest still read.
  const auto loop = ParseRib(head +
                                 "SubdivisionMesh \"loop\" [3] [0 1 2] [\"interpolateboundary\"] [0 0] [] [] "
                                 "\"P\" [0 0 0 1 0 0 1 1 0]\n"
                                 "SubdivisionMesh \"sqrt3\" [3] [0 1 2] \"P\" [0 0 0 1 0 0 1 1 0]\n" +
                                 cube + "WorldEnd\n",
                             "loop.rib");
  ASSERT_TRUE(std::holds_alternative<Scene>(loop)) << std::get<SourceError>(loop).What();
  EXPECT_EQ(std::get<Scene>(loop).surfaces.size(), 3u + 5u);
  ASSERT_EQ(std::get<Scene>(loop).warnings.size(), 1u);
  EXPECT_NE(std::get<Scene>(loop).warnings[0].find("loop.rib:3"), std::string::npos) << std::get<Scene>(loop).warnings[0];
  // A Loop cage of quadrilaterals is refused at its line.
  const auto quads = ParseRib(head + "SubdivisionMesh \"loop\" [4] [0 1 2 3] \"P\" [0 0 0 1 0 0 1 1 0 0 1 0]\n", "quads.rib");
  ASSERT_TRUE(std::holds_alternative<SourceError>(quads));
  EXPECT_NE(std::get<SourceError>(quads).What().find("quads.rib:2: SubdivisionMesh: face 0 has 4 vertices: a Loop cage"),
            std::string::npos)
      << std::get<SourceError>(quads).What();
}

TEST(Subdiv, WrittenAsTheSubdivisionMeshItWasReadAs) {
  // Every test cage, placed by a transform, written as RIB and read back: the same
  // surfaces, point for point (17 digits read back exactly), its tags and scheme kept.
  Camera camera;
  camera.eye = Vec3(3, -4, 2);
  Affine3 place = Affine3::Identity();
  place.translate(Vec3(0.5, 0, 0)).rotate(Eigen::AngleAxisd(0.3, Vec3::UnitZ()));
  for (const test::Cage& c : test::Cages()) {
    Scene scene;
    scene.source = c.name;
    for (SubdivFace& f : PrepareSubdivFaces(c.mesh)) {
      scene.surfaces.push_back(Surface{std::move(f), place});
      scene.sourceLines.push_back(1);
    }
    const auto rib = WriteRib(scene, camera, {});
    ASSERT_TRUE(std::holds_alternative<std::string>(rib)) << c.name << ": " << std::get<RibWriteError>(rib).message;
    const auto back = ParseRib(std::get<std::string>(rib), "written.rib");
    ASSERT_TRUE(std::holds_alternative<Scene>(back)) << c.name << ": " << std::get<SourceError>(back).What();
    const Scene& read = std::get<Scene>(back);
    ASSERT_EQ(read.surfaces.size(), scene.surfaces.size()) << c.name;
    ASSERT_EQ(read.cages.size(), 1u) << c.name;
    EXPECT_EQ(read.cages[0].scheme, c.mesh.scheme) << c.name;
    for (std::size_t k = 0; k < scene.surfaces.size(); ++k)
      for (double u : {0.0, 0.4, 1.0})
        for (double v : {0.0, 0.7, 1.0}) {
          SurfaceDerivs a, b;
          EvaluateObject(scene.surfaces[k], u, v, DerivOrder::Position, &a);
          EvaluateObject(read.surfaces[k], u, v, DerivOrder::Position, &b);
          const Vec3 pa = scene.surfaces[k].worldFromObject * a.p, pb = read.surfaces[k].worldFromObject * b.p;
          EXPECT_LT((pa - pb).norm(), 1e-12) << c.name << " surface " << k;
        }
  }
  // A surface with no RIB form (the test saddles) is refused by name.
  Scene saddle;
  saddle.surfaces.push_back(Surface{Saddle(1.0), Affine3::Identity()});
  saddle.sourceLines.push_back(1);
  const auto refused = WriteRib(saddle, camera, {});
  ASSERT_TRUE(std::holds_alternative<RibWriteError>(refused));
  EXPECT_NE(std::get<RibWriteError>(refused).message.find("has no RIB form here"), std::string::npos);
}

TEST(Subdiv, FacesArePreparedOnDemandAndFreedWhenTheirLastHoldEnds) {
  // An 8x8 grid: the 36 faces whose corners are all interior have regular neighbourhoods and
  // get their boxes from the cage's points; the 28 others are prepared once at load for their
  // boxes and freed. None is prepared after loading.
  SubdivCounts n;
  const auto faces = PrepareSubdivFaces(test::Grid(8, 1), &n);
  ASSERT_EQ(faces.size(), 64u);
  EXPECT_EQ(n.boundedAtLoad, 28);
  EXPECT_EQ(faces[0].PreparedNow(), 0);
  EXPECT_EQ(faces[0].Preparations(), 0);
  // Evaluated without a hold: prepared, and kept.
  At(faces[0], 0.5, 0.5);
  EXPECT_EQ(faces[0].PreparedNow(), 1);
  // Held twice, evaluated, released twice: prepared once, freed at the last release.
  faces[9].Hold();
  faces[9].Hold();
  At(faces[9], 0.5, 0.5);
  At(faces[9], 0.25, 0.5);
  EXPECT_EQ(faces[0].PreparedNow(), 2);
  faces[9].Release();
  EXPECT_EQ(faces[0].PreparedNow(), 2);
  faces[9].Release();
  EXPECT_EQ(faces[0].PreparedNow(), 1);
  EXPECT_EQ(faces[0].Preparations(), 2);
  // The unheld face is freed when a hold on it ends. (A release without a hold breaks the
  // contract: SubdivDeathTest below.)
  faces[0].Hold();
  faces[0].Release();
  EXPECT_EQ(faces[0].PreparedNow(), 0);
  EXPECT_EQ(faces[0].PeakPrepared(), 2);
  // Prepared again on demand, the same surface.
  const SurfaceDerivs again = At(faces[9], 0.25, 0.5);
  faces[9].Hold();
  faces[9].Release();
  SubdivMesh copy = test::Grid(8, 1);
  const auto fresh = PrepareSubdivFaces(copy);
  EXPECT_LT((again.p - At(fresh[9], 0.25, 0.5).p).norm(), 1e-15);
}

TEST(SubdivDeathTest, AReleaseWithoutAHoldBreaksTheContract) {
  if (!PATCHSCAN_CHECKS_ON) GTEST_SKIP() << "checks are compiled out of this build";
  const auto faces = PrepareSubdivFaces(test::Grid(2, 1));
  faces[0].Hold();
  faces[0].Release();
  EXPECT_DEATH(faces[0].Release(), "released as many times as held");
}

// A cage with "st" of class `c` equal to each point's (x, y).
SubdivMesh WithPlanarSt(SubdivMesh m, StClass c) {
  m.stClass = c;
  for (const Vec3& p : m.points) m.st.emplace_back(p.x(), p.y());
  if (c == StClass::FaceVarying) m.stIndices = m.faceVertices;
  return m;
}

TEST(Subdiv, VertexTextureCoordsAreSubdividedAsThePointsAre) {
  // "vertex" st equal to the points' (x, y) is the surface's (x, y), with its derivatives:
  // the same Bfr surface with other data. So is face-varying st without seams under the
  // smooth rule on closed cages (no boundary rule to differ). Both evaluate the same weights:
  // kSameTol is rounding.
  constexpr double kSameTol = 1e-12;
  struct Case {
    const char* name;
    SubdivMesh mesh;
  };
  SubdivMesh smooth = WithPlanarSt(test::Pyramid(5), StClass::FaceVarying);
  smooth.faceVaryingRule = FaceVaryingRule::Smooth;
  SubdivMesh ico = WithPlanarSt(test::Icosahedron(), StClass::FaceVarying);
  ico.faceVaryingRule = FaceVaryingRule::Smooth;
  const Case cases[] = {{"cube, vertex", WithPlanarSt(test::Cube(), StClass::Vertex)},
                        {"open grid, vertex", WithPlanarSt(test::Grid(4, 1), StClass::Vertex)},
                        {"pentagonal pyramid, vertex", WithPlanarSt(test::Pyramid(5), StClass::Vertex)},
                        {"pentagonal pyramid, face-varying smooth", smooth},
                        {"icosahedron, Loop, face-varying smooth", ico}};
  for (const Case& c : cases)
    for (const SubdivFace& f : PrepareSubdivFaces(c.mesh))
      for (double u : {0.0, 0.3, 0.77, 1.0})
        for (double v : {0.0, 0.45, 1.0}) {
          const SurfaceDerivs d = At(f, u, v);
          const auto t = f.TextureCoords(u, v);
          ASSERT_TRUE(t.has_value());
          EXPECT_LT((t->st - d.p.head<2>()).norm(), kSameTol) << c.name << ", " << f.Describe() << " at " << u << ", " << v;
          EXPECT_LT((t->dstdu - d.dpdu.head<2>()).norm(), kSameTol) << c.name << ", " << f.Describe();
          EXPECT_LT((t->dstdv - d.dpdv.head<2>()).norm(), kSameTol) << c.name << ", " << f.Describe();
        }
  // Without "st", none.
  EXPECT_FALSE(PrepareSubdivFaces(test::Cube())[0].TextureCoords(0.5, 0.5).has_value());
}

TEST(Subdiv, FaceVaryingTextureCoordsFollowTheirRule) {
  // Each face of the cube its own unit square of the map (every edge a seam): under the
  // bilinear rule a quadrilateral's st is its own (u, v) exactly; under the smooth rules each
  // face's map is still a square's, bounded by its corners where they are kept.
  constexpr double kSameTol = 1e-12;
  SubdivMesh m = test::Cube();
  m.st = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  for (std::size_t f = 0; f < 6; ++f) m.stIndices.insert(m.stIndices.end(), {0, 1, 2, 3});
  // The same values at every face's corners but indexed per corner: seams everywhere.
  m.st.resize(24);
  for (std::size_t k = 0; k < 24; ++k) {
    m.st[k] = m.st[k % 4];
    m.stIndices[k] = static_cast<int>(k);
  }
  m.faceVaryingRule = FaceVaryingRule::All;
  for (const SubdivFace& f : PrepareSubdivFaces(m))
    for (double u : {0.0, 0.3, 1.0})
      for (double v : {0.0, 0.6, 1.0}) {
        const TexCoords t = *f.TextureCoords(u, v);
        EXPECT_LT((t.st - Vec2(u, v)).norm(), kSameTol) << f.Describe();
        EXPECT_LT((t.dstdu - Vec2(1, 0)).norm(), kSameTol);
        EXPECT_LT((t.dstdv - Vec2(0, 1)).norm(), kSameTol);
      }
  m.faceVaryingRule = FaceVaryingRule::CornersOnly;
  for (const SubdivFace& f : PrepareSubdivFaces(m)) {
    for (const auto& [u, v] : {std::pair{0.0, 0.0}, {1.0, 0.0}, {1.0, 1.0}, {0.0, 1.0}})
      EXPECT_LT((f.TextureCoords(u, v)->st - Vec2(u, v)).norm(), kSameTol) << "a kept corner of " << f.Describe();
    const Vec2 centre = f.TextureCoords(0.5, 0.5)->st;
    EXPECT_LT((centre - Vec2(0.5, 0.5)).norm(), kSameTol) << "the square's symmetry";
  }
  // Out-of-range indices and wrong counts are refused.
  SubdivMesh bad = m;
  bad.stIndices[5] = 24;
  EXPECT_THROW(PrepareSubdivFaces(bad), std::invalid_argument);
  bad = m;
  bad.stIndices.pop_back();
  EXPECT_THROW(PrepareSubdivFaces(bad), std::invalid_argument);
  bad = WithPlanarSt(test::Cube(), StClass::Vertex);
  bad.st.pop_back();
  EXPECT_THROW(PrepareSubdivFaces(bad), std::invalid_argument);
}

TEST(Subdiv, RibTextureCoordsByClassAndTag) {
  const std::string head = "WorldBegin\nSubdivisionMesh \"catmull-clark\" [4 4 4 4 4 4]\n"
                           "  [0 1 3 2  2 3 5 4  4 5 7 6  6 7 1 0  1 7 5 3  6 0 2 4]\n";
  const std::string p = "  \"P\" [-1 -1 1  1 -1 1  -1 1 1  1 1 1  -1 1 -1  1 1 -1  -1 -1 -1  1 -1 -1]\n";
  std::string perCorner;
  for (int f = 0; f < 6; ++f) perCorner += " 0 0 1 0 1 1 0 1";
  auto read = [&](const std::string& text) {
    auto r = ParseRib(text, "st.rib");
    if (auto* e = std::get_if<SourceError>(&r)) ADD_FAILURE() << e->What();
    return std::get<Scene>(std::move(r));
  };
  // Face-varying, bilinear (RenderMan's 0): each face's own square, the corners welded where
  // their values agree at a vertex.
  const Scene fv = read(head + "  [\"facevaryinginterpolateboundary\"] [1 0] [0] []\n" + p +
                        "  \"facevarying float[2] st\" [" + perCorner + "]\nWorldEnd\n");
  const auto& face = std::get<SubdivFace>(fv.surfaces[0].shape);
  EXPECT_EQ(face.Mesh().stClass, StClass::FaceVarying);
  EXPECT_EQ(face.Mesh().faceVaryingRule, FaceVaryingRule::All);
  EXPECT_EQ(face.Mesh().stIndices.size(), 24u);
  EXPECT_LT(face.Mesh().st.size(), 24u);
  EXPECT_LT((face.TextureCoords(0.3, 0.8)->st - Vec2(0.3, 0.8)).norm(), 1e-12);
  // The default rule is RenderMan's 1 (corners kept); propagated corners are OpenSubdiv's
  // CornersPlus1.
  EXPECT_EQ(std::get<SubdivFace>(read(head + p + "  \"facevarying float[2] st\" [" + perCorner + "]\nWorldEnd\n")
                                     .surfaces[0].shape).Mesh().faceVaryingRule,
            FaceVaryingRule::CornersOnly);
  EXPECT_EQ(std::get<SubdivFace>(read(head + "  [\"facevaryingpropagatecorners\"] [1 0] [1] []\n" + p +
                                      "  \"facevarying float[2] st\" [" + perCorner + "]\nWorldEnd\n")
                                     .surfaces[0].shape).Mesh().faceVaryingRule,
            FaceVaryingRule::CornersPlus1);
  // Undeclared and one per point: varying (RenderMan's predeclared class); "vertex" declared.
  const std::string perPoint = " [0 0 1 0 0 1 1 1 0 1 1 1 0 0 1 0]\n";
  EXPECT_EQ(std::get<SubdivFace>(read(head + p + "  \"st\"" + perPoint + "WorldEnd\n").surfaces[0].shape).Mesh().stClass,
            StClass::Varying);
  EXPECT_EQ(std::get<SubdivFace>(read(head + p + "  \"vertex float[2] st\"" + perPoint + "WorldEnd\n").surfaces[0].shape)
                .Mesh().stClass,
            StClass::Vertex);
  // Wrong counts and unknown rules name the file and line.
  for (const auto& [text, message] :
       {std::pair{head + p + "  \"st\" [0 0 1]\nWorldEnd\n", "st.rib:5: SubdivisionMesh: \"st\" expects 2 numbers per face corner (48) or per point (16), found 3"},
        {head + p + "  \"vertex float[2] st\" [0 0]\nWorldEnd\n", "st.rib:5: SubdivisionMesh: \"st\" expects 2 numbers per point (16), found 2"},
        {head + "  [\"facevaryinginterpolateboundary\"] [1 0] [4] []\n" + p + "WorldEnd\n",
         "st.rib:4: SubdivisionMesh: \"facevaryinginterpolateboundary\" takes nothing, or 0, 1, 2 or 3"}}) {
    const auto r = ParseRib(text, "st.rib");
    ASSERT_TRUE(std::holds_alternative<SourceError>(r)) << message;
    EXPECT_NE(std::get<SourceError>(r).What().find(message), std::string::npos)
        << std::get<SourceError>(r).What() << "\nwanted: " << message;
  }
  // Written and read back: the same texture coordinates.
  Camera camera;
  camera.eye = Vec3(3, -4, 2);
  for (const Scene* s : {&fv}) {
    const auto rib = WriteRib(*s, camera, {});
    ASSERT_TRUE(std::holds_alternative<std::string>(rib));
    const Scene back = read(std::get<std::string>(rib));
    ASSERT_EQ(back.surfaces.size(), s->surfaces.size());
    for (std::size_t k = 0; k < back.surfaces.size(); ++k) {
      const auto& a = std::get<SubdivFace>(s->surfaces[k].shape);
      const auto& b = std::get<SubdivFace>(back.surfaces[k].shape);
      EXPECT_EQ(b.Mesh().faceVaryingRule, a.Mesh().faceVaryingRule);
      EXPECT_LT((a.TextureCoords(0.2, 0.7)->st - b.TextureCoords(0.2, 0.7)->st).norm(), 1e-12);
    }
  }
}

}  // namespace
}  // namespace patchscan
