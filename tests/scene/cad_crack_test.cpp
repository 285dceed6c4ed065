// No crack between the faces of a closed solid, at the default framing and zoomed 20 times on
// its shared edges: every pixel inside the silhouette of Open CASCADE's fine mesh of the
// solid (a watertight mesh: its faces share their edges' nodes) is wholly covered by the
// direct render. A crack shows as a pixel some of whose samples see through the solid.
#include <gtest/gtest.h>

#include <BRepAdaptor_Curve.hxx>
#include <BRepBndLib.hxx>
#include <BRepTools.hxx>
#include <BRep_Builder.hxx>
#include <BRep_Tool.hxx>
#include <Bnd_Box.hxx>
#include <STEPControl_Reader.hxx>
#include <TopExp.hxx>
#include <TopTools_IndexedDataMapOfShapeListOfShape.hxx>
#include <TopTools_ListOfShape.hxx>
#include <TopoDS.hxx>

#include <array>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "cli/folder.h"
#include "scene/cad_models.h"

namespace {

constexpr int kWidth = 160, kHeight = 120;
constexpr int kChannels = 11, kA = 3, kId = 5;  // R G B A Z id u v N.xyz, as OpenEXR orders them
// The zoom on each shared edge: the 20 times the default framing's field of view.
constexpr double kZoom = 20.0;
// How many of a model's shared edges are looked at, spread over its edge list.
constexpr int kEdgeViews = 6;
// A coverage short of 1 by more than rounding: at aa 3 one sample of 9 is 0.11.
constexpr float kShortOfWhole = 1e-4f;

std::string Xyz(const gp_Pnt& p) {
  std::ostringstream s;
  s.precision(17);
  s << p.X() << ',' << p.Y() << ',' << p.Z();
  return s.str();
}

// The cameras: the default framing, then kEdgeViews views of shared edges' midpoints from
// outside the model (from its box's centre through the point), zoomed kZoom times.
std::vector<std::string> Views(const TopoDS_Shape& shape) {
  Bnd_Box box;
  BRepBndLib::Add(shape, box);
  const gp_Pnt lo = box.CornerMin(), hi = box.CornerMax();
  const gp_Pnt centre((lo.XYZ() + hi.XYZ()) / 2);
  const double diagonal = lo.Distance(hi);
  TopTools_IndexedDataMapOfShapeListOfShape edgeFaces;
  TopExp::MapShapesAndAncestors(shape, TopAbs_EDGE, TopAbs_FACE, edgeFaces);
  std::vector<gp_Pnt> shared;
  for (int i = 1; i <= edgeFaces.Extent(); ++i) {
    const TopoDS_Edge& edge = TopoDS::Edge(edgeFaces.FindKey(i));
    if (BRep_Tool::Degenerated(edge) || edgeFaces(i).Extent() < 2) continue;
    const BRepAdaptor_Curve c(edge);
    shared.push_back(c.Value(0.5 * (c.FirstParameter() + c.LastParameter())));
  }
  std::vector<std::string> views = {""};
  const std::size_t step = std::max<std::size_t>(1, shared.size() / kEdgeViews);
  for (std::size_t k = 0; k < shared.size() && views.size() <= kEdgeViews; k += step) {
    gp_Vec out(centre, shared[k]);
    if (out.Magnitude() < 1e-9 * diagonal) out = gp_Vec(1, 0, 0);
    // Tilted off the line from the centre, so that the edge is not seen end-on.
    const gp_Vec dir = out.Normalized() + gp_Vec(0.3, -0.2, 0.4);
    const gp_Pnt eye = shared[k].Translated(dir.Normalized() * (2 * diagonal));
    std::ostringstream v;
    v << " --eye " << Xyz(eye) << " --look-at " << Xyz(shared[k]) << " --fov " << 30.0 / kZoom;
    views.push_back(v.str());
  }
  return views;
}

// Pixels wholly inside the mesh's silhouette (the pixel and its 8 neighbours covered) that
// the direct render leaves short of whole; *inside counts the pixels looked at.
int Cracks(const std::vector<float>& direct, const std::vector<float>& mesh, int* inside) {
  const auto a = [](const std::vector<float>& px, int x, int y) {
    return px[(static_cast<std::size_t>(y) * kWidth + static_cast<std::size_t>(x)) * kChannels + kA];
  };
  int cracks = 0;
  for (int y = 1; y + 1 < kHeight; ++y)
    for (int x = 1; x + 1 < kWidth; ++x) {
      bool covered = true;
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) covered = covered && a(mesh, x + dx, y + dy) >= 1.0f - kShortOfWhole;
      *inside += covered;
      if (covered && a(direct, x, y) < 1.0f - kShortOfWhole) {
        if (++cracks <= 3) std::cout << "  short of whole at (" << x << ", " << y << "): " << a(direct, x, y) << '\n';
      }
    }
  return cracks;
}

