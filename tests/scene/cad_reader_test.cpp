// CAD models through Open CASCADE: small models made here and written as STEP, IGES and
// BRep (tests/scene/cad_models.h) read back as trimmed surfaces (planes and quadrics as
// patchscan's analytic shapes, or every face as NURBS), checked point for point against the
// analytic shapes they are; colours, assemblies, the facts `info` reports, the
// sample models Debian's occt-misc installs, and files that must be refused.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <string>
#include <unistd.h>
#include <variant>

#ifdef PATCHSCAN_SANITIZED
#include <sanitizer/lsan_interface.h>
#endif

#include "scene/cad_models.h"
#include "scene/cad_reader.h"
#include "patch/surface.h"
#include "patch/trim.h"

namespace patchscan {
namespace {

namespace fs = std::filesystem;

// The models' rational B-splines represent planes, circles and spheres exactly: their points
// lie on the analytic shape to rounding (of coordinates of size ~10).
constexpr double kOnShapeTol = 1e-9;
// Their normals, P_u x P_v of the same exact representations, are the shapes' to rounding
// too: the 1e-6 rad a CAD face's normal must keep against the analytic shape's, with room.
// (A render's normal is further limited by the solve of each sample's (u, v):
// tests/scene/cad_render_test.cpp.)
constexpr double kNormalTolRad = 1e-7;

struct TempDir {
  TempDir() : path(fs::temp_directory_path() / ("patchscan_cad_" + std::to_string(::getpid()))) {
    fs::create_directories(path);
  }
  ~TempDir() { fs::remove_all(path); }
  std::string File(const std::string& name) const { return (path / name).string(); }
  fs::path path;
};

Scene Read(const std::string& path, bool asNurbs = false) {
  auto r = ReadCad(path, asNurbs);
  if (const auto* e = std::get_if<SourceError>(&r)) {
    ADD_FAILURE() << e->What();
    return Scene{};
  }
  return std::get<Scene>(std::move(r));
}

std::string Refused(const std::string& path) {
  const auto r = ReadCad(path);
  return std::holds_alternative<SourceError>(r) ? std::get<SourceError>(r).What() : std::string("read");
}

// Calls f(world point, world unit normal) at a grid of each surface's points that its trim
// keeps, the normal zero where P_u x P_v nearly vanishes (a pole: the sphere's rows of
// points along its collapsed edges); returns how many.
constexpr double kDefinedNormal = 1e-3;
int ForKeptPoints(const Scene& scene, const std::function<void(const Vec3&, const Vec3&)>& f) {
  int n = 0;
  for (const Surface& s : scene.surfaces)
    for (int i = 0; i <= 8; ++i)
      for (int j = 0; j <= 8; ++j) {
        const Vec2 st(i / 8.0, j / 8.0);
        if (const PieceTrim* t = TrimOf(s); t && !t->Kept(st)) continue;
        SurfaceDerivs d;
        EvaluateObject(s, st.x(), st.y(), DerivOrder::First, &d);
        const Vec3 normal = s.worldFromObject.linear().inverse().transpose() * d.dpdu.cross(d.dpdv);
        const bool defined = d.dpdu.cross(d.dpdv).norm() > kDefinedNormal * d.dpdu.norm() * d.dpdv.norm();
        f(s.worldFromObject * d.p, defined ? normal.normalized() : Vec3::Zero());
        ++n;
      }
  return n;
}

int Kind(const Scene& scene, const std::string& kind) {
  for (const auto& [k, n] : scene.cad->faceKinds)
    if (k == kind) return n;
  return 0;
}

TEST(CadReader, ABoxFromStepIgesAndBrep) {
  TempDir dir;
  ASSERT_TRUE(cad_models::WriteStep(cad_models::Box(), dir.File("box.step")));
  ASSERT_TRUE(cad_models::WriteIges(cad_models::Box(), dir.File("box.igs")));
  ASSERT_TRUE(cad_models::WriteBrep(cad_models::Box(), dir.File("box.brep")));
  for (const char* name : {"box.step", "box.igs", "box.brep"}) {
    SCOPED_TRACE(name);
    const Scene scene = Read(dir.File(name));
    ASSERT_TRUE(scene.cad);
    EXPECT_EQ(scene.cad->faces, 6);
    EXPECT_EQ(Kind(scene, "plane"), 6);
    EXPECT_EQ(scene.cad->skipped, 0);
    const Bounds3 b = scene.WorldBounds();
    EXPECT_LT((b.lo - Vec3(1, 2, 3)).norm(), kOnShapeTol);
    EXPECT_LT((b.hi - Vec3(5, 7, 9)).norm(), kOnShapeTol);
    // Every point lies on one of the six planes.
    const int n = ForKeptPoints(scene, [](const Vec3& p, const Vec3&) {
      const double d = std::min({std::abs(p.x() - 1), std::abs(p.x() - 5), std::abs(p.y() - 2), std::abs(p.y() - 7),
                                 std::abs(p.z() - 3), std::abs(p.z() - 9)});
      EXPECT_LT(d, kOnShapeTol) << p.transpose();
    });
    EXPECT_GT(n, 6 * 60);
  }
  EXPECT_EQ(Read(dir.File("box.step")).cad->edges, 12);
  // Written face by face, each face with its own four boundary curves, the box is read
  // with its faces sewn (Open CASCADE's IGES translation sews them): each edge is shared.
  ASSERT_TRUE(cad_models::WriteIges(cad_models::Box(), dir.File("faces.igs"), false));
  const Scene faces = Read(dir.File("faces.igs"));
  ASSERT_TRUE(faces.cad);
  EXPECT_EQ(faces.cad->faces, 6);
  EXPECT_EQ(faces.cad->edges, 12);
}

TEST(CadReader, QuadricFacesLieOnTheirQuadrics) {
  TempDir dir;
  ASSERT_TRUE(cad_models::WriteStep(cad_models::Cylinder(), dir.File("cylinder.step")));
  ASSERT_TRUE(cad_models::WriteStep(cad_models::Sphere(), dir.File("sphere.stp")));
  ASSERT_TRUE(cad_models::WriteBrep(cad_models::Torus(), dir.File("torus.brep")));
  const Scene cylinder = Read(dir.File("cylinder.step"));
  EXPECT_EQ(Kind(cylinder, "cylinder"), 1);
  EXPECT_EQ(Kind(cylinder, "plane"), 2);
  // The normals are the shapes' own (the sense of each is the face's business, as in RIB).
  const auto along = [](const Vec3& n, const Vec3& want) {
    return n.isZero() ? 0.0 : std::acos(std::min(1.0, std::abs(n.dot(want.normalized()))));
  };
  ForKeptPoints(cylinder, [&](const Vec3& p, const Vec3& n) {
    const double r = std::hypot(p.x(), p.y());
    const bool onSide = std::abs(r - 2) < kOnShapeTol && p.z() > -kOnShapeTol && p.z() < 5 + kOnShapeTol;
    const bool onCap = r < 2 + kOnShapeTol && (std::abs(p.z()) < kOnShapeTol || std::abs(p.z() - 5) < kOnShapeTol);
    EXPECT_TRUE(onSide || onCap) << p.transpose();
    // (A point of a cap's rim lies on the side too.)
    EXPECT_LT(std::min(onSide ? along(n, Vec3(p.x(), p.y(), 0)) : 9.0, onCap ? along(n, Vec3(0, 0, 1)) : 9.0), kNormalTolRad)
        << p.transpose();
  });
  const Scene sphere = Read(dir.File("sphere.stp"));
  EXPECT_EQ(Kind(sphere, "sphere"), 1);
  const int n = ForKeptPoints(sphere, [&](const Vec3& p, const Vec3& normal) {
    EXPECT_NEAR((p - Vec3(1, 1, 1)).norm(), 3, kOnShapeTol);
    EXPECT_LT(along(normal, p - Vec3(1, 1, 1)), kNormalTolRad) << p.transpose();
  });
  EXPECT_GT(n, 60);
  const Scene torus = Read(dir.File("torus.brep"));
  EXPECT_EQ(Kind(torus, "torus"), 1);
  ForKeptPoints(torus, [&](const Vec3& p, const Vec3& normal) {
    EXPECT_NEAR(std::hypot(std::hypot(p.x(), p.y()) - 4, p.z()), 1, kOnShapeTol);
    const Vec3 ring = 4 * Vec3(p.x(), p.y(), 0).normalized();  // the tube's centre nearest p
    EXPECT_LT(along(normal, p - ring), kNormalTolRad) << p.transpose();
  });
  // Each face is its analytic shape, one surface apiece (every full turn here is one
  // RenderMan quadric of thetamax 360), trimmed by its wires.
  const auto count = [](const Scene& scene, auto kind) {
    return std::count_if(scene.surfaces.begin(), scene.surfaces.end(),
                         [&](const Surface& s) { return std::holds_alternative<decltype(kind)>(s.shape); });
  };
  EXPECT_EQ(count(cylinder, Cylinder(1, 0, 1, 360)), 1);
  EXPECT_EQ(count(cylinder, BilinearPatch({})), 2);
  EXPECT_EQ(count(sphere, Sphere(1, -1, 1, 360)), 1);
  EXPECT_EQ(count(torus, Torus(2, 1, 0, 360, 360)), 1);
  for (const Scene* s : {&cylinder, &sphere, &torus}) EXPECT_EQ(s->surfaces.size(), static_cast<std::size_t>(s->cad->faces));
  // As NURBS (what convert writes): the same points, every surface a NURBS piece.
  const Scene asNurbs = Read(dir.File("cylinder.step"), true);
  EXPECT_EQ(count(asNurbs, NurbsPiece(1, 1, std::vector<Vec4>(4, Vec4(0, 0, 0, 1)), 0, 1, 0, 1)),
            static_cast<std::ptrdiff_t>(asNurbs.surfaces.size()));
  ForKeptPoints(asNurbs, [&](const Vec3& p, const Vec3&) {
    const double r = std::hypot(p.x(), p.y());
    EXPECT_TRUE((std::abs(r - 2) < kOnShapeTol) || (r < 2 + kOnShapeTol && (std::abs(p.z()) < kOnShapeTol || std::abs(p.z() - 5) < kOnShapeTol)))
        << p.transpose();
  });
}

// A face's front is OCCT's P_u x P_v of the face (reversed for a reversed face). A face on
// left-handed axes has its analytic shape placed by a mirroring map, its appearance turned to
// match; the front in exact mode (the shape's normal, turned where the appearance says) and
// in OCCT's mesh (tess mode) is the face's: here into the cylinder.
TEST(CadReader, AFaceOnLeftHandedAxesKeepsItsFront) {
  TempDir dir;
  // (OCCT's own format: STEP's placements are right-handed, its writer turns the axes.)
  ASSERT_TRUE(cad_models::WriteBrep(cad_models::MirroredCylinderSide(), dir.File("m.brep")));
  const Scene scene = Read(dir.File("m.brep"));
  ASSERT_EQ(scene.surfaces.size(), 1u);
  ASSERT_TRUE(std::holds_alternative<Cylinder>(scene.surfaces[0].shape));
  const bool turned = scene.appearances[scene.appearanceOf[0]].reversed;
  const int n = ForKeptPoints(scene, [&](const Vec3& p, const Vec3& normal) {
    EXPECT_LT((turned ? -normal : normal).dot(Vec3(p.x(), p.y(), 0)), 0.0) << p.transpose();
  });
  EXPECT_GT(n, 60);
  const TessMesh mesh = scene.cad->mesh(0.01);
  ASSERT_FALSE(mesh.vertices.empty());
  for (const TessVertex& v : mesh.vertices)
    EXPECT_LT((turned ? -v.normal : v.normal).dot(Vec3(v.position.x(), v.position.y(), 0)), 0.0) << v.position.transpose();
}

// What --mode tess renders of a CAD file: Open CASCADE's mesh at the deflection asked, its
// nodes on the surface, its facets within the deflection of it, normals the surface's.
TEST(CadReader, OpenCascadesMeshIsWithinItsDeflection) {
  TempDir dir;
  ASSERT_TRUE(cad_models::WriteStep(cad_models::Cylinder(), dir.File("cylinder.step")));
  const Scene scene = Read(dir.File("cylinder.step"));
  ASSERT_TRUE(scene.cad && scene.cad->mesh);
  for (double deflection : {0.1, 0.01}) {
    SCOPED_TRACE(deflection);
    const TessMesh mesh = scene.cad->mesh(deflection);
    ASSERT_EQ(mesh.surfaceOf.size(), mesh.triangles.size());
    for (std::uint32_t id : mesh.surfaceOf) EXPECT_LT(id, scene.surfaces.size());
    int side = 0;
    for (const auto& t : mesh.triangles) {
      const Vec3 c = (mesh.vertices[t[0]].position + mesh.vertices[t[1]].position + mesh.vertices[t[2]].position) / 3;
      const double r = std::hypot(c.x(), c.y());
      const auto onCap = [&](double z) {
        return std::all_of(t.begin(), t.end(), [&](std::uint32_t i) { return std::abs(mesh.vertices[i].position.z() - z) < kOnShapeTol; });
      };
      if (onCap(0) || onCap(5)) continue;
      ++side;
      EXPECT_GT(r, 2 - deflection * (1 + 1e-9));  // the chord's deviation
      for (std::uint32_t i : t) {
        const TessVertex& v = mesh.vertices[i];
        EXPECT_NEAR(std::hypot(v.position.x(), v.position.y()), 2, kOnShapeTol);
        EXPECT_LT((v.normal - Vec3(v.position.x(), v.position.y(), 0) / 2).norm(), kOnShapeTol);
      }
    }
    EXPECT_GT(side, 8);
  }
  EXPECT_GT(scene.cad->mesh(0.001).triangles.size(), scene.cad->mesh(0.1).triangles.size());
}

TEST(CadReader, AHoleIsCutByTheFacesInnerWire) {
  TempDir dir;
  ASSERT_TRUE(cad_models::WriteStep(cad_models::BoxWithHole(), dir.File("holed.step")));
  const Scene scene = Read(dir.File("holed.step"));
  EXPECT_EQ(scene.cad->faces, 7);
  EXPECT_EQ(Kind(scene, "cylinder"), 1);
  // The top and bottom faces keep nothing inside the hole, and their points outside it.
  int inHole = 0, capPoints = 0;
  ForKeptPoints(scene, [&](const Vec3& p, const Vec3&) {
    const double r = std::hypot(p.x() - 5, p.y() - 5);
    if (std::abs(p.z()) < kOnShapeTol || std::abs(p.z() - 4) < kOnShapeTol) {
      ++capPoints;
      if (r < 2 - kOnShapeTol) ++inHole;
    }
  });
  EXPECT_EQ(inHole, 0);
  EXPECT_GT(capPoints, 50);
  EXPECT_EQ(scene.cad->wires, 9);  // six faces' outer wires, two inner ones round the hole, the hole's
}

TEST(CadReader, ColoursOfFacesAndParts) {
  TempDir dir;
  ASSERT_TRUE(cad_models::WriteColouredBox(dir.File("coloured.step")));
  const Scene scene = Read(dir.File("coloured.step"));
  ASSERT_EQ(scene.appearanceOf.size(), scene.surfaces.size());
  int red = 0, blue = 0;
  for (std::uint32_t a : scene.appearanceOf) {
    const Vec3& c = scene.appearances[a].colour;
    red += c.isApprox(Vec3(1, 0, 0)) ? 1 : 0;
    blue += c.isApprox(Vec3(0, 0, 1)) ? 1 : 0;
  }
  EXPECT_EQ(red + blue, static_cast<int>(scene.surfaces.size()));
  EXPECT_GT(red, 0);
  EXPECT_GT(blue, 0);
  EXPECT_EQ(scene.cad->colours, 2);
}

TEST(CadReader, AnAssemblyPlacesOnePartTwice) {
  TempDir dir;
  ASSERT_TRUE(cad_models::WriteAssembly(dir.File("assembly.step")));
  const Scene scene = Read(dir.File("assembly.step"));
  EXPECT_EQ(scene.cad->instances, 2);
  EXPECT_EQ(scene.cad->faces, 6);  // prepared once
  EXPECT_NEAR(scene.WorldBounds().lo.x(), 1, kOnShapeTol);
  EXPECT_NEAR(scene.WorldBounds().hi.x(), 25, kOnShapeTol);
  ASSERT_GE(scene.cad->tree.size(), 3u);
  EXPECT_NE(scene.cad->tree[0].find("(assembly)"), std::string::npos);
  EXPECT_NE(scene.cad->tree[1].find("  "), std::string::npos);
}

TEST(CadReader, SampleModelsReadWithEveryFace) {
  const fs::path data = "/usr/share/opencascade/data";
  if (!fs::exists(data)) GTEST_SKIP() << "occt-misc is not installed";
  for (const char* name : {"step/screw.step", "iges/hammer.iges", "occ/Pump_Nut.brep", "occ/CrankArm.brep"}) {
    SCOPED_TRACE(name);
    const Scene scene = Read((data / name).string());
    ASSERT_TRUE(scene.cad);
    EXPECT_GT(scene.cad->faces, 5);
    EXPECT_EQ(scene.cad->skipped, 0);
    EXPECT_GE(scene.surfaces.size(), static_cast<std::size_t>(scene.cad->faces));
    EXPECT_TRUE(scene.warnings.empty()) << scene.warnings.front();
  }
  // A bottle whose thread winds twice round a cylinder (its face's u range two turns): the
  // cylinder as two quadrics of a turn each, trimmed by the face's own pcurves, meets its
  // neighbours within their tolerance (as NURBS, re-approximated pcurves opened 0.31 mm).
  const Scene bottle = Read((data / "occ/bottle.brep").string());
  ASSERT_TRUE(bottle.cad);
  EXPECT_EQ(bottle.cad->skipped, 0);
  EXPECT_LE(bottle.cad->largestGap, bottle.cad->largestTolerance);
}

TEST(CadReader, FilesThatCannotBeReadAreRefusedByName) {
  TempDir dir;
  EXPECT_EQ(Refused(dir.File("missing.step")), dir.File("missing.step") + ": cannot open the file");
  std::ofstream(dir.File("garbage.step")) << "this is not STEP\n";
  EXPECT_NE(Refused(dir.File("garbage.step")).find("not a STEP file"), std::string::npos);
  std::ofstream(dir.File("garbage.igs")) << "this is not IGES either\n";
  EXPECT_NE(Refused(dir.File("garbage.igs")).find(dir.File("garbage.igs") + ": "), std::string::npos);
  std::ofstream(dir.File("garbage.brep")) << "DBRep_DrawableShape\nnonsense\n";
  EXPECT_NE(Refused(dir.File("garbage.brep")).find("not a B-rep file"), std::string::npos);
  // A STEP file whose data section holds no shape.
  std::ofstream(dir.File("empty.step")) << "ISO-10303-21;\nHEADER;\nFILE_DESCRIPTION((''),'2;1');\n"
                                        << "FILE_NAME('empty','',(''),(''),'','','');\n"
                                        << "FILE_SCHEMA(('AUTOMOTIVE_DESIGN'));\nENDSEC;\nDATA;\nENDSEC;\n"
                                        << "END-ISO-10303-21;\n";
  EXPECT_NE(Refused(dir.File("empty.step")).find(dir.File("empty.step") + ": "), std::string::npos);
  // A file cut short: the first half of a real one.
  ASSERT_TRUE(cad_models::WriteStep(cad_models::BoxWithHole(), dir.File("whole.step")));
  std::ifstream whole(dir.File("whole.step"));
  const std::string text((std::istreambuf_iterator<char>(whole)), std::istreambuf_iterator<char>());
  std::ofstream(dir.File("cut.step")) << text.substr(0, text.size() / 2);
  const auto cut = ReadCad(dir.File("cut.step"));
  if (const auto* e = std::get_if<SourceError>(&cut)) {
    EXPECT_EQ(e->file, dir.File("cut.step"));
  }
  EXPECT_TRUE(IsCadExtension(".STEP") && IsCadExtension(".igs") && !IsCadExtension(".rib"));
}

// A count past the end of a .brep file: OCCT's parser, reading on from its failed stream,
// looped for as many rounds as the count says (fuzz_cad found it); the reader's stream ends
// the read at the first failed extraction.
TEST(CadReader, ACountPastTheEndOfABrepFileIsAnErrorNotAHang) {
  TempDir dir;
  std::ofstream(dir.File("cut.brep")) << "DBRep_DrawableShape\n\nCASCADE Topology V1, (c) Matra-Datavision\n"
                                         "Locations 0\nCurve2ds 2000000000\n1 0 0 1 0\n";
  const std::string refused = Refused(dir.File("cut.brep"));
  EXPECT_EQ(refused, dir.File("cut.brep") + ": not a B-rep file Open CASCADE can read (a value is missing or malformed)");
}

// A trimmed curve whose basis curve is of no known type: OCCT's parser dereferences the null
// curve, a crash without the reader's signal guard. The long jump out of the crash skips
// OCCT's destructors: what they would have freed is not a leak of the reader's.
TEST(CadReader, ACrashInsideOpenCascadesParserIsAnError) {
  TempDir dir;
  std::ofstream(dir.File("null.brep")) << "DBRep_DrawableShape\n\nCASCADE Topology V1, (c) Matra-Datavision\n"
                                          "Locations 0\nCurve2ds 0\nCurves 1\n8 0 1\n99 0 0 0\nPolygon3D 0\n"
                                          "PolygonOnTriangulations 0\nSurfaces 0\nTriangulations 0\n\nTShapes 0\n\n+0 0 \n";
#ifdef PATCHSCAN_SANITIZED
  __lsan_disable();
#endif
  const std::string refused = Refused(dir.File("null.brep"));
#ifdef PATCHSCAN_SANITIZED
  __lsan_enable();
#endif
  EXPECT_EQ(refused.rfind(dir.File("null.brep") + ": ", 0), 0u) << refused;
}

}  // namespace
}  // namespace patchscan
