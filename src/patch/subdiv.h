// Subdivision surfaces as surfaces: every base face of a Catmull-Clark control cage is a
// Surface on [0,1]^2, evaluated on its limit surface with first and second derivatives by
// OpenSubdiv's Bfr (DESIGN.md, round 2). A quadrilateral face is one surface; a face of n != 4
// sides is n surfaces, Bfr's quadrangulated sub-faces (each the quarter of the face at one
// corner). Faces that share an edge evaluate the same limit curve along it, so the scans see
// no cracks between them.
//
// Bfr represents a regular face exactly (a bicubic B-spline patch) and an irregular one (an
// extraordinary vertex, a semi-sharp crease) by its approximation at the factory's default
// adaptive level of 2 (OpenSubdiv 3.5 Bfr::SurfaceFactory::Options, "approxLevelSharp" and
// "approxLevelSmooth"), a patch that matches its neighbours along the shared edges.
#pragma once

#include <memory>
#include <span>
#include <string>
#include <vector>

#include "patch/surface_derivs.h"

namespace patchscan {

// The subdivision rules: RenderMan's "catmull-clark", "loop" (triangles only) and
// "bilinear" (the cage itself, flat: each face bilinear, an n-gon as n bilinear quarters).
enum class SubdivScheme { CatmullClark, Loop, Bilinear };

// A control cage and its tags, as RenderMan's SubdivisionMesh gives them.
struct SubdivMesh {
  SubdivScheme scheme = SubdivScheme::CatmullClark;
  std::vector<int> faceSizes;     // vertices of each face
  std::vector<int> faceVertices;  // each face's vertex indices, counter-clockwise seen from outside
  std::vector<Vec3> points;
  // "crease": a chain of vertices whose edges get one sharpness (10 or more: infinitely sharp).
  struct Crease {
    std::vector<int> chain;
    double sharpness = 0.0;
  };
  std::vector<Crease> creases;
  std::vector<std::pair<int, double>> corners;  // "corner": vertex, sharpness
  std::vector<int> holes;                       // "hole": faces not rendered
  // "interpolateboundary", RenderMan's meaning: 0 the boundary faces are not rendered (the
  // limit surface does not reach the cage's boundary), 1 boundary edges and corners sharp,
  // 2 boundary edges sharp, corners smooth.
  int interpolateBoundary = 0;
};

// One base face (or one sub-face of a non-quadrilateral face) of a prepared cage. A
// sub-face is a quarter of the face at one corner: Bfr's own for Catmull-Clark and bilinear
// n-gons, and for a Loop triangle the kite from its corner to the midpoints of its two
// edges there and its centre (in Bfr's triangle coordinates), so that every surface has
// the domain [0,1]^2 and no collapsed edge.
class SubdivFace {
 public:
  struct Prepared;  // the Bfr surface of the face and its patch points, shared by sub-faces
  SubdivFace(std::shared_ptr<const Prepared> face, int subFace);

  void Evaluate(double u, double v, DerivOrder order, SurfaceDerivs* out) const;
  // The face's patch points: the surface lies in their convex hull (Catmull-Clark's and
  // Bfr's bases are non-negative).
  std::span<const Vec3> Hull() const;
  std::string Describe() const;
  // The base face's index in the cage, and the sub-face (-1: the face is a quadrilateral).
  int Face() const;
  int SubFace() const { return subFace_; }
  bool Regular() const;
  // The cage the face belongs to, as given (one copy shared by all its faces).
  const SubdivMesh& Cage() const;

 private:
  std::shared_ptr<const Prepared> face_;
  int subFace_;
  // The sub-face's (u, v) to the face's Bfr coordinates, bilinearly: c00 + eu u + ev v +
  // twist u v (affine, twist 0, for Bfr's quadrangulated sub-faces).
  double c00_[2] = {0.0, 0.0}, eu_[2] = {1.0, 0.0}, ev_[2] = {0.0, 1.0}, twist_[2] = {0.0, 0.0};
};

// Statistics of a cage, for `patchscan info`.
struct SubdivCounts {
  int faces = 0, vertices = 0, irregularFaces = 0, extraordinaryVertices = 0, holes = 0, surfaces = 0;
  int creaseEdges = 0, corners = 0;
};

// Prepares every face of `mesh` that is rendered (not a hole, nor a boundary face where
// interpolateBoundary is 0). Throws std::invalid_argument naming what is wrong with a cage
// that is not a valid mesh (indices out of range, a face of fewer than 3 vertices, a face
// using a vertex twice, a face of a Loop cage that is not a triangle, a non-manifold edge
// OpenSubdiv refuses).
std::vector<SubdivFace> PrepareSubdivFaces(const SubdivMesh& mesh, SubdivCounts* counts = nullptr);

}  // namespace patchscan
