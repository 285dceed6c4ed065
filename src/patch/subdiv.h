// Subdivision surfaces as surfaces: every base face of a Catmull-Clark control cage is a
// Surface on [0,1]^2, evaluated on its limit surface with first and second derivatives by
// OpenSubdiv's Bfr. A quadrilateral face is one surface; a face of n != 4
// sides is n surfaces, Bfr's quadrangulated sub-faces (each the quarter of the face at one
// corner). Faces that share an edge evaluate the same limit curve along it, so the scans see
// no cracks between them.
//
// Bfr represents a regular face exactly (a bicubic B-spline patch) and an irregular one (an
// extraordinary vertex, a semi-sharp crease) by its approximation at the factory's default
// adaptive level of 2 (OpenSubdiv 3.5 Bfr::SurfaceFactory::Options, "approxLevelSharp" and
// "approxLevelSmooth"), a patch that matches its neighbours along the shared edges.
//
// A face is prepared (its Bfr surface initialised and its patch points computed) on demand,
// when it is first evaluated, and freed when the last hold on it is released: a scan holds
// a face from the row its screen box begins to the row it ends, so off-screen faces are
// never prepared and memory follows the active faces, not the cage.
#pragma once

#include <array>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "patch/surface_derivs.h"

namespace patchscan {

class BicubicPatch;

struct FaceData;       // a prepared base face (patch/subdiv.cpp)
struct BicubicPieces;  // where a sub-face is a bicubic polynomial (patch/subdiv.cpp)

// The subdivision rules: RenderMan's "catmull-clark", "loop" (triangles only) and
// "bilinear" (the cage itself, flat: each face bilinear, an n-gon as n bilinear quarters).
enum class SubdivScheme { CatmullClark, Loop, Bilinear };

// How face-varying texture coordinates are interpolated: OpenSubdiv's
// Sdc::Options::FVarLinearInterpolation, in its order. Smooth: subdivided like the points,
// each region of the texture map bounded by a smooth curve; CornersOnly: and its corners
// kept; CornersPlus1/Plus2: and points where three or more regions meet (and darts, concave
// corners); Boundaries: the regions' boundaries linear; All: every face bilinear.
enum class FaceVaryingRule { Smooth, CornersOnly, CornersPlus1, CornersPlus2, Boundaries, All };

// The storage class of "st": Vertex, one per point, subdivided as the points are; Varying,
// one per point, bilinear on each face; FaceVarying, one per face corner (so a texture map
// may be cut along edges), by the mesh's FaceVaryingRule.
enum class StClass { Vertex, Varying, FaceVarying };

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
  // Texture coordinates "st" (empty: none, each face's own (u, v) instead). Vertex and
  // Varying: one per point. FaceVarying: stIndices has one index into st per face corner,
  // in faceVertices' layout.
  StClass stClass = StClass::FaceVarying;
  std::vector<Vec2> st;
  std::vector<int> stIndices;
  FaceVaryingRule faceVaryingRule = FaceVaryingRule::CornersOnly;
};

// Texture coordinates at a point of a surface and their derivatives in (u, v).
struct TexCoords {
  Vec2 st, dstdu, dstdv;
};

// One base face (or one sub-face of a non-quadrilateral face) of a prepared cage. A
// sub-face is a quarter of the face at one corner: Bfr's own for Catmull-Clark and bilinear
// n-gons, and for a Loop triangle the kite from its corner to the midpoints of its two
// edges there and its centre (in Bfr's triangle coordinates), so that every surface has
// the domain [0,1]^2 and no collapsed edge.
class SubdivFace {
 public:
  class Cage;  // the cage, its OpenSubdiv topology and the prepared faces, shared by its faces
  SubdivFace(std::shared_ptr<Cage> cage, int face, int subFace, std::shared_ptr<const std::vector<Vec3>> hull);

  // Prepares the base face first if it is not (thread-safe; allocates then, and not after).
  // Where the limit surface is a bicubic polynomial (a regular Catmull-Clark or bilinear
  // quadrilateral, or the cells of an irregular Catmull-Clark face away from its
  // extraordinary corners), it is evaluated as that bicubic once a hold that fits has
  // fitted it (Hold); at an extraordinary corner, where Bfr's surface is a Gregory patch,
  // as that patch (fitted too: Bfr's position and first derivatives, and the second
  // derivatives of those); elsewhere (Loop's faces, or before such a hold) by Bfr.
  void Evaluate(double u, double v, DerivOrder order, SurfaceDerivs* out) const;
  // Bfr's own evaluation, even where Evaluate takes the bicubic (to test one against the other).
  void EvaluateByBfr(double u, double v, DerivOrder order, SurfaceDerivs* out) const;
  // Whether Evaluate takes a bicubic at (u, v) (prepares the face).
  bool BicubicAt(double u, double v) const;
  // Which fitted piece, bicubic or Gregory, Evaluate takes at (u, v), as an index two points
  // share exactly when one piece serves both; -1 where Bfr's evaluation serves (or before a
  // fitting hold). Along the face's edges every such piece is one cubic in the edge's
  // parameter: a Gregory patch's boundary curves are the cubic Bézier curves of its
  // boundary points (its blended interior points weigh nothing there). Prepares the face.
  int PieceAt(double u, double v) const;
  // Whether a hold has fitted the (sub-)face as bicubic pieces in every cell; if so the
  // pieces (each over its own [0,1]^2, a square of the face's (u, v) scaled by a positive
  // factor), at most 16, in *out, and how many. -1 when a cell is a Gregory patch or Bfr's.
  int BicubicCover(std::array<const BicubicPatch*, 16>* out) const;
  // Whether Evaluate takes a fitted Gregory patch at (u, v) (prepares the face).
  bool GregoryAt(double u, double v) const;
  // The texture coordinates "st" at (u, v) with their derivatives, or nullopt when the cage
  // has none. Prepares as Evaluate does.
  std::optional<TexCoords> TextureCoords(double u, double v) const;
  // Points whose convex hull contains the surface, known without preparing the face (the
  // cage's points or, for faces bounded at load, Bfr's patch points; shared by sub-faces).
  std::span<const Vec3> Hull() const { return *hull_; }
  std::string Describe() const;
  // The base face's index in the cage, and the sub-face (-1: the face is a quadrilateral).
  int Face() const { return face_; }
  int SubFace() const { return subFace_; }
  bool Regular() const;
  // The cage the face belongs to, as given (one copy shared by all its faces).
  const SubdivMesh& Mesh() const;

