// Triangle setup in 2D homogeneous coordinates after Olano and Greer (1997): the
// edge functions are the rows of the inverse of the vertex matrix M = [h0 h1 h2], so no
// triangle is clipped or split. Triangles crossing the eye plane become "external"
// triangles whose visible parts are still exactly the samples where all edge functions
// are non-negative; a hither edge masks out what is nearer than the hither plane.
#pragma once

#include <optional>

#include "raster/mesh.h"

namespace patchscan::raster {

// Below this |det M| relative to the product of the vertices' sizes, a triangle is seen
// edge-on or is degenerate (Olano and Greer 1997 §"Computation of the inverse"): it covers no
// sample reliably and its inverse would amplify rounding without bound.
constexpr double kMinRelativeDet = 1e-14;

// How far a triangle's screen bounds reach beyond its vertices: far above the rounding of
// a vertex's x = X/W (1e-12 px at 65536 px), far below a sample spacing.
constexpr double kBoundsSlackPx = 1e-6;

struct TriangleSetup {
  // Edge lines in homogeneous screen space, oriented so that inside is >= 0:
  // edge[i] is the line through the two vertices other than i; edge[i] . (x, y, 1) is
  // proportional to the barycentric b_i divided by w.
  Vec3 edge[3];
  double invDet = 0.0;  // 1 / det M, signed
  bool frontFacing = true;
  // Screen bounds of the visible part (whole image when the triangle crosses w = 0).
  double xMin = 0, xMax = 0, yMin = 0, yMax = 0;
};

// Sets up a triangle; nullopt if it is degenerate, seen edge-on, or back-facing when
// culling. `front` faces are those with det M > 0 (counter-clockwise on screen with y
// down). Allocation-free.
std::optional<TriangleSetup> SetupTriangle(const Vec3& h0, const Vec3& h1, const Vec3& h2,
                                           bool cullBackFaces, double width, double height);

// The tie rule for samples exactly on an edge: of two triangles sharing an edge (whose
// oriented lines are exact negatives, see SetupTriangle), exactly one owns the sample.
inline bool OwnsEdgeSample(const Vec3& line) {
  return line.x() > 0.0 || (line.x() == 0.0 && line.y() > 0.0);
}

// Whether the sample (x, y) is inside: every oriented edge value positive, or zero with
// the tie rule. Also returns the three edge values (b_i / w up to the common factor det).
inline bool Inside(const TriangleSetup& t, double x, double y, double e[3]) {
  for (int i = 0; i < 3; ++i) {
    e[i] = t.edge[i].x() * x + t.edge[i].y() * y + t.edge[i].z();
    if (e[i] < 0.0 || (e[i] == 0.0 && !OwnsEdgeSample(t.edge[i]))) return false;
  }
  return true;
}

}  // namespace patchscan::raster
