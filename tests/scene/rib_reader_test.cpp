// The RIB reader: a small scene for every request it reads, with the effect asserted;
// quadric parameters against the formulas of the RenderMan Interface 3.2 ("Quadrics");
// malformed scenes answered with file:line; skipped requests warned about once per kind.
#include <gtest/gtest.h>
#include <zlib.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <functional>
#include <numbers>
#include <unistd.h>

#include "scene/mutator.h"
#include "patch/nurbs_shapes.h"
#include "scene/rib/reader.h"
#include "patch/screen.h"

namespace patchscan {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kRad = kPi / 180.0;
// Positions computed from parameters read back from text: the reader and the formulas
// round differently only in the last bits.
constexpr double kPosTol = 1e-12;

// A world block around `body`.
std::string World(const std::string& body) { return "WorldBegin\n" + body + "\nWorldEnd\n"; }

Scene Parse(const std::string& text, const LoadOptions& o = {}) {
  auto r = ParseRib(text, "t.rib", o);
  if (auto* e = std::get_if<SourceError>(&r)) ADD_FAILURE() << e->What() << "\n" << text;
  return std::get_if<Scene>(&r) ? std::get<Scene>(r) : Scene{};
}

std::string Error(const std::string& text, const LoadOptions& o = {}) {
  auto r = ParseRib(text, "t.rib", o);
  if (auto* e = std::get_if<SourceError>(&r)) return e->What();
  return "(accepted)";
}

Vec3 At(const Surface& s, double u, double v) {
  SurfaceDerivs d;
  EvaluateObject(s, u, v, DerivOrder::Position, &d);
  return s.worldFromObject * d.p;
}

void ExpectNear(const Vec3& a, const Vec3& b, double tol = kPosTol) {
  EXPECT_LT((a - b).norm(), tol * std::max(1.0, b.norm())) << a.transpose() << " vs " << b.transpose();
}

// ---- structure ----

TEST(Rib, CommentsAndBothLayoutsOfArguments) {
  const Scene s = Parse("# a comment\n" + World("Sphere 1 -1 1 360 # after\nSphere [2 -2 2 360]"));
  ASSERT_EQ(s.surfaces.size(), 2u);
  EXPECT_EQ(s.sourceLines[0], 3);
  EXPECT_EQ(s.sourceLines[1], 4);
  ExpectNear(At(s.surfaces[1], 0, 1), Vec3(0, 0, 2));
}

TEST(Rib, FramesTheFirstOrTheChosen) {
  const std::string text = "Format 10 10 1\nFrameBegin 1\n" + World("Sphere 1 -1 1 360") +
                           "FrameEnd\nFrameBegin 2\n" + World("Sphere 2 -2 2 360\nSphere 3 -3 3 360") +
                           "FrameEnd\n";
  EXPECT_EQ(Parse(text).surfaces.size(), 1u);
  LoadOptions two;
  two.frame = 2;
  const Scene s = Parse(text, two);
  EXPECT_EQ(s.surfaces.size(), 2u);
  ASSERT_TRUE(s.image.size);  // options before the frames apply to every frame
  EXPECT_EQ(s.image.size->first, 10);
  LoadOptions missing;
  missing.frame = 7;
  EXPECT_EQ(Error(text, missing), "t.rib: no FrameBegin 7 in the file");
}

TEST(Rib, AttributeBlocksRestoreAppearanceAndTransformTransformBlocksOnlyTheTransform) {
  const Scene s = Parse(World(
      "Color [1 0 0]\n"
      "AttributeBegin\n Color [0 1 0]\n Translate 5 0 0\n Sphere 1 -1 1 360\nAttributeEnd\n"
      "Sphere 1 -1 1 360\n"
      "TransformBegin\n Color [0 0 1]\n Translate 0 5 0\n Sphere 1 -1 1 360\nTransformEnd\n"
      "Sphere 1 -1 1 360"));
  ASSERT_EQ(s.surfaces.size(), 4u);
  const auto colour = [&](int k) { return s.appearances[s.appearanceOf[k]].colour; };
  EXPECT_EQ(colour(0), Vec3(0, 1, 0));
  EXPECT_EQ(colour(1), Vec3(1, 0, 0));
  EXPECT_EQ(colour(2), Vec3(0, 0, 1));
  EXPECT_EQ(colour(3), Vec3(0, 0, 1));  // TransformEnd keeps the colour
  ExpectNear(At(s.surfaces[0], 0, 0.5), Vec3(6, 0, 0));
  ExpectNear(At(s.surfaces[1], 0, 0.5), Vec3(1, 0, 0));
  ExpectNear(At(s.surfaces[2], 0, 0.5), Vec3(1, 5, 0));
  ExpectNear(At(s.surfaces[3], 0, 0.5), Vec3(1, 0, 0));  // TransformEnd restores the transform
}

TEST(Rib, ReadArchiveReadsRelativeToTheIncludingFile) {
  const auto dir = std::filesystem::temp_directory_path() / ("patchscan_rib_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir / "parts");
  std::ofstream(dir / "main.rib") << World("Translate 1 0 0\nReadArchive \"parts/a.rib\"");
  std::ofstream(dir / "parts" / "a.rib") << "Sphere 1 -1 1 360\nReadArchive \"b.rib\"\n";
  std::ofstream(dir / "parts" / "b.rib") << "Sphere 2 -2 2 360\nAttributeEnd\n";
  auto r = ReadRib((dir / "main.rib").string());
  ASSERT_TRUE(std::holds_alternative<SourceError>(r));
  // The error names the archive and its line.
  EXPECT_EQ(std::get<SourceError>(r).What(), (dir / "parts" / "b.rib").string() + ":2: AttributeEnd closes WorldBegin at " +
                                                 (dir / "main.rib").string() + ":1");
  std::ofstream(dir / "parts" / "b.rib") << "Sphere 2 -2 2 360\n";
  auto ok = ReadRib((dir / "main.rib").string());
  ASSERT_TRUE(std::holds_alternative<Scene>(ok)) << std::get<SourceError>(ok).What();
  const Scene& s = std::get<Scene>(ok);
  ASSERT_EQ(s.surfaces.size(), 2u);
  ExpectNear(At(s.surfaces[1], 0, 0.5), Vec3(3, 0, 0));  // the archive's surface, translated
  EXPECT_EQ(s.sourceFiles[1], (dir / "parts" / "b.rib").string());
  std::ofstream(dir / "parts" / "b.rib") << "ReadArchive \"b.rib\"\n";
  auto loop = ReadRib((dir / "main.rib").string());
  ASSERT_TRUE(std::holds_alternative<SourceError>(loop));
  EXPECT_NE(std::get<SourceError>(loop).message.find("nested more than 16 deep"), std::string::npos);
  std::filesystem::remove_all(dir);
}

TEST(Rib, CompressedArchivesAndDelayedReadArchive) {
  // A gzip-compressed archive read by ReadArchive and by Procedural "DelayedReadArchive"
  // (in a block of its own: its Translate and Color stay inside); a corrupt and a
  // truncated one are errors naming the file.
  const auto dir = std::filesystem::temp_directory_path() / ("patchscan_gz_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  auto gzip = [&](const std::string& name, const std::string& text, std::size_t keep = std::string::npos) {
    const std::string path = (dir / name).string();
    gzFile f = gzopen(path.c_str(), "wb");
    gzwrite(f, text.data(), static_cast<unsigned>(text.size()));
    gzclose(f);
    if (keep != std::string::npos) std::filesystem::resize_file(path, keep);
  };
  gzip("part.rib.gz", "Translate 0 0 2\nColor [0 1 0]\nSphere 1 -1 1 360\n");
  std::ofstream(dir / "main.rib") << World("ReadArchive \"part.rib.gz\"\nProcedural \"DelayedReadArchive\" [\"part.rib.gz\"] "
                                           "[-1 1 -1 1 -1 1]\nSphere 0.5 -0.5 0.5 360\nProcedural \"RunProgram\" [\"x\" \"\"] [0 1 0 1 0 1]");
  auto ok = ReadRib((dir / "main.rib").string());
  ASSERT_TRUE(std::holds_alternative<Scene>(ok)) << std::get<SourceError>(ok).What();
  const Scene& s = std::get<Scene>(ok);
  ASSERT_EQ(s.surfaces.size(), 3u);
  ExpectNear(Vec3(s.surfaces[0].worldFromObject.translation()), Vec3(0, 0, 2));
  ExpectNear(Vec3(s.surfaces[1].worldFromObject.translation()), Vec3(0, 0, 4));  // after ReadArchive's Translate
  ExpectNear(Vec3(s.surfaces[2].worldFromObject.translation()), Vec3(0, 0, 2));  // the procedural's stayed inside
  EXPECT_EQ(s.appearances[s.appearanceOf[2]].colour, Vec3(0, 1, 0));            // ReadArchive's Color did not
  ASSERT_EQ(s.warnings.size(), 1u);
  EXPECT_NE(s.warnings[0].find("Procedural 'RunProgram' is not supported here: skipped"), std::string::npos);
  std::ofstream(dir / "bad.rib.gz") << std::string("\x1f\x8b\x08\x00\x00\x00\x00\x00\x00\x03\xff\xff\xff\xff", 14);
  std::ofstream(dir / "main.rib") << World("ReadArchive \"bad.rib.gz\"");
  auto bad = ReadRib((dir / "main.rib").string());
  ASSERT_TRUE(std::holds_alternative<SourceError>(bad));
  EXPECT_EQ(std::get<SourceError>(bad).What(),
            (dir / "main.rib").string() + ":2: ReadArchive: " + (dir / "bad.rib.gz").string() + ": gzip data is corrupt: invalid block type");
  gzip("cut.rib.gz", std::string(5000, '#') + "\nSphere 1 -1 1 360\n", 30);
  std::ofstream(dir / "main.rib") << World("ReadArchive \"cut.rib.gz\"");
  auto cut = ReadRib((dir / "main.rib").string());
  ASSERT_TRUE(std::holds_alternative<SourceError>(cut));
  EXPECT_EQ(std::get<SourceError>(cut).What(),
            (dir / "main.rib").string() + ":2: ReadArchive: " + (dir / "cut.rib.gz").string() + ": the gzip data ends early");
  std::filesystem::remove_all(dir);
}

// ---- camera and image ----

TEST(Rib, CameraStatementsBeforeTheWorld) {
  const Scene s = Parse(
      "Display \"out.png\" \"file\" \"rgba\"\nFormat 400 200 1\nPixelSamples 4 4\n"
      "Projection \"perspective\" \"fov\" [45]\nScreenWindow -1 1 -0.5 0.5\nClipping 0.5 100\n"
      "Translate 0 0 5\n" + World("Sphere 1 -1 1 360"));
  EXPECT_EQ(s.image.displayName, "out.png");
  ASSERT_TRUE(s.image.size && s.image.pixelSamples && s.image.hither && s.image.screenWindow);
  EXPECT_EQ(*s.image.size, std::make_pair(400, 200));
  EXPECT_EQ(*s.image.pixelSamples, 4);
  EXPECT_EQ(*s.image.hither, 0.5);
  EXPECT_EQ(s.image.fovDeg, 45.0);
  EXPECT_EQ(*s.image.screenWindow, Vec4(-1, 1, -0.5, 0.5));
  ASSERT_TRUE(s.image.cameraFromWorld);
  // World origin at camera (0, 0, 5); the sphere is placed in world space, untouched.
  EXPECT_EQ((*s.image.cameraFromWorld * Vec4(0, 0, 0, 1)), Vec4(0, 0, 5, 1));
  EXPECT_EQ(s.surfaces[0].worldFromObject.matrix(), Mat4::Identity());
}

TEST(Rib, TheCameraMapsAsRenderManSays) {
  // Camera looking along +z at a point (1, 1, 10) of camera space: with fov 90 and a
  // square image, x_screen = x/z = 0.1 of the half-width right of centre, y up.
  Camera c;
  c.width = c.height = 200;
  c.cameraFromWorld = Mat4::Identity();
  c.screenWindow = Vec4(-1, 1, -1, 1) * std::tan(0.5 * 90 * kRad);
  c.hither = 0.1;
  ASSERT_FALSE(ValidateCamera(c));
  const Vec4 h = ScreenFromWorld(c) * Vec4(1, 1, 10, 1);
  EXPECT_NEAR(h.x() / h.w(), 110.0, 1e-9);
  EXPECT_NEAR(h.y() / h.w(), 90.0, 1e-9);
  EXPECT_NEAR(h.w(), 10.0, 1e-12);
  EXPECT_EQ(EyePoint(c), Vec3(0, 0, 0));
  EXPECT_EQ(ViewForward(c), Vec3(0, 0, 1));
  EXPECT_EQ(ViewRight(c), Vec3(1, 0, 0));
}

TEST(Rib, OrthographicProjectionAndUnknownOnes) {
  const Scene s = Parse("Projection \"orthographic\"\nScreenWindow -2 2 -1.5 1.5\nTranslate 0 0 5\n" + World("Sphere 1 -1 1 360"));
  EXPECT_TRUE(s.image.orthographic);
  EXPECT_EQ(*s.image.screenWindow, Vec4(-2, 2, -1.5, 1.5));
  EXPECT_EQ(Error("Projection \"fisheye\"\n" + World("")),
            "t.rib:1: Projection: unknown projection 'fisheye' (known: \"perspective\", \"orthographic\")");
}

// An orthographic camera maps camera space to pixels without division: x_px = W (x - l) /
// (r - l), y_px = H (t - y) / (t - b), whatever the depth; w is the depth.
TEST(Rib, TheOrthographicCameraMapsAsRenderManSays) {
  Camera c;
  c.width = 200;
  c.height = 100;
  c.cameraFromWorld = Mat4::Identity();
  c.orthographic = true;
  c.screenWindow = Vec4(-2, 2, -1, 1);
  c.hither = 0.1;
  ASSERT_FALSE(ValidateCamera(c));
  for (double z : {0.5, 7.0, 300.0}) {
    const Vec4 h = ScreenFromWorld(c) * Vec4(1, 0.5, z, 1);
    EXPECT_NEAR(h.x() / h.w(), 150.0, 1e-12);
    EXPECT_NEAR(h.y() / h.w(), 25.0, 1e-12);
    EXPECT_NEAR(ViewDepthRow(c).dot(Vec4(1, 0.5, z, 1)), z, 1e-12);
  }
  const ScreenMap map(c, Affine3(Eigen::Translation3d(0, 0, 4)));
  ScreenDerivs d;
  EvaluateScreen(Surface{Sphere(1, -1, 1, 360), Affine3(Eigen::Translation3d(0, 0, 4))}, map, 0.0, 0.5,
                 DerivOrder::First, &d);
  EXPECT_NEAR(d.w, 4.0, 1e-12);  // the point (1, 0, 4): depth 4
  EXPECT_NEAR(d.p.x(), 150.0, 1e-12);
}

// ---- transformations ----

TEST(Rib, TransformationsComposeAsTheSpecificationSays) {
  // Translate then Rotate: the rotation applies first to the object's points.
  const Scene s = Parse(World(
      "Translate 10 0 0\nRotate 90 0 0 1\nScale 2 2 2\nSphere 1 -1 1 360\n"
      "Identity\nConcatTransform [1 0 0 0  0 1 0 0  0 0 1 0  0 0 7 1]\nSphere 1 -1 1 360\n"
      "Transform [0 1 0 0  -1 0 0 0  0 0 1 0  0 0 0 1]\nSphere 1 -1 1 360"));
  ASSERT_EQ(s.surfaces.size(), 3u);
  // The sphere's point at u = 0, v = 1/2 is (1, 0, 0): scaled to (2, 0, 0), rotated to
  // (0, 2, 0), translated to (10, 2, 0).
  ExpectNear(At(s.surfaces[0], 0, 0.5), Vec3(10, 2, 0));
  ExpectNear(At(s.surfaces[1], 0, 0.5), Vec3(1, 0, 7));  // RIB's translation row
  ExpectNear(At(s.surfaces[2], 0, 0.5), Vec3(0, 1, 0));  // row vectors: x maps to row 0
}

TEST(Rib, OrientationReverseOrientationAndSides) {
  const Scene s = Parse(World(
      "Sphere 1 -1 1 360\nSides 1\nSphere 1 -1 1 360\nReverseOrientation\nSphere 1 -1 1 360\n"
      "Orientation \"outside\"\nScale -1 1 1\nSphere 1 -1 1 360\nOrientation \"inside\"\nSphere 1 -1 1 360"));
  ASSERT_EQ(s.surfaces.size(), 5u);
  const auto look = [&](int k) { return s.appearances[s.appearanceOf[k]]; };
  EXPECT_TRUE(look(0).twoSided);
  EXPECT_FALSE(look(0).reversed);
  EXPECT_FALSE(look(1).twoSided);
  EXPECT_FALSE(look(1).reversed);
  EXPECT_TRUE(look(2).reversed);   // ReverseOrientation
  EXPECT_TRUE(look(3).reversed);   // a mirroring transformation flips the handedness
  EXPECT_FALSE(look(4).reversed);  // ... and "inside" flips it back
  EXPECT_EQ(Error(World("Orientation \"up\"")),
            "t.rib:2: Orientation: expected \"outside\", \"inside\", \"lh\" or \"rh\", found 'up'");
  EXPECT_EQ(Error(World("Sides 3")), "t.rib:2: Sides: expected 1 or 2");
}

// ---- geometry ----

// Points as a RIB array, with 17 significant digits.
std::string Array(const std::vector<Vec3>& points) {
  std::ostringstream out;
  out << std::setprecision(17) << '[';
  for (const Vec3& p : points) out << ' ' << p.x() << ' ' << p.y() << ' ' << p.z();
  out << " ]";
  return out.str();
}

// The 16 control points of a bicubic patch over [0, 3]^2 with a bump, u fastest.
std::string GridPoints(double bump) {
  std::vector<Vec3> p;
  for (int j = 0; j < 4; ++j)
    for (int i = 0; i < 4; ++i) p.emplace_back(i, j, (i == 1 || i == 2) && (j == 1 || j == 2) ? bump : 0.0);
  return Array(p);
}

// Homogeneous points as a RIB array: (w x, w y, w z, w).
std::string Array(const std::vector<Vec4>& points) {
  std::ostringstream out;
  out << std::setprecision(17) << '[';
  for (const Vec4& p : points) out << ' ' << p.x() << ' ' << p.y() << ' ' << p.z() << ' ' << p.w();
  out << " ]";
  return out.str();
}

std::string Knots(const std::vector<double>& knots) {
  std::ostringstream out;
  out << std::setprecision(17) << '[';
  for (const double k : knots) out << ' ' << k;
  out << " ]";
  return out.str();
}

TEST(Rib, NuPatchIsSplitIntoItsBezierPieces) {
  const NurbsSurface n = test::NurbsSphere(2.0);
  std::ostringstream text;
  text << "NuPatch " << n.nu << ' ' << n.uorder << ' ' << Knots(n.uknot) << " 0 1 " << n.nv << ' ' << n.vorder << ' '
       << Knots(n.vknot) << " 0 1 \"Pw\" " << Array(n.pw) << '\n'
       // A part of it, non-rational points (weights 1): the plain B-spline of the same points.
       << "NuPatch 4 4 [0 0 0 0 1 1 1 1] 0.25 0.75 2 2 [0 0 1 1] 0 1 \"P\" "
       << Array(std::vector<Vec3>{{0, 0, 0}, {1, 0, 1}, {2, 0, 1}, {3, 0, 0}, {0, 1, 0}, {1, 1, 1}, {2, 1, 1}, {3, 1, 0}});
  const Scene s = Parse(World(text.str()));
  ASSERT_EQ(s.surfaces.size(), 8u + 1u);
  for (std::size_t k = 0; k < 8; ++k) {
    ASSERT_TRUE(std::holds_alternative<NurbsPiece>(s.surfaces[k].shape));
    for (const double u : {0.0, 0.3, 1.0}) EXPECT_NEAR(At(s.surfaces[k], u, 0.6).norm(), 2.0, kPosTol);
  }
  // u in [0.25, 0.75] of a cubic Bézier in x: x(0.25) = 0.75; its z at (0.5 of the
  // piece) is the Bézier's at 0.5, 0.75.
  ExpectNear(At(s.surfaces[8], 0, 0), Vec3(0.75, 0, 0.5625));
  ExpectNear(At(s.surfaces[8], 0.5, 1), Vec3(1.5, 1, 0.75));
}

// A square of 2 x 2 linear spans on [0,1]^2 and, before it, the triangle loop
// (0.1,0.1) (0.4,0.1) (0.1,0.4) (within the piece [0, 0.5]^2) as one linear TrimCurve.
const char* kTrimTriangle = "TrimCurve [1] [2] [0 0 1 2 3 3] [0] [3] [4] [0.1 0.4 0.1 0.1] [0.1 0.1 0.4 0.1] [1 1 1 1]\n";
const char* kSquare = "NuPatch 3 2 [0 0 0.5 1 1] 0 1 3 2 [0 0 0.5 1 1] 0 1 \"P\" [0 0 0  1 0 0  2 0 0  0 1 0  1 1 0  2 1 0  0 2 0  1 2 0  2 2 0]\n";

TEST(Rib, TrimCurveTrimsTheNuPatchesThatFollowInItsBlock) {
  const Scene s = Parse(World(std::string("AttributeBegin\n") + kTrimTriangle + kSquare +
                              "Attribute \"trimcurve\" \"sense\" \"outside\"\n" + kSquare + "AttributeEnd\n" + kSquare));
  // "inside" (the default) keeps the triangle alone: the one piece it lies in. "outside"
  // keeps all four pieces, the first with the triangle cut from it; after the block, none
  // is trimmed.
  ASSERT_EQ(s.surfaces.size(), 1u + 4u + 4u);
  const Vec2 inTriangle(0.3, 0.3), outside(0.8, 0.8);  // in the first piece's own (u,v)
  const PieceTrim* kept = TrimOf(s.surfaces[0]);
  ASSERT_NE(kept, nullptr);
  EXPECT_TRUE(kept->Kept(inTriangle));
  EXPECT_FALSE(kept->Kept(outside));
  const PieceTrim* cut = TrimOf(s.surfaces[1]);
  ASSERT_NE(cut, nullptr);
  EXPECT_FALSE(cut->Kept(inTriangle));
  EXPECT_TRUE(cut->Kept(outside));
  for (std::size_t k = 2; k < s.surfaces.size(); ++k) EXPECT_EQ(TrimOf(s.surfaces[k]), nullptr) << k;
}

TEST(Rib, HeightFieldsTakeTheirXAndYFromTheParameters) {
  // "Pz": x and y of point (i, j) of an nu x nv grid are i / (nu - 1) and j / (nv - 1).
  // A bilinear patch of heights 0 0 0 1 is z = u v; a bicubic Bézier patch of heights
  // z_ij reproduces x = u and y = v (the Bernstein basis's linear precision); a bilinear
  // mesh of 3 x 2 heights is two patches.
  std::ostringstream heights;
  for (int j = 0; j < 4; ++j)
    for (int i = 0; i < 4; ++i) heights << (i == j ? 1 : 0) << ' ';
  const Scene s = Parse(World("Patch \"bilinear\" \"Pz\" [0 0 0 1]\nPatch \"bicubic\" \"Pz\" [" + heights.str() +
                              "]\nPatchMesh \"bilinear\" 3 \"nonperiodic\" 2 \"nonperiodic\" \"Pz\" [0 1 2 3 4 5]"));
  ASSERT_EQ(s.surfaces.size(), 4u);
  for (const double u : {0.0, 0.3, 1.0})
    for (const double v : {0.0, 0.7, 1.0}) {
      ExpectNear(At(s.surfaces[0], u, v), Vec3(u, v, u * v));
      const Vec3 p = At(s.surfaces[1], u, v);
      EXPECT_NEAR(p.x(), u, kPosTol);
      EXPECT_NEAR(p.y(), v, kPosTol);
    }
  ExpectNear(At(s.surfaces[2], 1, 1), Vec3(0.5, 1, 4));
  ExpectNear(At(s.surfaces[3], 1, 1), Vec3(1, 1, 5));
}

TEST(Rib, RationalPatchesAreRationalBezierPieces) {
  // Weights all 2: the same surface as the points divided by them, in any basis.
  std::vector<Vec4> doubled;
  for (int j = 0; j < 4; ++j)
    for (int i = 0; i < 4; ++i) doubled.emplace_back(2.0 * i, 2.0 * j, (i == 1 || i == 2) && (j == 1 || j == 2) ? 2.0 : 0.0, 2.0);
  // A rational Bézier patch with weights from 0.5 to 2.
  std::vector<Vec4> varied;
  std::vector<Vec3> plain;
  std::vector<double> weights;
  for (int j = 0; j < 4; ++j)
    for (int i = 0; i < 4; ++i) {
      const Vec3 p(i, j, std::sin(i + 2.0 * j));
      const double w = 0.5 + 0.1 * ((5 * i + 3 * j) % 16);
      plain.push_back(p);
      weights.push_back(w);
      varied.emplace_back(w * p.x(), w * p.y(), w * p.z(), w);
    }
  const Scene s = Parse(World("Basis \"b-spline\" 1 \"catmull-rom\" 1\nPatch \"bicubic\" \"P\" " + GridPoints(1) +
                              "\nPatch \"bicubic\" \"Pw\" " + Array(doubled) + "\nBasis \"bezier\" 3 \"bezier\" 3\n" +
                              "Patch \"bicubic\" \"Pw\" " + Array(varied) +
                              "\nPatch \"bilinear\" \"Pw\" [0 0 0 1  2 0 0 2  0 1 0 1  1 1 1 1]\n" +
                              "PatchMesh \"bicubic\" 4 \"nonperiodic\" 4 \"nonperiodic\" \"Pw\" " + Array(varied)));
  ASSERT_EQ(s.surfaces.size(), 5u);
  ASSERT_TRUE(std::holds_alternative<NurbsPiece>(s.surfaces[1].shape));
  for (const double u : {0.0, 0.4, 1.0})
    for (const double v : {0.0, 0.7, 1.0}) {
      ExpectNear(At(s.surfaces[1], u, v), At(s.surfaces[0], u, v));
      // sum B_i(u) B_j(v) w_ij P_ij / sum B_i(u) B_j(v) w_ij
      Vec3 num = Vec3::Zero();
      double den = 0.0;
      auto b = [](int i, double t) { return std::array{1.0, 3.0, 3.0, 1.0}[i] * std::pow(1 - t, 3 - i) * std::pow(t, i); };
      for (int j = 0; j < 4; ++j)
        for (int i = 0; i < 4; ++i) {
          const double c = b(i, u) * b(j, v) * weights[4 * j + i];
          num += c * plain[4 * j + i];
          den += c;
        }
      ExpectNear(At(s.surfaces[2], u, v), num / den);
      ExpectNear(At(s.surfaces[4], u, v), num / den);
    }
  // The bilinear one: ((1-u) 0 + u 2 * 2/2 ...) at (0.5, 0): (0 + 2) / (1 + 2) along x.
  ExpectNear(At(s.surfaces[3], 0.5, 0), Vec3(2.0 / 3.0, 0, 0));
}

TEST(Rib, PatchesInEveryBasisAndBilinear) {
  const Scene s = Parse(World(
      "Patch \"bicubic\" \"P\" " + GridPoints(1) + "\n" +
      "Basis \"b-spline\" 1 \"catmull-rom\" 1\nPatch \"bicubic\" \"P\" " + GridPoints(1) + "\n" +
      "Basis [-1 3 -3 1  3 -6 3 0  -3 3 0 0  1 0 0 0] 3 \"bezier\" 3\nPatch \"bicubic\" \"P\" " + GridPoints(1) + "\n" +
      "Patch \"bilinear\" \"P\" [0 0 0  1 0 0  0 1 0  1 1 1]"));
  ASSERT_EQ(s.surfaces.size(), 4u);
  // Bézier: corners interpolated, the centre at 9/16 of the bump (weights (3/8)^2 * 4).
  ExpectNear(At(s.surfaces[0], 0, 0), Vec3(0, 0, 0));
  ExpectNear(At(s.surfaces[0], 1, 1), Vec3(3, 3, 0));
  ExpectNear(At(s.surfaces[0], 0.5, 0.5), Vec3(1.5, 1.5, 0.5625));
  // B-spline in u (weights 1/6, 2/3, 1/6 at t = 0) and Catmull-Rom in v (through G1 at
  // t = 0): at (0, 0) x = 1, y = 1, z = (2/3 + 1/6) of the bump (row j = 1 only).
  ExpectNear(At(s.surfaces[1], 0, 0), Vec3(1, 1, 5.0 / 6.0));
  // The explicit Bézier matrix gives the Bézier patch.
  ExpectNear(At(s.surfaces[2], 0.3, 0.7), At(s.surfaces[0], 0.3, 0.7));
  ExpectNear(At(s.surfaces[3], 0.5, 0.5), Vec3(0.5, 0.5, 0.25));
}

TEST(Rib, PatchMeshPeriodicAndNonperiodic) {
  // A 7 x 4 nonperiodic Bézier mesh (step 3): 2 x 1 patches sharing the column x = 3.
  std::vector<Vec3> grid;
  for (int j = 0; j < 4; ++j)
    for (int i = 0; i < 7; ++i) grid.emplace_back(i, j, 0);
  const std::string p7 = Array(grid);
  // A 4 x 2 periodic bilinear mesh (a band closed in u): 4 x 2 patches.
  std::vector<Vec3> bandPoints;
  for (int j = 0; j < 2; ++j)
    for (int i = 0; i < 4; ++i) bandPoints.emplace_back(std::cos(i * kPi / 2), std::sin(i * kPi / 2), j);
  const std::string band = Array(bandPoints);
  // A 6 x 4 periodic b-spline mesh in u (step 1): 6 patches.
  std::vector<Vec3> ringPoints;
  for (int j = 0; j < 4; ++j)
    for (int i = 0; i < 6; ++i) ringPoints.emplace_back(std::cos(i * kPi / 3), std::sin(i * kPi / 3), j);
  const std::string ring = Array(ringPoints);
  const Scene s = Parse(World("PatchMesh \"bicubic\" 7 \"nonperiodic\" 4 \"nonperiodic\" \"P\" " + p7 + "\n" +
                              "PatchMesh \"bilinear\" 4 \"periodic\" 2 \"periodic\" \"P\" " + band + "\n" +
                              "Basis \"b-spline\" 1 \"b-spline\" 1\n" +
                              "PatchMesh \"bicubic\" 6 \"periodic\" 4 \"nonperiodic\" \"P\" " + ring));
  ASSERT_EQ(s.surfaces.size(), 2u + 8u + 6u);
  ExpectNear(At(s.surfaces[0], 1, 0), Vec3(3, 0, 0));
  ExpectNear(At(s.surfaces[1], 0, 0), Vec3(3, 0, 0));
  ExpectNear(At(s.surfaces[1], 1, 1), Vec3(6, 3, 0));
  // The band's last patch in u joins its first: u = 1 of patch 3 is u = 0 of patch 0.
  ExpectNear(At(s.surfaces[2 + 3], 1, 0), At(s.surfaces[2], 0, 0));
  // The ring's patches join with continuity around the closed direction.
  for (int k = 0; k < 6; ++k)
    ExpectNear(At(s.surfaces[10 + k], 1, 0.5), At(s.surfaces[10 + (k + 1) % 6], 0, 0.5), 1e-12);
  EXPECT_EQ(Error(World("PatchMesh \"bicubic\" 5 \"nonperiodic\" 4 \"nonperiodic\" \"P\" [" + std::string(60, ' ') + "]")),
            "t.rib:2: PatchMesh: \"P\" expects 60 numbers (20 points), found 0");
}

// RenderMan Interface 3.2, "Quadrics": each surface at (u, v) from the formulas.
TEST(Rib, QuadricParametersFollowTheSpecification) {
  struct Case {
    std::string rib;
    std::function<Vec3(double, double)> formula;
  };
  std::vector<Case> cases;
  for (const std::array<double, 3>& limits : std::vector<std::array<double, 3>>{{-2, 2, 360}, {-1, 1.5, 270}, {0.5, 1.9, 90}, {-2, 0, -120}}) {
    // Named, not bound: a lambda may not capture a structured binding (clang 14).
    const double zmin = limits[0], zmax = limits[1], tmax = limits[2];
    const double r = 2;
    const double pmin = std::asin(std::clamp(zmin / r, -1.0, 1.0)), pmax = std::asin(std::clamp(zmax / r, -1.0, 1.0));
    cases.push_back({"Sphere 2 " + std::to_string(zmin) + " " + std::to_string(zmax) + " " + std::to_string(tmax),
                     [=](double u, double v) {
                       const double t = u * tmax * kRad, p = pmin + v * (pmax - pmin);
                       return Vec3(r * std::cos(t) * std::cos(p), r * std::sin(t) * std::cos(p), r * std::sin(p));
                     }});
    cases.push_back({"Cylinder 1.5 " + std::to_string(zmin) + " " + std::to_string(zmax) + " " + std::to_string(tmax),
                     [=](double u, double v) {
                       const double t = u * tmax * kRad;
                       return Vec3(1.5 * std::cos(t), 1.5 * std::sin(t), zmin + v * (zmax - zmin));
                     }});
    cases.push_back({"Cone 3 1.25 " + std::to_string(tmax), [=](double u, double v) {
                       const double t = u * tmax * kRad;
                       return Vec3(1.25 * (1 - v) * std::cos(t), 1.25 * (1 - v) * std::sin(t), 3 * v);
                     }});
    cases.push_back({"Disk 0.5 2 " + std::to_string(tmax), [=](double u, double v) {
                       const double t = u * tmax * kRad;
                       return Vec3(2 * (1 - v) * std::cos(t), 2 * (1 - v) * std::sin(t), 0.5);
                     }});
    cases.push_back({"Paraboloid 1.5 0.25 2 " + std::to_string(tmax), [=](double u, double v) {
                       const double t = u * tmax * kRad, z = 0.25 + v * 1.75, rr = 1.5 * std::sqrt(z / 2);
                       return Vec3(rr * std::cos(t), rr * std::sin(t), z);
                     }});
    cases.push_back({"Hyperboloid 1 0 -1  0.5 1 1 " + std::to_string(tmax), [=](double u, double v) {
                       const double t = u * tmax * kRad;
                       const Vec3 p = Vec3(1, 0, -1) + v * Vec3(-0.5, 1, 2);
                       return Vec3(p.x() * std::cos(t) - p.y() * std::sin(t), p.x() * std::sin(t) + p.y() * std::cos(t), p.z());
                     }});
    cases.push_back({"Torus 3 0.5 " + std::to_string(zmin * 45) + " " + std::to_string(zmax * 90) + " " + std::to_string(tmax),
                     [=](double u, double v) {
                       const double t = u * tmax * kRad, p = (zmin * 45 + v * (zmax * 90 - zmin * 45)) * kRad;
                       const double rr = 3 + 0.5 * std::cos(p);
                       return Vec3(rr * std::cos(t), rr * std::sin(t), 0.5 * std::sin(p));
                     }});
  }
  for (const Case& c : cases) {
    const Scene s = Parse(World(c.rib));
    ASSERT_EQ(s.surfaces.size(), 1u) << c.rib;
    for (double u : {0.0, 0.3, 1.0})
      for (double v : {0.0, 0.6, 1.0}) {
        SCOPED_TRACE(c.rib + " at u " + std::to_string(u) + " v " + std::to_string(v));
        ExpectNear(At(s.surfaces[0], u, v), c.formula(u, v), 1e-9);
      }
  }
}

TEST(Rib, GeometryTeapotIsTheUtahTeapot) {
  const Scene s = Parse(World("Geometry \"teapot\""));
  ASSERT_EQ(s.surfaces.size(), 32u);
  const Bounds3 b = s.WorldBounds();
  EXPECT_NEAR(b.lo.z(), 0.0, 1e-12);
  EXPECT_NEAR(b.hi.z(), 3.15, 1e-12);
}

// ---- appearance ----

TEST(Rib, ColourOpacityAndTheStandardShaders) {
  const Scene s = Parse(World(
      "Color 0.5 0.25 1\nOpacity [0.5 0.5 0.5]\nSphere 1 -1 1 360\n"
      "Surface \"matte\" \"Kd\" [0.7]\nSphere 1 -1 1 360\n"
      "Surface \"plastic\" \"uniform float roughness\" 0.2 \"specularcolor\" [1 0 0]\nSphere 1 -1 1 360\n"
      "Surface \"metal\" \"Ks\" [0.9]\nSphere 1 -1 1 360\n"
      "Surface \"constant\"\nSphere 1 -1 1 360\n"
      "Surface \"paintedplastic\" \"texturename\" \"grid.tx\"\nSphere 1 -1 1 360\n"
      "Surface \"wood\"\nSphere 1 -1 1 360"));
  ASSERT_EQ(s.surfaces.size(), 7u);
  const auto look = [&](int k) { return s.appearances[s.appearanceOf[k]]; };
  using S = Appearance::Shader;
  EXPECT_EQ(look(0).colour, Vec3(0.5, 0.25, 1));
  EXPECT_EQ(look(0).opacity, Vec3(0.5, 0.5, 0.5));
  EXPECT_EQ(look(0).shader, S::Default);
  EXPECT_EQ(look(1).shader, S::Matte);
  EXPECT_EQ(look(1).kd, 0.7);
  EXPECT_EQ(look(1).ka, 1.0);
  EXPECT_EQ(look(2).shader, S::Plastic);
  EXPECT_EQ(look(2).roughness, 0.2);
  EXPECT_EQ(look(2).specularColour, Vec3(1, 0, 0));
  EXPECT_EQ(look(2).kd, 0.5);
  EXPECT_EQ(look(3).shader, S::Metal);
  EXPECT_EQ(look(3).ks, 0.9);
  EXPECT_EQ(look(4).shader, S::Constant);
  EXPECT_EQ(look(5).shader, S::PaintedPlastic);
  EXPECT_EQ(look(5).textureName, "grid.tx");  // relative to the scene file's directory
  EXPECT_EQ(look(6).shader, S::Default);
  ASSERT_EQ(s.warnings.size(), 1u);
  EXPECT_EQ(s.warnings[0], "t.rib:15: Surface: unknown shader 'wood': the default material is used");
}

TEST(Rib, BumpyDisplacementIsABumpMap) {
  const Scene s = Parse(World(
      "Attribute \"displacementbound\" \"sphere\" [0.1] \"coordinatesystem\" [\"shader\"]\n"
      "Displacement \"bumpy\" \"Km\" [2] \"amplitude\" [0.25] \"texturename\" \"h.tx\"\nSphere 1 -1 1 360\n"
      "AttributeBegin\nDisplacement \"bumpy\"\nSphere 1 -1 1 360\nAttributeEnd\n"
      "Sphere 1 -1 1 360\nDisplacement \"dented\"\nSphere 1 -1 1 360"));
  ASSERT_EQ(s.surfaces.size(), 4u);
  const auto look = [&](int k) { return s.appearances[s.appearanceOf[k]]; };
  EXPECT_EQ(look(0).bumpName, "h.tx");  // relative to the scene file's directory
  EXPECT_EQ(look(0).bumpScale, 0.5);    // Km times amplitude
  EXPECT_EQ(look(1).bumpName, "");      // bumpy without a texture: no bump
  EXPECT_EQ(look(2).bumpName, "h.tx");  // the attribute block restored it
  EXPECT_EQ(look(3).bumpName, "");
  EXPECT_EQ(s.warnings, std::vector<std::string>{
                            "t.rib:10: Displacement: unknown shader 'dented': the surface is not displaced"});
  EXPECT_EQ(Error(World("Attribute \"displacementbound\" \"sphere\" [-1]")),
            "t.rib:2: Attribute \"displacementbound\" \"sphere\" must be 0 or more");
  EXPECT_EQ(Parse(World("Attribute \"displacementbound\" \"radius\" [1]\nSphere 1 -1 1 360")).warnings,
            std::vector<std::string>{"t.rib:2: Attribute: parameter \"radius\" is not supported here: ignored"});
}

TEST(Rib, ShinyMetalAndMakeLatLongEnvironment) {
  const Scene s = Parse("MakeLatLongEnvironment \"sky.exr\" \"sky.tx\" \"gaussian\" 1 1\n"
                        "MakeShadow \"key.z\" \"key.shd\"\n" +
                        World("Surface \"shinymetal\" \"Kr\" [0.4] \"Ks\" [0.8] \"texturename\" \"sky.tx\"\n"
                              "Sphere 1 -1 1 360\nSurface \"metal\"\nSphere 1 -1 1 360"));
  ASSERT_EQ(s.surfaces.size(), 2u);
  const auto look = [&](int k) { return s.appearances[s.appearanceOf[k]]; };
  EXPECT_EQ(look(0).shader, Appearance::Shader::ShinyMetal);
  EXPECT_EQ(look(0).kr, 0.4);
  EXPECT_EQ(look(0).ks, 0.8);
  EXPECT_EQ(look(0).environmentName, "sky.tx");  // as given: where MakeLatLongEnvironment writes it
  EXPECT_EQ(look(1).shader, Appearance::Shader::Metal);
  EXPECT_EQ(look(1).environmentName, "");
  ASSERT_EQ(s.makeTextures.size(), 2u);
  EXPECT_EQ(s.makeTextures[0].kind, SceneMakeTexture::Kind::LatLong);
  EXPECT_EQ(s.makeTextures[0].input, "sky.exr");  // beside the scene file
  EXPECT_EQ(s.makeTextures[0].output, "sky.tx");
  EXPECT_EQ(s.makeTextures[1].kind, SceneMakeTexture::Kind::Shadow);
  EXPECT_TRUE(s.warnings.empty());
}

TEST(Rib, MakeCubeFaceEnvironment) {
  const Scene s = Parse("MakeCubeFaceEnvironment \"a\" \"b\" \"c\" \"d\" \"e\" \"f\" \"env.tx\" 95 \"gaussian\" 2 2\n" +
                        World("Sphere 1 -1 1 360"));
  ASSERT_EQ(s.makeTextures.size(), 1u);
  const SceneMakeTexture& m = s.makeTextures[0];
  EXPECT_EQ(m.kind, SceneMakeTexture::Kind::CubeFace);
  EXPECT_EQ(m.faces, (std::array<std::string, 6>{"a", "b", "c", "d", "e", "f"}));  // beside the scene file
  EXPECT_EQ(m.input, "a");
  EXPECT_EQ(m.output, "env.tx");
  EXPECT_EQ(m.fovDeg, 95);
  EXPECT_TRUE(s.warnings.empty());
  EXPECT_EQ(Error("MakeCubeFaceEnvironment \"a\" \"b\" \"c\" \"d\" \"e\" \"f\" \"env.tx\" 60 \"box\" 1 1\n"),
            "t.rib:1: MakeCubeFaceEnvironment: the field of view must be at least 90 and less than 180 degrees");
  EXPECT_EQ(Error("MakeCubeFaceEnvironment \"a\" \"b\" \"c\" \"d\" \"e\" \"f\" \"env.tx\"\n"),
            "t.rib:1: MakeCubeFaceEnvironment expects the faces' field of view as argument 8");
  EXPECT_EQ(Error("MakeCubeFaceEnvironment \"a\" \"b\" \"c\" \"d\" \"e\" 1 \"env.tx\" 90\n"),
            "t.rib:1: MakeCubeFaceEnvironment expects a string as argument 6");
}

TEST(Rib, LightSourcesInWorldSpace) {
  const Scene s = Parse(
      "Translate 0 0 10\n"
      "LightSource \"pointlight\" 9 \"from\" [0 0 0]\n" +  // in the space being made world space
      World("LightSource \"ambientlight\" 1 \"intensity\" 0.2 \"lightcolor\" [1 0.5 0]\n"
            "LightSource \"distantlight\" 2 \"from\" [0 0 1] \"to\" [0 0 0]\n"
            "Translate 1 2 3\n"
            "LightSource \"pointlight\" \"key\" \"intensity\" [5] \"from\" [1 0 0]\n"
            "LightSource \"spotlight\" 4 \"coneangle\" 0.5 \"conedeltaangle\" 0.1 \"beamdistribution\" 3 \"to\" [0 0 -1]\n"
            "LightSource \"arealight\" 5"));
  ASSERT_EQ(s.lights.size(), 5u);
  using K = SceneLight::Kind;
  EXPECT_EQ(s.lights[0].kind, K::Point);
  ExpectNear(s.lights[0].from, Vec3(0, 0, 0));
  EXPECT_EQ(s.lights[1].kind, K::Ambient);
  ExpectNear(s.lights[1].colour, Vec3(0.2, 0.1, 0));
  EXPECT_EQ(s.lights[2].kind, K::Distant);
  ExpectNear(s.lights[2].to - s.lights[2].from, Vec3(0, 0, -1));
  EXPECT_EQ(s.lights[3].kind, K::Point);
  ExpectNear(s.lights[3].from, Vec3(2, 2, 3));
  ExpectNear(s.lights[3].colour, Vec3(5, 5, 5));
  EXPECT_EQ(s.lights[4].kind, K::Spot);
  ExpectNear(s.lights[4].from, Vec3(1, 2, 3));
  ExpectNear(s.lights[4].to, Vec3(1, 2, 2));
  EXPECT_EQ(s.lights[4].coneAngle, 0.5);
  EXPECT_EQ(s.lights[4].coneDelta, 0.1);
  EXPECT_EQ(s.lights[4].beamDistribution, 3.0);
  ASSERT_EQ(s.warnings.size(), 1u);
  EXPECT_EQ(s.warnings[0], "t.rib:9: LightSource: unknown light shader 'arealight': skipped");
}

// Option "shadow" "bias" is the bias of the shadow lights after it that give none; Hider
// "hidden" "depthfilter" how depth maps are filtered (min by default, as in RenderMan).
TEST(Rib, ShadowBiasOptionAndDepthFilter) {
  EXPECT_EQ(Parse(World("Sphere 1 -1 1 360")).image.depthFilter, "min");
  const Scene s = Parse("Hider \"hidden\" \"depthfilter\" \"midpoint\"\n"
                        "LightSource \"shadowspot\" 1 \"shadowname\" [\"a.shd\"]\n"
                        "Option \"shadow\" \"bias\" [0.25]\n"
                        "Option \"limits\" \"bucketsize\" [16 16]\n" +
                        World("LightSource \"shadowspot\" 2 \"shadowname\" [\"a.shd\"]\n"
                              "LightSource \"shadowspot\" 3 \"shadowname\" [\"a.shd\"] \"bias\" [0.5]"));
  EXPECT_EQ(s.image.depthFilter, "midpoint");
  ASSERT_EQ(s.lights.size(), 3u);
  EXPECT_EQ(s.lights[0].shadowBias, kDefaultShadowBias);
  EXPECT_EQ(s.lights[1].shadowBias, 0.25);
  EXPECT_EQ(s.lights[2].shadowBias, 0.5);
  ASSERT_EQ(s.warnings.size(), 1u);
  EXPECT_EQ(s.warnings[0], "t.rib:4: Option 'limits' is not supported here: skipped");
  const Scene bad = Parse("Hider \"hidden\" \"depthfilter\" \"median\"\n" + World("Sphere 1 -1 1 360"));
  EXPECT_EQ(bad.image.depthFilter, "min");
  ASSERT_EQ(bad.warnings.size(), 1u);
  EXPECT_EQ(bad.warnings[0], "t.rib:1: Hider: depthfilter 'median' is not min, max, average or midpoint: min is used");
}

// ---- what is skipped, and what is refused ----

TEST(Rib, ObjectInstancesReplayTheirObjectUnderTheCurrentState) {
  // An object of two surfaces (one in a block of its own, coloured and moved there),
  // defined before the world, and one defined in it by name; instanced under transforms
  // and colours. The object's own state changes stay inside each instance.
  const Scene s = Parse(
      "ObjectBegin 7\nSphere 1 -1 1 360\nAttributeBegin\nColor [0 0 1]\nTranslate 0 0 5\nDisk 0 1 360\n"
      "AttributeEnd\nObjectEnd\n" +
      World("ObjectBegin \"pair\"\nObjectInstance 7\nTranslate 10 0 0\nObjectInstance 7\nObjectEnd\n"
            "Color [1 0 0]\nAttributeBegin\nTranslate 0 3 0\nObjectInstance 7\nAttributeEnd\n"
            "Translate 0 0 -2\nObjectInstance \"pair\"\nSphere 0.5 -0.5 0.5 360"));
  ASSERT_EQ(s.surfaces.size(), 2u + 4u + 1u);
  auto origin = [&](std::size_t k) { return Vec3(s.surfaces[k].worldFromObject.translation()); };
  ExpectNear(origin(0), Vec3(0, 3, 0));
  ExpectNear(origin(1), Vec3(0, 3, 5));
  ExpectNear(origin(2), Vec3(0, 0, -2));
  ExpectNear(origin(3), Vec3(0, 0, 3));
  ExpectNear(origin(4), Vec3(10, 0, -2));
  ExpectNear(origin(5), Vec3(10, 0, 3));
  ExpectNear(origin(6), Vec3(0, 0, -2));  // the pair's Translate stayed inside it
  ASSERT_EQ(s.appearanceOf.size(), s.surfaces.size());
  for (std::size_t k : {0u, 2u, 4u, 6u}) EXPECT_EQ(s.appearances[s.appearanceOf[k]].colour, Vec3(1, 0, 0)) << k;
  for (std::size_t k : {1u, 3u, 5u}) EXPECT_EQ(s.appearances[s.appearanceOf[k]].colour, Vec3(0, 0, 1)) << k;
}

// ---- polygons ----

// The vertices of one polygon mesh, by position.
const PolygonVertex* VertexAt(const ScenePolygons& p, const Vec3& at) {
  for (const PolygonVertex& v : p.mesh.vertices)
    if ((v.position - at).norm() < kPosTol) return &v;
  return nullptr;
}

TEST(Rib, PolygonsOfEveryRequestAreTriangulatedInWorldSpace) {
  const Scene s = Parse(World(
      "Translate 10 0 0\n"
      "Polygon \"P\" [0 0 0  2 0 0  2 1 0  0 1 0] \"Cs\" [1 0 0  0 1 0  0 0 1  1 1 1]\n"
      "GeneralPolygon [4 3] \"P\" [0 0 0  4 0 0  4 4 0  0 4 0  1 1 0  1 2 0  2 1 0]\n"
      "PointsPolygons [3 3] [0 1 2  0 2 3] \"P\" [0 0 1  1 0 1  1 1 1  0 1 1] \"uniform color Cs\" [1 0 0  0 0 1]\n"
      "PointsGeneralPolygons [2] [4 3] [0 1 2 3 4 5 6] \"P\" [0 0 0  4 0 0  4 4 0  0 4 0  1 1 0  1 2 0  2 1 0] "
      "\"st\" [0 0  1 0  1 1  0 1  0.25 0.25  0.25 0.5  0.5 0.25]"));
  ASSERT_EQ(s.polygons.size(), 4u);
  EXPECT_TRUE(s.surfaces.empty());
  // One appearance id per request, after the surfaces'.
  EXPECT_EQ(s.appearanceOf.size(), 4u);
  EXPECT_EQ(s.Ids(), 4u);
  EXPECT_EQ(s.polygons[0].line, 3);
  EXPECT_EQ(s.polygons[0].file, "t.rib");
  // A quad is two triangles; a square with a triangular hole 4 + 3 + 2 - 2 = 7.
  EXPECT_EQ(s.polygons[0].mesh.triangles.size(), 2u);
  EXPECT_EQ(s.polygons[1].mesh.triangles.size(), 7u);
  EXPECT_EQ(s.polygons[2].mesh.triangles.size(), 2u);
  EXPECT_EQ(s.polygons[3].mesh.triangles.size(), 7u);
  // Positions in world space; "Cs" per point; the polygon's own normal, unit.
  const PolygonVertex* v = VertexAt(s.polygons[0], Vec3(12, 1, 0));
  ASSERT_NE(v, nullptr);
  EXPECT_EQ(v->colour, Vec3(0, 0, 1));
  EXPECT_NEAR(std::abs(v->normal.z()), 1.0, 1e-15);
  // "uniform color Cs": per face, so the shared point 0 has a colour per face.
  int red = 0, blue = 0;
  for (const PolygonVertex& c : s.polygons[2].mesh.vertices) {
    red += c.colour == Vec3(1, 0, 0);
    blue += c.colour == Vec3(0, 0, 1);
  }
  EXPECT_EQ(red, 3);
  EXPECT_EQ(blue, 3);
  // "st" per point, and every triangle index in range.
  v = VertexAt(s.polygons[3], Vec3(11, 2, 0));
  ASSERT_NE(v, nullptr);
  EXPECT_EQ(v->st, Vec2(0.25, 0.5));
  for (const ScenePolygons& p : s.polygons)
    for (const auto& t : p.mesh.triangles)
      for (const std::uint32_t k : t) EXPECT_LT(k, p.mesh.vertices.size());
  // The world box holds the polygons.
  const Bounds3 b = s.WorldBounds();
  EXPECT_EQ(b.lo, Vec3(10, 0, 0));
  EXPECT_EQ(b.hi, Vec3(14, 4, 1));
}

TEST(Rib, PolygonNormalsFollowTheTransformAndFaceVaryingColours) {
  // A scale that is not uniform: normals transform by the inverse transpose.
  const Scene s = Parse(World(
      "Scale 2 1 1\n"
      "PointsPolygons [3] [0 1 2] \"P\" [0 0 0  1 0 0  0 1 0] \"N\" [1 0 1  1 0 1  1 0 1] "
      "\"facevarying color Cs\" [1 0 0  0 1 0  0 0 1]"));
  ASSERT_EQ(s.polygons.size(), 1u);
  for (const PolygonVertex& v : s.polygons[0].mesh.vertices)
    EXPECT_LT((v.normal - Vec3(0.5, 0, 1).normalized()).norm(), 1e-15);
  const PolygonVertex* v = VertexAt(s.polygons[0], Vec3(2, 0, 0));
  ASSERT_NE(v, nullptr);
  EXPECT_EQ(v->colour, Vec3(0, 1, 0));
}

TEST(Rib, PolygonsInObjectsAndWithoutArea) {
  const Scene s = Parse(World("ObjectBegin 1\nPolygon \"P\" [0 0 0 1 0 0 0 1 0]\nObjectEnd\n"
                              "ObjectInstance 1\nTranslate 5 0 0\nObjectInstance 1\n"
                              "Polygon \"P\" [0 0 0 1 0 0 2 0 0]"));
  // The instances are two meshes; the polygon without area shows nothing and is dropped.
  ASSERT_EQ(s.polygons.size(), 2u);
  EXPECT_NE(VertexAt(s.polygons[1], Vec3(6, 0, 0)), nullptr);
}

TEST(Rib, SkippedKindsAreCounted) {
  const Scene s = Parse(World("Blobby 0 [] [] []\nSphere 1 -1 1 360\nBlobby 0 [] [] []\nBlobby 0 [] [] []"));
  EXPECT_EQ(s.warnings, std::vector<std::string>{"t.rib:2: Blobby is not supported here: skipped (3 times)"});
}

TEST(Rib, EverythingElseIsSkippedWithOneWarningPerKind) {
  const Scene s = Parse(
      "Option \"searchpath\" \"shader\" [\"@\"]\nHider \"raytrace\"\nDeclare \"foo\" \"float\"\n" +
      World("Attribute \"identifier\" \"name\" [\"a\"]\nAttribute \"visibility\" \"int camera\" [1]\n"
            "Displacement \"bumpy\"\nMakeTexture \"a\" \"b\"\nPolygon \"P\" [0 0 0 1 0 0 0 1 0] \"Os\" [1 1 1]\n"
            "FooBar 1 2 3\nSphere 1 -1 1 360 \"Cs\" [1 0 0]\n"
            "Points \"P\" [0 0 0]\nBlobby 0 [] [] []"));
  EXPECT_EQ(s.surfaces.size(), 1u);
  EXPECT_EQ(s.polygons.size(), 1u);
  const std::vector<std::string> want = {
      "t.rib:1: Option 'searchpath' is not supported here: skipped",
      "t.rib:2: Hider 'raytrace' is not supported here: the scan-line hider is used",
      "t.rib:3: Declare is not supported here: skipped",
      "t.rib:5: Attribute 'identifier' is not supported here: skipped",
      "t.rib:6: Attribute 'visibility' is not supported here: skipped",
      "t.rib:8: MakeTexture is not supported here: skipped",
      "t.rib:9: Polygon: parameter \"Os\" is not supported here: ignored",
      "t.rib:10: unknown request 'FooBar': skipped",
      "t.rib:11: Sphere: parameter \"Cs\" is not supported here: ignored",
      "t.rib:12: Points is not supported here: skipped",
      "t.rib:13: Blobby is not supported here: skipped"};
  EXPECT_EQ(s.warnings, want);
}

TEST(Rib, MalformedScenesAreAnsweredWithFileAndLine) {
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"WorldBegin\nAttributeBegin\nSphere 1 -1 1 360\nWorldEnd\n", "t.rib:4: WorldEnd closes AttributeBegin at line 2"},
      {"WorldBegin\nAttributeEnd\nWorldEnd\n", "t.rib:2: AttributeEnd closes WorldBegin at line 1"},
      {"AttributeEnd\nWorldBegin\nWorldEnd\n", "t.rib:1: AttributeEnd without AttributeBegin"},
      {"WorldBegin\nAttributeBegin\n", "t.rib:2: AttributeBegin is never closed"},
      {"WorldBegin\nSphere 1 -1 1 360\n", "t.rib:1: WorldBegin is never closed"},
      {"FrameBegin 1\nWorldBegin\nWorldEnd\n", "t.rib:1: FrameBegin is never closed"},
      {"Sphere 1 -1 1 360\n", "t.rib:1: Sphere outside WorldBegin/WorldEnd"},
      {"Format 10 10 1\n", "t.rib: no WorldBegin: a RIB scene needs a world block"},
      {World("Sphere 1 -1 1"), "t.rib:2: Sphere expects 4 numbers, found 3"},
      {World("Sphere [1 -1 1 360 5]"), "t.rib:2: Sphere expects 4 numbers, found 5"},
      {World("Sphere 0 -1 1 360"), "t.rib:2: Sphere: the radius must be positive"},
      {World("Sphere 1 -1 1 1e300"), "t.rib:2: Sphere: thetamax must be from -360 to 360 degrees"},
      {World("Torus 1 0.5 0 1e300 360"), "t.rib:2: Torus: phimin and phimax must be from -360 to 360 degrees"},
      {World("Patch \"bicubic\" \"P\" [0 0 0]"), "t.rib:2: Patch: \"P\" expects 48 numbers (16 points), found 3"},
      {World("Patch \"bilinear\" \"Pw\" [0 0 0 1 1 0 0 1 0 1 0 1 1 1 0 0]"),
       "t.rib:2: Patch: point 3 of \"Pw\" has weight 0 (weights are positive)"},
      {World("Patch \"bilinear\" \"P\" [0 0 0 1 0 0 0 1 0 1 1 0] \"Pw\" [0 0 0 1 1 0 0 1 0 1 0 1 1 1 0 1]"),
       "t.rib:2: Patch: more than one of \"P\", \"Pw\" and \"Pz\": give one"},
      {World("NuPatch 2 2 [0 0 1 1] 0 1 2 2 [0 0 1 1] 0 1 \"Pz\" [0 0 0 1]"),
       "t.rib:2: NuPatch: \"Pz\" (height fields) is for Patch and PatchMesh; give \"P\""},
      {World("Patch \"bilinear\" \"Pz\" [0 0 0]"), "t.rib:2: Patch: \"Pz\" expects 4 numbers (4 points), found 3"},
      {World("SubdivisionMesh \"catmull-clark\" [3] [0 1 2] \"Pw\" [0 0 0 1 1 0 0 1 0 1 0 1]"),
       "t.rib:2: SubdivisionMesh: \"Pw\" (rational points) is not supported here; give \"P\""},
      {World("NuPatch 2 2 [0 0 1 1] 0 1 2 2 [0 0 1 1] 0 1"),
       "t.rib:2: NuPatch: no \"P\" or \"Pw\""},
      {World("NuPatch 2 2 [0 0 1 1] 0 1 2 2 [0 0 1 1]"),
       "t.rib:2: NuPatch expects nu uorder uknot umin umax nv vorder vknot vmin vmax, then \"P\" or \"Pw\""},
      {World("NuPatch 2 2 [0 1 1] 0 1 2 2 [0 0 1 1] 0 1 \"P\" [0 0 0 1 0 0 0 1 0 1 1 0]"),
       "t.rib:2: NuPatch: uknot has 3 values, nu + uorder = 4"},
      {World("NuPatch 2.5 2 [0 0 1 1] 0 1 2 2 [0 0 1 1] 0 1 \"P\" [0 0 0 1 0 0 0 1 0 1 1 0]"),
       "t.rib:2: NuPatch: nu is a whole number from 1 to 10000000"},
      {World("NuPatch 2 2 [0 0 1 1] 0 1 2 2 [0 0 1 1] 0 2 \"P\" [0 0 0 1 0 0 0 1 0 1 1 0]"),
       "t.rib:2: NuPatch: vrange [0, 2] is not within the knots' [0, 1]"},
      {World("NuPatch 2 2 [0 0 1 1] [0 0] 1 2 2 [0 0 1 1] 0 1 \"P\" [0 0 0 1 0 0 0 1 0 1 1 0]"),
       "t.rib:2: NuPatch: umin is one number"},
      {World("TrimCurve [1] [2] [0 0 1 2 3 3] [0] [3] [4] [0.1 0.4 0.1 0.1] [0.1 0.1 0.4 0.1]"),
       "t.rib:2: TrimCurve expects 9 arrays: ncurves order knot min max n u v w"},
      {World("TrimCurve [1] [2] [0 0 1 2 3] [0] [3] [4] [0.1 0.4 0.1 0.1] [0.1 0.1 0.4 0.1] [1 1 1 1]"),
       "t.rib:2: TrimCurve: knot has 5 values, the curves' n + order add up to 6"},
      {World("TrimCurve [1] [2] [0 0 1 2 3 3] [0] [3] [4] [0.1 0.4 0.1 0.2] [0.1 0.1 0.4 0.1] [1 1 1 1]"),
       "t.rib:2: TrimCurve: loop 1 is not closed: a curve ends at (0.2, 0.1) and the next starts at (0.1, 0.1)"},
      {World("TrimCurve [1] [2] [0 0 1 2 3 3] [0] [3] [4] [0.1 0.4 0.1 0.1] [0.1 0.1 0.4 0.1] [1 1 -1 1]"),
       "t.rib:2: TrimCurve: loop 1, curve 1: control point 2 has weight -1 (weights are positive)"},
      {World("TrimCurve [0.5] [2] [0 0 1 2 3 3] [0] [3] [4] [0.1 0.4 0.1 0.1] [0.1 0.1 0.4 0.1] [1 1 1 1]"),
       "t.rib:2: TrimCurve: ncurves are whole numbers from 1"},
      {World("ObjectInstance 3"), "t.rib:2: ObjectInstance: no object '3' was defined"},
      {"ObjectBegin 1\nSphere 1 -1 1 360\n", "t.rib:1: ObjectBegin is never closed"},
      {"ObjectBegin 1\nWorldBegin\nWorldEnd\nObjectEnd\n",
       "t.rib:2: WorldBegin inside the object definition of ObjectBegin at t.rib:1"},
      {"ObjectBegin 1\nObjectBegin 2\nObjectEnd\nObjectEnd\n",
       "t.rib:2: ObjectBegin inside the object definition of ObjectBegin at t.rib:1"},
      {World("ObjectBegin 1\nAttributeBegin\nObjectEnd\nObjectInstance 1"),
       "t.rib:5: ObjectInstance: object '1' leaves AttributeBegin at t.rib:3 open"},
      {World("ObjectBegin 1\nSphere 1 -1 1 1e9\nObjectEnd\nObjectInstance 1"),
       "t.rib:3: Sphere: thetamax must be from -360 to 360 degrees"},
      {World("ObjectBegin 1\nObjectInstance 1\nObjectEnd\nObjectInstance 1"),
       "t.rib:3: ObjectInstance nested more than 16 deep (an object that instances itself?)"},
      {World("ObjectEnd"), "t.rib:2: ObjectEnd without ObjectBegin"},
      {World("ObjectBegin 1\nSphere 1 -1 1 360\nSphere 1 -1 1 360\nSphere 1 -1 1 360\nSphere 1 -1 1 360\nObjectEnd\n"
             "ObjectBegin 2\nObjectInstance 1\nObjectInstance 1\nObjectInstance 1\nObjectInstance 1\nObjectEnd\n"
             "ObjectBegin 3\nObjectInstance 2\nObjectInstance 2\nObjectInstance 2\nObjectInstance 2\nObjectEnd\n"
             "ObjectBegin 4\nObjectInstance 3\nObjectInstance 3\nObjectInstance 3\nObjectInstance 3\nObjectEnd\n"
             "ObjectBegin 5\nObjectInstance 4\nObjectInstance 4\nObjectInstance 4\nObjectInstance 4\nObjectEnd\n"
             "ObjectBegin 6\nObjectInstance 5\nObjectInstance 5\nObjectInstance 5\nObjectInstance 5\nObjectEnd\n"
             "ObjectBegin 7\nObjectInstance 6\nObjectInstance 6\nObjectInstance 6\nObjectInstance 6\nObjectEnd\n"
             "ObjectBegin 8\nObjectInstance 7\nObjectInstance 7\nObjectInstance 7\nObjectInstance 7\nObjectEnd\n"
             "ObjectBegin 9\nObjectInstance 8\nObjectInstance 8\nObjectInstance 8\nObjectInstance 8\nObjectEnd\n"
             "ObjectBegin 10\nObjectInstance 9\nObjectInstance 9\nObjectInstance 9\nObjectInstance 9\nObjectEnd\n"
             "ObjectInstance 10"),
       "t.rib:10: ObjectInstance: more than 1000000 requests replayed in all (instances of instances of ...)"},
      {World("Attribute \"trimcurve\" \"sense\" \"sideways\""),
       "t.rib:2: Attribute \"trimcurve\" \"sense\" is \"inside\" or \"outside\", not 'sideways'"},
      {World("NuPatch 2 2 [0 0 1 1] 0 1 2 2 [0 0 1 1] 0 1 \"Pw\" [0 0 0 1 1 0 0 1 0 1 0 1]"),
       "t.rib:2: NuPatch: \"Pw\" expects 16 numbers (4 points), found 12"},
      {World("Patch \"bicubic\""), "t.rib:2: Patch: no \"P\" or \"Pw\""},
      {World("Patch \"trilinear\" \"P\" [0 0 0]"), "t.rib:2: Patch: unknown type 'trilinear' (known: \"bilinear\", \"bicubic\")"},
      {World("Basis \"nurbs\" 3 \"bezier\" 3"),
       "t.rib:2: Basis: unknown basis 'nurbs' (known: bezier, b-spline, catmull-rom, hermite, power)"},
      {World("Basis [1 2 3] 3 \"bezier\" 3"), "t.rib:2: Basis: a basis matrix has 16 numbers, found 3"},
      {World("Basis \"bezier\" 0 \"bezier\" 3"), "t.rib:2: Basis: a step is a whole number from 1 to 4"},
      {World("Transform [1 0 0 0 0 1 0 0 0 0 1 0 0 0 0]"), "t.rib:2: Transform expects 16 numbers, found 15"},
      {World("Transform [1 0 0 1 0 1 0 0 0 0 1 0 0 0 0 1]"),
       "t.rib:2: Transform: projective matrices are not supported (the last column must be 0 0 0 1)"},
      {World("Color [1 0 0"), "t.rib:2: the array opened here is not closed before 'WorldEnd'"},
      {"WorldBegin\nColor [1 0", "t.rib:2: the array opened here is not closed"},
      {"WorldBegin\nSurface \"plastic", "t.rib:2: the string opened here is not closed"},
      {World("Color [1 [0] 0]"), "t.rib:2: arrays do not nest"},
      {World("Color 1 0 0]"), "t.rib:2: ']' without '['"},
      {World("Color [1 \"a\" 0]"), "t.rib:2: an array mixes numbers and strings"},
      {World("Translate 1e999 0 0"), "t.rib:2: number '1e999' is not finite"},
      {World("Translate 1x 0 0"), "t.rib:2: expected a number, found '1x'"},
      {"\x80\x01", "t.rib:1: expected a request name, found '?" "?'"},
      {World("Sphere \x80"), "t.rib:2: binary RIB is not supported (a byte above 0x7f)"},
      {World("Surface \"plastic\" \"Ks\""), "t.rib:2: Surface: the parameter list must be name-value pairs"},
      {World("Surface \"plastic\" \"Ks\" [1 2]"), "t.rib:2: Surface: parameter \"Ks\" expects 1 number"},
      {World("Surface \"plastic\" 0.5 \"Ks\""), "t.rib:2: Surface: expected a parameter name (a string)"},
      {World("LightSource \"spotlight\" 1 \"from\" [0 0 0] \"to\" [0 0 0]"),
       "t.rib:2: LightSource: \"from\" and \"to\" are the same point"},
      {World("PatchMesh \"bicubic\" 5 \"nonperiodic\" 4 \"sideways\" \"P\" []"),
       "t.rib:2: PatchMesh: wrap is \"periodic\" or \"nonperiodic\""},
      {"FrameBegin 1.5\nWorldBegin\nWorldEnd\nFrameEnd\n", "t.rib:1: FrameBegin: the frame number must be a whole number"},
      {"WorldBegin\nWorldBegin\n", "t.rib:2: WorldBegin inside WorldBegin at line 1"},
      {"ReadArchive \"no-such-file.rib\"\n", "t.rib:1: ReadArchive: no-such-file.rib: cannot open: No such file or directory"},
      {World("Polygon \"P\" [0 0 0 1 0 0]"), "t.rib:2: Polygon: a polygon has at least 3 points"},
      {World("Polygon \"P\" [0 0 0 1 0 0 0 1 0 1]"), "t.rib:2: Polygon: \"P\" expects 9 numbers (3 points), found 10"},
      {World("Polygon \"N\" [0 0 1]"), "t.rib:2: Polygon: no \"P\""},
      {World("GeneralPolygon [4 2] \"P\" [0 0 0]"),
       "t.rib:2: GeneralPolygon: loop sizes are whole numbers from 3 to 1000000000, found '2.000000'"},
      {World("PointsPolygons [3 3] [0 1 2] \"P\" [0 0 0 1 0 0 0 1 0]"),
       "t.rib:2: PointsPolygons: the loop sizes add up to 6, but 3 vertex indices are given"},
      {World("PointsPolygons [3] [0 1 5] \"P\" [0 0 0 1 0 0 0 1 0]"),
       "t.rib:2: PointsPolygons: \"P\" expects 18 numbers (6 points), found 9"},
      {World("PointsPolygons [3] [0 1 2] \"P\" [0 0 0 1 0 0 0 1 0] \"Cs\" [1 0]"),
       "t.rib:2: PointsPolygons: \"Cs\" expects 3 numbers per point (9), per corner (9), per face (3) or 3 in all, found 2"},
      {World("PointsPolygons [3] [0 1 2] \"P\" [0 0 0 1 0 0 0 1 0] \"facevarying float st\" [1 0]"),
       "t.rib:2: PointsPolygons: \"st\" expects 2 numbers per point (6), per corner (6), per face (2) or 2 in all, found 2"},
      {World("PointsGeneralPolygons [2] [3] [0 1 2] \"P\" [0 0 0 1 0 0 0 1 0]"),
       "t.rib:2: PointsGeneralPolygons: the loop counts add up to more than the 1 loop sizes given"},
      {World("PointsPolygons [3] \"P\" [0 0 0 1 0 0 0 1 0]"),
       "t.rib:2: PointsPolygons: expected vertex indices (an array of whole numbers) as argument 2"},
      {World("Polygon \"Pw\" [0 0 0 1 1 0 0 1 0 1 0 0]"), "t.rib:2: Polygon: \"Pw\" weights must be positive"},
  };
  for (const auto& [text, want] : cases) EXPECT_EQ(Error(text), want) << text;
}

