// Polygons (RIB Polygon, GeneralPolygon, PointsPolygons, PointsGeneralPolygons): planar
// pieces of surface that are already exact as triangles, so they go to the back end as
// triangles in every mode. A polygon may be concave and have holes;
// it is triangulated once, at reading, by ear clipping in its own plane.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "core/vec.h"

namespace patchscan {

// One corner of a polygon, in world space, with the primitive variables RenderMan gives
// polygons: "N" (the polygon's own normal where not given), "st" (0 where not given) and
// "Cs" (multiplies the surface's colour; 1 where not given).
struct PolygonVertex {
  Vec3 position;
  Vec3 normal;
  Vec2 st = Vec2::Zero();
  Vec3 colour = Vec3::Ones();
};

// The polygons of one request: vertices per corner (a point shared by two polygons is
// two vertices, so each polygon keeps its own normal), triangles indexing them.
struct PolygonMesh {
  std::vector<PolygonVertex> vertices;
  std::vector<std::array<std::uint32_t, 3>> triangles;
};

// The normal of a polygon's outline by Newell's method: its length is twice the area of
// the outline projected on the plane it is normal to, and it points the way the outline
// turns counter-clockwise (right-hand rule). Exact for planar polygons, a best fit for
// others; zero for an outline without area.
Vec3 NewellNormal(std::span<const Vec3> points, std::span<const std::uint32_t> loop);

// Triangulates a polygon with holes: loops[0] the outline, the others holes, each a list
// of indices into `points`. Appends triangles of indices into `points`, wound the way the
// outline is. Holes are joined to the outline by bridges (each from a hole's rightmost
// point to a point of the outline it sees), then ears are clipped in the plane normal to
// the outline's Newell normal. Loops of fewer than three points and outlines without area
// give nothing; a hole outside the outline is dropped; a self-intersecting outline (whose
// triangulation RenderMan leaves undefined) still gives triangles covering its points.
// Returns the number of triangles appended.
std::size_t TriangulatePolygon(std::span<const Vec3> points, std::span<const std::vector<std::uint32_t>> loops,
                               std::vector<std::array<std::uint32_t, 3>>* out);

}  // namespace patchscan
