// Small CAD models made with Open CASCADE and written as STEP, IGES or BRep files, for the
// CAD reader's tests: a box, a cylinder, a sphere, a torus, a cylinder's side on left-handed
// axes, a box with a hole, a coloured box and an assembly of two placed boxes.
#pragma once

#include <BRepAlgoAPI_Cut.hxx>
#include <BRepBuilderAPI_MakeEdge.hxx>
#include <BRepBuilderAPI_MakeFace.hxx>
#include <BRepBuilderAPI_MakeVertex.hxx>
#include <BRepBuilderAPI_MakeWire.hxx>
#include <BRep_Builder.hxx>
#include <Geom2d_Line.hxx>
#include <TopoDS_Compound.hxx>
#include <gp_Pln.hxx>
#include <BRepPrimAPI_MakeBox.hxx>
#include <BRepPrimAPI_MakeCylinder.hxx>
#include <BRepPrimAPI_MakeSphere.hxx>
#include <BRepPrimAPI_MakeTorus.hxx>
#include <BRepTools.hxx>
#include <Geom_CylindricalSurface.hxx>
#include <IGESControl_Writer.hxx>
#include <Interface_Static.hxx>
#include <Message.hxx>
#include <Message_Messenger.hxx>
#include <Quantity_Color.hxx>
#include <STEPCAFControl_Writer.hxx>
#include <STEPControl_Writer.hxx>
#include <TDocStd_Document.hxx>
#include <TopExp_Explorer.hxx>
#include <XCAFApp_Application.hxx>
#include <XCAFDoc_ColorTool.hxx>
#include <XCAFDoc_DocumentTool.hxx>
#include <XCAFDoc_ShapeTool.hxx>
#include <gp_Ax2.hxx>
#include <gp_Ax3.hxx>

#include <cmath>

#include <string>

namespace cad_models {

// Open CASCADE's writers print to stdout: quiet for the tests.
inline void Quiet() { Message::DefaultMessenger()->ChangePrinters().Clear(); }

inline TopoDS_Shape Box() { return BRepPrimAPI_MakeBox(gp_Pnt(1, 2, 3), 4, 5, 6).Shape(); }
// Axis +z through (0,0,0), radius 2, height 5.
inline TopoDS_Shape Cylinder() { return BRepPrimAPI_MakeCylinder(2.0, 5.0).Shape(); }
inline TopoDS_Shape Sphere() { return BRepPrimAPI_MakeSphere(gp_Pnt(1, 1, 1), 3.0).Shape(); }
// Axis +z through the origin, radii 4 and 1.
inline TopoDS_Shape Torus() { return BRepPrimAPI_MakeTorus(4.0, 1.0).Shape(); }
// One face, the side of Cylinder() on left-handed axes (u runs clockwise seen from +z): its
// P_u x P_v points into the cylinder.
inline TopoDS_Shape MirroredCylinderSide() {
  gp_Ax3 axes(gp_Pnt(0, 0, 0), gp_Dir(0, 0, 1), gp_Dir(1, 0, 0));
  axes.YReverse();
  return BRepBuilderAPI_MakeFace(new Geom_CylindricalSurface(axes, 2.0), 0.0, 2.0 * M_PI, 0.0, 5.0, 1e-7).Face();
}
// A 10 x 10 x 4 box with a hole of radius 2 through it, along z at (5, 5).
inline TopoDS_Shape BoxWithHole() {
  const TopoDS_Shape box = BRepPrimAPI_MakeBox(10, 10, 4).Shape();
  const TopoDS_Shape hole = BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(5, 5, -1), gp_Dir(0, 0, 1)), 2.0, 6.0).Shape();
  return BRepAlgoAPI_Cut(box, hole).Shape();
}
// Two triangles in the plane y = 0 sharing the edge x = 1, 0 <= z <= 1 (a diamond 2 wide
// and 1 high), the right one's pcurve of that edge moved `gap` along x: its face ends `gap`
// short of the edge, as the faces of an exported model may within their tolerance.
inline TopoDS_Shape GappedDiamond(double gap) {
  const auto vertex = [](double x, double z) { return BRepBuilderAPI_MakeVertex(gp_Pnt(x, 0, z)).Vertex(); };
  const TopoDS_Vertex a = vertex(1, 0), b = vertex(1, 1), left = vertex(0, 0.5), right = vertex(2, 0.5);
  const auto edge = [](const TopoDS_Vertex& p, const TopoDS_Vertex& q) { return BRepBuilderAPI_MakeEdge(p, q).Edge(); };
  const TopoDS_Edge shared = edge(a, b);
  const gp_Pln plane(gp_Ax3(gp_Pnt(0, 0, 0), gp_Dir(0, -1, 0), gp_Dir(1, 0, 0)));  // u along x, v along z
  const TopoDS_Face leftFace = BRepBuilderAPI_MakeFace(plane, BRepBuilderAPI_MakeWire(shared, edge(b, left), edge(left, a)));
  const TopoDS_Face rightFace = BRepBuilderAPI_MakeFace(plane, BRepBuilderAPI_MakeWire(edge(a, right), edge(right, b), shared));
  BRep_Builder builder;
  builder.UpdateEdge(shared, new Geom2d_Line(gp_Pnt2d(1 + gap, 0), gp_Dir2d(0, 1)), rightFace, gap);
  TopoDS_Compound both;
  builder.MakeCompound(both);
  builder.Add(both, leftFace);
  builder.Add(both, rightFace);
  return both;
}