TEST(RibCorpus, EveryMalformedFileGetsItsExactMessage) {
  test::ExpectCorpusMessages(PATCHSCAN_TESTS_DIR "/corpus/rib", ".rib", [](const std::string& path) { return ReadRib(path); });
}

// The RIB reader against a fixed budget of mutants of the scenes in surfaces/ and the
// malformed corpus (CI runs
// exactly this many, in the release and the sanitizer builds; PATCHSCAN_FUZZ_MUTANTS
// raises it): each is read or refused with a message located on a line of its text.
TEST(RibFuzz, MutantsAreReadOrRefusedWithALocatedMessage) {
  // The scenes of surfaces/ and the malformed corpus.
  std::vector<std::string> seeds;
  for (const char* dir : {PATCHSCAN_SURFACES_DIR, PATCHSCAN_TESTS_DIR "/corpus/rib"})
    for (const auto& e : std::filesystem::directory_iterator(dir))
      if (e.path().extension() == ".rib") seeds.push_back(test::Slurp(e.path()));
  ASSERT_GE(seeds.size(), 20u);
  const std::string alphabet = "0123456789.-+eE \n\r\t#[]\"\\xaA_\x01\xff";
  const std::vector<std::string> tokens = {
      "1e308", "-1e308", "1e-320", "nan", "inf", "-0", "0", "1", "99999999999", "10000000", "[", "]",
      "\"", "\"\"", "[]", "WorldBegin", "WorldEnd", "AttributeBegin", "AttributeEnd", "TransformEnd",
      "FrameBegin", "FrameEnd", "ObjectBegin", "ObjectEnd", "ObjectInstance 1", "\"periodic\"", "\"b-spline\"", "\"P\"",
      "\"Pw\"", "NuPatch", "TrimCurve", "Polygon", "PointsGeneralPolygons", "\"Cs\"", "\"facevarying float st\"", "Sphere", "Torus", "PatchMesh", "Basis", "Rotate", "Scale", "ReadArchive", "\"teapot\"",
      "#", "\n", "\xc3\xa9"};
  test::Mutator mutate(20261123, alphabet, tokens);
  long accepted = 0, refused = 0;
  const long budget = test::FuzzBudget();
  for (long k = 0; k < budget; ++k) {
    const std::string text = mutate.Mutate(seeds[static_cast<std::size_t>(k) % seeds.size()]);
    const long lines = 1 + std::count(text.begin(), text.end(), '\n');
    auto r = ParseRib(text, "m.rib");
    if (const auto* e = std::get_if<SourceError>(&r)) {
      ++refused;
      if (e->file != "m.rib") continue;  // an archive the mutant named, located in it
      ASSERT_GE(e->line, 0) << "mutant " << k;
      ASSERT_LE(e->line, lines) << "mutant " << k << ": " << e->What();
      ASSERT_FALSE(e->message.empty()) << "mutant " << k;
      continue;
    }
    ++accepted;
    const Scene& s = std::get<Scene>(r);
    ASSERT_EQ(s.surfaces.size(), s.sourceLines.size());
    ASSERT_EQ(s.Ids(), s.appearanceOf.size());
    for (std::size_t i = 0; i < s.Ids(); ++i) ASSERT_LT(s.appearanceOf[i], s.appearances.size());
    for (std::size_t i = 0; i < s.surfaces.size(); ++i) {
      ASSERT_GE(s.sourceLines[i], 1);
      ASSERT_LE(s.sourceLines[i], lines);
    }
    for (const ScenePolygons& p : s.polygons) {
      ASSERT_LE(p.line, lines);
      for (const auto& t : p.mesh.triangles)
        for (const std::uint32_t v : t) ASSERT_LT(v, p.mesh.vertices.size());
    }
  }
  RecordProperty("mutants", std::to_string(budget));
  RecordProperty("accepted", std::to_string(accepted));
  EXPECT_GT(accepted, budget / 50);
  EXPECT_GT(refused, budget / 4);
}

}  // namespace
}  // namespace patchscan