  // Holds the base face prepared (Hold) until as many Release calls: the last frees it; a
  // Release without a Hold breaks the contract (PATCHSCAN_DCHECK; a release build ignores
  // it). A face evaluated without a hold stays prepared until a hold on it ends. A face must not be
  // evaluated by one thread while another releases its last hold.
  // fit: the holder evaluates the face many times (a scan: thousands of times), so the
  // bicubic and Gregory pieces Evaluate takes are fitted first (~25 evaluations of a
  // regular face, ~150 to ~250 of an irregular one) if they are not yet; without, Evaluate
  // is Bfr's.
  void Hold(bool fit = false) const;
  void Release() const;
  // Base faces of this face's cage prepared now, preparations so far and the most prepared
  // at once (for tests and statistics; the boxes' preparations at load are not counted).
  long PreparedNow() const;
  long Preparations() const;
  long PeakPrepared() const;

  // The sub-face's (u, v) to the face's Bfr coordinates (U, V), bilinearly: c00 + eu u + ev
  // v + twist u v (affine, twist 0, for Bfr's quadrangulated sub-faces; the identity for a
  // quadrilateral). Public for subdiv.cpp's free helpers (Bfr evaluation through the map,
  // and the fitting of bicubic pieces, which see no SubdivFace), not for other users.
  struct SubFaceMap {
    double c00[2] = {0.0, 0.0}, eu[2] = {1.0, 0.0}, ev[2] = {0.0, 1.0}, twist[2] = {0.0, 0.0};
    // The map at (u, v): the face's Bfr coordinates, and the map's Jacobian columns
    // d(U, V)/du = (a00, a10) = eu + twist v and d(U, V)/dv = (a01, a11) = ev + twist u.
    struct Point {
      double uv[2];
      double a00, a10, a01, a11;
      // Chain rule: a derivative along u or v from the Bfr derivatives dU, dV.
      template <class V>
      V AlongU(const V& dU, const V& dV) const { return a00 * dU + a10 * dV; }
      template <class V>
      V AlongV(const V& dU, const V& dV) const { return a01 * dU + a11 * dV; }
    };
    Point At(double u, double v) const {
      return {{c00[0] + eu[0] * u + ev[0] * v + twist[0] * u * v, c00[1] + eu[1] * u + ev[1] * v + twist[1] * u * v},
              eu[0] + twist[0] * v, eu[1] + twist[1] * v, ev[0] + twist[0] * u, ev[1] + twist[1] * u};
    }
  };

 private:
  // The sub-face's bicubic pieces, if a hold has fitted them.
  const BicubicPieces* Pieces(const FaceData& face) const;

  std::shared_ptr<Cage> cage_;
  int face_;
  int subFace_;
  std::shared_ptr<const std::vector<Vec3>> hull_;
  SubFaceMap map_;
};

// Statistics of a cage, for `patchscan info`.
// boundedAtLoad: the faces whose box took their Bfr patch points at load (every face but
// the Catmull-Clark quadrilaterals of regular interior neighbourhood and the bilinear ones,
// whose boxes the cage's points give): prepared then and freed at once.
struct SubdivCounts {
  // irregularFaces: the faces Bfr approximates (Catmull-Clark and Loop; bilinear faces are exact).
  int faces = 0, vertices = 0, irregularFaces = 0, extraordinaryVertices = 0, holes = 0, surfaces = 0;
  int creaseEdges = 0, corners = 0, boundedAtLoad = 0;
  bool textureCoords = false;
};

// The surfaces of every face of `mesh` that is rendered (not a hole, nor a boundary face
// where interpolateBoundary is 0), each prepared on demand. Throws std::invalid_argument
// naming what is wrong with a cage that is not a valid mesh (indices out of range, a face of
// fewer than 3 vertices, a face using a vertex twice, a face of a Loop cage that is not a
// triangle, a non-manifold edge OpenSubdiv refuses, "st" of the wrong size).
std::vector<SubdivFace> PrepareSubdivFaces(const SubdivMesh& mesh, SubdivCounts* counts = nullptr);

// An independent reference for tests: every rendered base face tessellated by Bfr's own
// Tessellation pattern at `rate` segments per edge over the face's own parameterisation
// (not SubdivFace's sub-faces), each point evaluated by Bfr; object space, counter-clockwise
// as the faces. maxChordError: the largest distance, over every triangle's edge midpoints
// and centroid, between the surface at that point's parameters and the flat triangle there.
struct CageTessellation {
  std::vector<Vec3> points;
  std::vector<std::array<int, 3>> triangles;
  double maxChordError = 0.0;
};
CageTessellation TessellateCage(const SubdivMesh& mesh, int rate);

}  // namespace patchscan
