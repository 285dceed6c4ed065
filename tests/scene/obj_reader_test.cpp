// Wavefront .obj cages: the reader against the same cage given directly (the surfaces must
// be the same limit surface, point for point), every form of face vertex and index, the
// OpenSubdiv shape files' tag lines, and malformed files refused at their line.
#include <gtest/gtest.h>

#include <sstream>
#include <string>
#include <variant>

#include "patch/cages.h"
#include "scene/obj_reader.h"
#include "patch/surface.h"

namespace patchscan {
namespace {

Scene Read(std::variant<Scene, SourceError> r) {
  if (const auto* e = std::get_if<SourceError>(&r)) {
    ADD_FAILURE() << e->What();
    return Scene{};
  }
  return std::get<Scene>(std::move(r));
}

std::string Refused(const std::string& text, const ObjOptions& options = {}) {
  const auto r = ParseObj(text, "bad.obj", options);
  return std::holds_alternative<SourceError>(r) ? std::get<SourceError>(r).What() : std::string("read");
}

// Both evaluate one Bfr limit surface from the same cage: equal to rounding.
constexpr double kSameTol = 1e-12;

void ExpectSameSurfaces(const Scene& scene, const SubdivMesh& mesh, const std::string& what) {
  const auto faces = PrepareSubdivFaces(mesh);
  ASSERT_EQ(scene.surfaces.size(), faces.size()) << what;
  for (std::size_t k = 0; k < faces.size(); ++k)
    for (double u : {0.0, 0.3, 1.0})
      for (double v : {0.0, 0.6, 1.0}) {
        SurfaceDerivs a, b;
        EvaluateObject(scene.surfaces[k], u, v, DerivOrder::First, &a);
        faces[k].Evaluate(u, v, DerivOrder::First, &b);
        EXPECT_LT((a.p - b.p).norm(), kSameTol) << what << " surface " << k;
        EXPECT_LT((a.dpdu - b.dpdu).norm(), kSameTol) << what << " surface " << k;
      }
}

const char* kCubeVertices =
    "v -1 -1 1\nv 1 -1 1\nv -1 1 1\nv 1 1 1\nv -1 1 -1\nv 1 1 -1\nv -1 -1 -1\nv 1 -1 -1\n";

TEST(ObjReader, ACubeIsTheCageGivenDirectly) {
  // test::Cube() with 1-based, negative, v/vt, v//vn and v/vt/vn references, a continued
  // line, comments, groups and smoothing groups.
  const std::string text = std::string("# cube\no box\n") + kCubeVertices +
                           "vt 0 0\nvt 1 0\nvn 0 0 1\ng side\ns 1\n"
                           "f 1/1 2/2 4/1 3/2   # the front\n"
                           "f -6//1 -5//1 \\\n  -3//1 -4//1\n"
                           "f 5/1/1 6/2/1 8/1/1 7/2/1\n"
                           "f 7 8 2 1\nf 2 8 6 4\nf 7 1 3 5\n"
                           "t interpolateboundary 1/0/0 1\n";
  const Scene scene = Read(ParseObj(text, "cube.obj"));
  ExpectSameSurfaces(scene, test::Cube(), "cube");
  ASSERT_EQ(scene.cages.size(), 1u);
  EXPECT_EQ(scene.cages[0].counts.faces, 6);
  EXPECT_EQ(scene.cages[0].line, 16);  // the first face
  // Each surface remembers its face's line; the continued face starts on line 17.
  ASSERT_EQ(scene.sourceLines.size(), 6u);
  EXPECT_EQ(scene.sourceLines[0], 16);
  EXPECT_EQ(scene.sourceLines[1], 17);
  EXPECT_EQ(scene.sourceLines[2], 19);
  // vt on some faces only is not applied: said once, at the first face without.
  ASSERT_EQ(scene.warnings.size(), 1u);
  EXPECT_NE(scene.warnings[0].find("cube.obj:17: this face gives no texture coordinates (v/vt) and others do"),
            std::string::npos)
      << scene.warnings[0];
}

TEST(ObjReader, TagLinesAreOpenSubdivShapeTags) {
  // The creased cube and the holed cube of tests/patch/cages.h, as tag lines (indices from
  // 0); a crease chain with one sharpness or one per edge; corners likewise.
  SubdivMesh creased = test::Cube();
  creased.creases = {{{0, 1, 3, 2, 0}, 10.0}, {{4, 5, 7, 6, 4}, 1.5}};
  creased.corners = {{6, 10.0}};
  const std::string faces = "f 1 2 4 3\nf 3 4 6 5\nf 5 6 8 7\nf 7 8 2 1\nf 2 8 6 4\nf 7 1 3 5\n";
  const std::string text = std::string(kCubeVertices) + faces +
                           "t crease 5/1/0 0 1 3 2 0 10\n"
                           "t crease 5/4/0 4 5 7 6 4 1.5 1.5 1.5 1.5\n"
                           "t corner 1/1/0 6 10\n";
  ExpectSameSurfaces(Read(ParseObj(text, "creased.obj")), creased, "creased cube");
  SubdivMesh holed = test::Cube();
  holed.holes = {1};
  const Scene h = Read(ParseObj(std::string(kCubeVertices) + faces + "t hole 1/0/0 1\n", "holed.obj"));
  ExpectSameSurfaces(h, holed, "holed cube");
  EXPECT_EQ(h.cages[0].counts.holes, 1);
  // interpolateboundary: 1 by default here, RenderMan's 0 when asked (the open grid's
  // boundary faces dropped), by number or by name.
  std::ostringstream gridText;
  const SubdivMesh g = test::Grid(4, 0);
  gridText.precision(17);
  for (const Vec3& p : g.points) gridText << "v " << p.x() << ' ' << p.y() << ' ' << p.z() << '\n';
  for (std::size_t f = 0; f < g.faceSizes.size(); ++f) {
    gridText << 'f';
    for (int i = 0; i < 4; ++i) gridText << ' ' << g.faceVertices[4 * f + static_cast<std::size_t>(i)] + 1;
    gridText << '\n';
  }
  const std::string grid = gridText.str();
  EXPECT_EQ(Read(ParseObj(grid, "grid.obj")).surfaces.size(), 16u);
  EXPECT_EQ(Read(ParseObj(grid + "t interpolateboundary 1/0/0 0\n", "grid.obj")).surfaces.size(), 4u);
  EXPECT_EQ(Read(ParseObj(grid + "t interpolateboundary 0/0/1 none\n", "grid.obj")).surfaces.size(), 4u);
}

TEST(ObjReader, SchemesAndUnknownStatements) {
  const std::string tetra = "v 1 1 1\nv 1 -1 -1\nv -1 1 -1\nv -1 -1 1\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 3 1 4\n";
  SubdivMesh loop;
  loop.scheme = SubdivScheme::Loop;
  loop.faceSizes = {3, 3, 3, 3};
  loop.faceVertices = {0, 2, 1, 0, 1, 3, 1, 2, 3, 2, 0, 3};
  loop.points = {{1, 1, 1}, {1, -1, -1}, {-1, 1, -1}, {-1, -1, 1}};
  loop.interpolateBoundary = 1;
  ExpectSameSurfaces(Read(ParseObj(tetra, "t.obj", {SubdivScheme::Loop})), loop, "Loop tetrahedron");
  // Bilinear: the cage itself; a face's centre is the mean of its corners.
  const Scene flat = Read(ParseObj(tetra, "t.obj", {SubdivScheme::Bilinear}));
  ASSERT_EQ(flat.surfaces.size(), 12u);  // 3 quarters per triangle
  SurfaceDerivs centre;
  EvaluateObject(flat.surfaces[0], 1.0, 1.0, DerivOrder::Position, &centre);
  EXPECT_LT((centre.p - Vec3(1, 1, -1) / 3.0).norm(), kSameTol);
  // Lines, curves and unknown tags: one warning per kind, with its first line and count.
  const Scene s = Read(ParseObj(tetra + "l 1 2\nl 2 3\ncurv 0 1 1 2\nt facevaryingpropagatecorners 1/0/0 1\n", "t.obj"));
  ASSERT_EQ(s.warnings.size(), 3u);
  EXPECT_EQ(s.warnings[0], "t.obj:11: 'curv' is not read here: 1 statement skipped");
  EXPECT_EQ(s.warnings[1], "t.obj:9: 'l' is not read here: 2 statements skipped");
  EXPECT_EQ(s.warnings[2], "t.obj:12: 't facevaryingpropagatecorners' is not read here: 1 statement skipped");
}

TEST(ObjReader, MalformedFilesAreRefusedAtTheirLine) {
  const std::string tri = "v 0 0 0\nv 1 0 0\nv 1 1 0\n";
  const struct {
    std::string text, message;
  } cases[] = {
      {tri + "f 1 2 4\n", "bad.obj:4: vertex index '4' is out of range (3 vertices read so far)"},
      {tri + "f 1 2 0\n", "bad.obj:4: vertex index '0' is out of range"},
      {tri + "f 1 2 -4\n", "bad.obj:4: vertex index '-4' is out of range"},
      {tri + "f 1 2 3/1\n", "bad.obj:4: texture coordinate index '1' is out of range (0 texture coordinates"},
      {tri + "vn 0 0 1\nf 1 2 3//2\n", "bad.obj:5: normal index '2' is out of range (1 normal read so far)"},
      {tri + "f 1 2 3/\n", "bad.obj:4: a face vertex '3/' is v, v/vt, v//vn or v/vt/vn"},
      {tri + "f 1 2 x\n", "bad.obj:4: expected a whole number, found 'x'"},
      {tri + "f 1 2\n", "bad.obj:4: a face has at least 3 vertices, this one 2"},
      {tri + "f 1 2 2\n", "bad.obj:4: the face uses vertex 2 twice (a degenerate face)"},
      {"v 0 0\n", "bad.obj:1: 'v' takes x y z [w]"},
      {"v 0 0 1e999\n", "bad.obj:1: the number '1e999' is not finite"},
      {"v 0 0 0,5\n", "bad.obj:1: expected a number, found '0,5'"},
      {tri + "l 1 2\n", "bad.obj: no faces ('f') to render (not read here: 1 'l')"},
      {tri + "f 1 2 3\nt crease 2/1 0 1 5\n", "bad.obj:5: tag 'crease': the counts '2/1' are nint/nfloat/nstring"},
      {tri + "f 1 2 3\nt crease 2/1/0 0 1\n", "bad.obj:5: tag 'crease': '2/1/0' asks for 3 arguments, found 2"},
      // Counts whose sum would overflow (found by fuzz_obj).
      {tri + "f 1 2 3\nt crease 1/9223372036854775807/0 0 1\n",
       "bad.obj:5: tag 'crease': '1/9223372036854775807/0' asks for more than the 2 arguments found"},
      {tri + "f 1 2 3\nt crease 2/1/0 0 3 5\n", "bad.obj:5: tag 'crease': vertex 3 is out of range (3 vertices read so far, from 0)"},
      {tri + "f 1 2 3\nt crease 1/1/0 0 5\n", "bad.obj:5: tag \"crease\" takes a chain of 2 or more vertices"},
      {tri + "f 1 2 3\nt corner 2/3/0 0 1 5 5 5\n", "bad.obj:5: tag \"corner\" takes vertices and one sharpness"},
      {tri + "f 1 2 3\nt hole 1/0/0 1\n", "bad.obj:5: tag \"hole\": face 1 is out of range (1 faces, from 0)"},
      {tri + "f 1 2 3\nt interpolateboundary 1/0/0 3\n", "bad.obj:5: tag \"interpolateboundary\" takes 0, 1 or 2"},
      {tri + "f 1 2 3\nt\n", "bad.obj:5: a tag line is 't name nint/nfloat/nstring arguments...'"},
  };
  for (const auto& c : cases) EXPECT_NE(Refused(c.text).find(c.message), std::string::npos) << Refused(c.text);
  EXPECT_NE(Refused("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n", {SubdivScheme::Loop})
                .find("bad.obj:5: a face of 4 vertices: a Loop cage is of triangles"),
            std::string::npos);
  const auto missing = ReadObj("/nonexistent/cage.obj");
  ASSERT_TRUE(std::holds_alternative<SourceError>(missing));
  EXPECT_EQ(std::get<SourceError>(missing).file, "/nonexistent/cage.obj");
}

TEST(ObjReader, TheCorpusReadsOrIsRefusedWithALine) {
  // tests/corpus/obj and surfaces/cube_tags.obj: the seeds of fuzz/fuzz_obj, in every scheme.
  for (const std::string& path : {std::string(PATCHSCAN_SURFACES_DIR "/cube_tags.obj"),
                                 std::string(PATCHSCAN_TESTS_DIR "/corpus/obj/ngons_negative.obj"),
                                 std::string(PATCHSCAN_TESTS_DIR "/corpus/obj/triangles.obj")}) {
    const std::string& name = path;
    EXPECT_FALSE(Read(ReadObj(path)).surfaces.empty()) << name;
    EXPECT_FALSE(Read(ReadObj(path, {SubdivScheme::Bilinear})).surfaces.empty()) << name;
  }
  EXPECT_FALSE(Read(ReadObj(PATCHSCAN_TESTS_DIR "/corpus/obj/triangles.obj", {SubdivScheme::Loop})).surfaces.empty());
  for (const char* name : {"degenerate_face", "folded_crease", "index_out_of_range", "index_zero", "nan", "tag_counts"}) {
    const auto r = ReadObj(std::string(PATCHSCAN_TESTS_DIR "/corpus/obj/") + name + ".obj");
    ASSERT_TRUE(std::holds_alternative<SourceError>(r)) << name;
    EXPECT_GT(std::get<SourceError>(r).line, 0) << name;
  }
}

}  // namespace
}  // namespace patchscan