// Two unit squares in the plane y = 0 sharing the edge x = 1, 0 <= z <= 1 (a rectangle 2
// wide and 1 high), every pcurve of the right one moved `gap` along x: its wire still runs
// round its box of parameters (a face scanned whole to that box), which ends `gap` short of
// the edge.
inline TopoDS_Shape GappedSquares(double gap) {
  const auto vertex = [](double x, double z) { return BRepBuilderAPI_MakeVertex(gp_Pnt(x, 0, z)).Vertex(); };
  const TopoDS_Vertex a = vertex(1, 0), b = vertex(1, 1), l0 = vertex(0, 0), l1 = vertex(0, 1), r0 = vertex(2, 0),
                      r1 = vertex(2, 1);
  const auto edge = [](const TopoDS_Vertex& p, const TopoDS_Vertex& q) { return BRepBuilderAPI_MakeEdge(p, q).Edge(); };
  const TopoDS_Edge shared = edge(a, b), bottom = edge(a, r0), side = edge(r0, r1), top = edge(r1, b);
  const gp_Pln plane(gp_Ax3(gp_Pnt(0, 0, 0), gp_Dir(0, -1, 0), gp_Dir(1, 0, 0)));  // u along x, v along z
  const TopoDS_Face leftFace = BRepBuilderAPI_MakeFace(plane, BRepBuilderAPI_MakeWire(edge(l0, a), shared, edge(b, l1), edge(l1, l0)));
  const TopoDS_Face rightFace = BRepBuilderAPI_MakeFace(plane, BRepBuilderAPI_MakeWire(bottom, side, top, shared));
  // Each edge runs from its first vertex at parameter 0 to its second at 1.
  BRep_Builder builder;
  const auto moved = [&](const TopoDS_Edge& e, double u, double v, double du, double dv) {
    builder.UpdateEdge(e, new Geom2d_Line(gp_Pnt2d(u + gap, v), gp_Dir2d(du, dv)), rightFace, gap);
  };
  moved(shared, 1, 0, 0, 1);
  moved(bottom, 1, 0, 1, 0);
  moved(side, 2, 0, 0, 1);
  moved(top, 2, 1, -1, 0);
  TopoDS_Compound both;
  builder.MakeCompound(both);
  builder.Add(both, leftFace);
  builder.Add(both, rightFace);
  return both;
}

inline bool WriteStep(const TopoDS_Shape& shape, const std::string& path) {
  Quiet();
  STEPControl_Writer w;
  return w.Transfer(shape, STEPControl_AsIs) == IFSelect_RetDone && w.Write(path.c_str()) == IFSelect_RetDone;
}

// In B-rep mode (solids, shells and their shared edges), else face by face (trimmed
// surfaces, each with its own boundary, as many exporters write IGES).
inline bool WriteIges(const TopoDS_Shape& shape, const std::string& path, bool brep = true) {
  Quiet();
  IGESControl_Writer w("MM", brep ? 1 : 0);
  return w.AddShape(shape) && w.Write(path.c_str());
}

inline bool WriteBrep(const TopoDS_Shape& shape, const std::string& path) {
  return BRepTools::Write(shape, path.c_str());
}

// Writes the XDE document of `fill` (given the shape and colour tools) as STEP.
template <class Fill>
bool WriteXdeStep(const std::string& path, Fill&& fill) {
  Quiet();
  Handle(TDocStd_Document) doc;
  Handle(XCAFApp_Application) app = XCAFApp_Application::GetApplication();
  app->NewDocument("MDTV-XCAF", doc);
  fill(XCAFDoc_DocumentTool::ShapeTool(doc->Main()), XCAFDoc_DocumentTool::ColorTool(doc->Main()));
  STEPCAFControl_Writer w;
  const bool ok = w.Transfer(doc, STEPControl_AsIs) && w.Write(path.c_str()) == IFSelect_RetDone;
  app->Close(doc);
  return ok;
}

// Box() in red, its first face (x = 1) in blue.
inline bool WriteColouredBox(const std::string& path) {
  return WriteXdeStep(path, [](const Handle(XCAFDoc_ShapeTool)& shapes, const Handle(XCAFDoc_ColorTool)& colours) {
    const TopoDS_Shape box = Box();
    const TDF_Label part = shapes->AddShape(box, false);
    colours->SetColor(part, Quantity_Color(1, 0, 0, Quantity_TOC_RGB), XCAFDoc_ColorSurf);
    const TopoDS_Shape face = TopExp_Explorer(box, TopAbs_FACE).Current();
    colours->SetColor(shapes->AddSubShape(part, face), Quantity_Color(0, 0, 1, Quantity_TOC_RGB), XCAFDoc_ColorSurf);
  });
}

// One part, Box(), placed twice: as it is and moved by (20, 0, 0).
inline bool WriteAssembly(const std::string& path) {
  return WriteXdeStep(path, [](const Handle(XCAFDoc_ShapeTool)& shapes, const Handle(XCAFDoc_ColorTool)&) {
    const TDF_Label part = shapes->AddShape(Box(), false);
    const TDF_Label assembly = shapes->NewShape();
    gp_Trsf moved;
    moved.SetTranslation(gp_Vec(20, 0, 0));
    shapes->AddComponent(assembly, part, TopLoc_Location());
    shapes->AddComponent(assembly, part, TopLoc_Location(moved));
    shapes->UpdateAssemblies();
  });
}

}  // namespace cad_models