void ExpectNoCracks(const std::string& model) {
  TopoDS_Shape shape;
  BRep_Builder builder;
  if (model.ends_with(".brep")) {
    ASSERT_TRUE(BRepTools::Read(shape, model.c_str(), builder));
  } else {
    // The views need only the shape's edges: the model as patchscan reads it through OCCT.
    cad_models::Quiet();
    STEPControl_Reader reader;
    ASSERT_EQ(reader.ReadFile(model.c_str()), IFSelect_RetDone);
    reader.TransferRoots();
    shape = reader.OneShape();
  }
  Folder dir("cad_cracks");
  const std::string common = " --size 160x120 --aa 3 --aov";
  int views = 0;
  for (const std::string& view : Views(shape)) {
    SCOPED_TRACE(view.empty() ? "default framing" : view);
    ASSERT_EQ(dir.Run("render " + model + " -o direct.exr --mode exact" + common + view), 0) << dir.Err();
    ASSERT_EQ(dir.Run("render " + model + " -o mesh.exr --mode tess --tess-error 0.25" + common + view), 0) << dir.Err();
    int inside = 0;
    EXPECT_EQ(Cracks(Pixels((dir.path / "direct.exr").string()), Pixels((dir.path / "mesh.exr").string()), &inside), 0);
    std::cout << (view.empty() ? "default framing" : view) << ": " << inside << " pixels inside\n";
    views += inside > kWidth * kHeight / 10;  // a view that sees the solid, not past it
  }
  EXPECT_GT(views, 3);
}

// Faces whose own boundaries lie apart meet all the same: each ends where the scan line
// crosses the edge they share. The right face ends 0.02 (2.3 px) short of the edge on its
// own; the pixels between are its own in the render, and none is short of whole. Two
// models: a diamond, whose right face's trim crosses its box of parameters, and two squares,
// whose right face's wire runs round its box (a face otherwise scanned whole).
TEST(CadCracks, AGapBetweenTwoFacesIsClosedByTheEdgeTheyShare) {
  Folder dir("cad_gap");
  constexpr double kGap = 0.02;
  for (const auto& [name, shape] : {std::pair{"diamond", cad_models::GappedDiamond(kGap)},
                                    std::pair{"squares", cad_models::GappedSquares(kGap)}}) {
    SCOPED_TRACE(name);
    ASSERT_TRUE(cad_models::WriteBrep(shape, (dir.path / "d.brep").string()));
    const Result info = Patchscan("info " + (dir.path / "d.brep").string());
    ASSERT_EQ(info.code, 0) << info.err;
    EXPECT_NE(info.out.find("widest gap between faces along an edge 0.02"), std::string::npos) << info.out;
    // The edge at x = 1 is the image's middle column, x = 80; 1 + kGap at 82.3.
    const std::string view = " --size 160x120 --aa 3 --aov --eye 1,-5,0.5 --look-at 1,0,0.5 --fov 16";
    ASSERT_EQ(dir.Run("render d.brep -o mesh.exr --mode tess --tess-error 0.25" + view), 0) << dir.Err();
    const std::vector<float> mesh = Pixels((dir.path / "mesh.exr").string());
    for (const char* mode : {"exact", "theta"}) {
      SCOPED_TRACE(mode);
      ASSERT_EQ(dir.Run(std::string("render d.brep -o direct.exr --mode ") + mode + view), 0) << dir.Err();
      const std::vector<float> direct = Pixels((dir.path / "direct.exr").string());
      int inside = 0;
      EXPECT_EQ(Cracks(direct, mesh, &inside), 0);
      EXPECT_GT(inside, kWidth * kHeight / 10);
      const auto id = [&](int x, int y) { return direct[(static_cast<std::size_t>(y) * kWidth + x) * kChannels + kId]; };
      for (int y = 40; y < 80; ++y)
        for (int x : {80, 81}) EXPECT_EQ(id(x, y), id(120, 60)) << "(" << x << ", " << y << ")";
    }
  }
}

TEST(CadCracks, NoneInABoxWithAHoleAtAnyZoom) {
  Folder models("cad_crack_models");
  const std::string file = (models.path / "h.brep").string();
  ASSERT_TRUE(cad_models::WriteBrep(cad_models::BoxWithHole(), file));
  ExpectNoCracks(file);
}

TEST(CadCracks, NoneInOpenCascadesSampleSolidsAtAnyZoom) {
  const std::filesystem::path data = "/usr/share/opencascade/data";
  if (!std::filesystem::exists(data)) GTEST_SKIP() << "occt-misc is not installed";
  for (const char* name : {"step/screw.step", "occ/Motor-c.brep"}) {
    SCOPED_TRACE(name);
    ExpectNoCracks((data / name).string());
  }
}

}  // namespace
