// One or more instances of every surface kind, for tests that must hold for all of them.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "patch/surface.h"
#include "patch/nurbs_shapes.h"

namespace patchscan::test {

inline std::vector<std::pair<std::string, Surface>> AllSurfaceKinds() {
  std::array<Vec3, 16> cv;
  for (int j = 0; j < 4; ++j)
    for (int i = 0; i < 4; ++i)  // a wavy, non-planar grid
      cv[4 * j + i] = Vec3(i - 1.5, j - 1.5, 0.4 * ((i * 7 + j * 3) % 5) - 0.8);
  std::vector<std::pair<std::string, Surface>> s;
  auto add = [&](std::string name, Shape shape) {
    s.emplace_back(std::move(name), Surface{std::move(shape), Affine3::Identity()});
  };
  add("bezier", BicubicPatch(cv));
  add("b-spline", BicubicPatch(cv, BSplineBasis(), BSplineBasis()));
  add("catmull-rom", BicubicPatch(cv, CatmullRomBasis(), CatmullRomBasis()));
  add("hermite", BicubicPatch(cv, HermiteBasis(), HermiteBasis()));
  add("power", BicubicPatch(cv, PowerBasis(), PowerBasis()));
  add("bezier x b-spline", BicubicPatch(cv, BezierBasis(), BSplineBasis()));
  add("bilinear", BilinearPatch({Vec3(-1, -1, 0), Vec3(1, -1, 0.5), Vec3(-1, 1, 0.3),
                                 Vec3(1, 1, -0.4)}));
  add("sphere", Sphere(1.5, -1.5, 1.5, 360));
  add("sphere cap", Sphere(1.0, -0.3, 0.8, 250));
  add("cylinder", Cylinder(0.7, -1.0, 1.2, 300));
  add("cone", Cone(2.0, 0.8, 360));
  add("paraboloid", Paraboloid(1.0, 0.0, 2.0, 360));
  add("paraboloid band", Paraboloid(1.2, 0.5, 1.5, 200));
  add("hyperboloid", Hyperboloid(Vec3(1, -0.5, -1), Vec3(-0.3, 1, 1), 360));
  add("disk", Disk(0.5, 1.3, 270));
  add("torus", Torus(1.5, 0.4, 0, 360, 360));
  add("torus part", Torus(1.0, 0.5, -60, 200, 120));
  add("saddle", Saddle(1.0));
  add("monkey saddle", MonkeySaddle(0.9));
  // A piece at the sphere's south pole (its v = 0 edge collapsed) and a wavy rational one.
  const std::vector<NurbsPiece> sphere = SplitNurbs(NurbsSphere(1.2));
  add("NURBS sphere, pole piece", sphere.front());
  add("NURBS sphere, piece at the north pole", sphere.back());
  const std::vector<NurbsPiece> wavy = SplitNurbs(WavyNurbs());
  add("NURBS wavy, first piece", wavy.front());
  add("NURBS wavy, last piece", wavy.back());
  return s;
}

}  // namespace patchscan::test
