// Tessellation of surfaces into triangles with OpenSubdiv's Bfr::Tessellation pattern
// over the quad parameter domain, with exact positions, normals and uv at the vertices.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "patch/camera.h"
#include "patch/surface.h"

namespace patchscan {

struct TessVertex {
  Vec3 position;  // world space
  Vec3 normal;    // world space, unit; at a collapsed edge, the limit from inside
  Vec2 uv;        // the surface's parameters
  Vec2 st;        // its texture coordinates (TextureCoordsAt): uv, unless the scene gives "st"
};

struct TessMesh {
  std::vector<TessVertex> vertices;
  std::vector<std::array<std::uint32_t, 3>> triangles;
  std::vector<std::uint32_t> surfaceOf;  // per triangle
};

// Largest accepted rate: rate^2 * 2 triangles per surface must stay a sane count.
constexpr int kMaxTessRate = 4096;

// Appends `s` tessellated uniformly at `rate` segments per edge (1..kMaxTessRate).
void TessellateUniform(const Surface& s, int rate, std::uint32_t surfaceId, TessMesh* out);

// Appends `s` tessellated with per-edge rates chosen so that tessellation edges are about
// `pixels` long on the screen of `camera`. An edge's rate depends only on the edge curve
// itself (for bicubic patches, on its four control points in a canonical order), so two
// patches that share an edge give it the same rate and the mesh has no T-junctions; the
// inner rates come from interior iso-lines too (as for TessellateToChordError), so that a
// surface with collapsed edges (a sphere's poles) is not one segment around.
// Rates are 1..kMaxAdaptiveRate; an edge that reaches behind the eye gets the maximum.
constexpr int kMaxAdaptiveRate = 256;
// The four rates, in OpenSubdiv's quad edge order: v=0, u=1, v=1, u=0.
std::array<int, 4> ScreenEdgeRates(const Surface& s, const Camera& camera, double pixels);
void TessellateToScreen(const Surface& s, const Camera& camera, double pixels,
                        std::uint32_t surfaceId, TessMesh* out);

// Appends `s` tessellated so that no triangle is more than about `errorPx` pixels from
// the surface (chord error, estimated from second differences of 16 segments of each
// curve, in 3D scaled to pixels at each point, so that a curve seen end-on still counts).
// The edge rates depend only on the edge curve (as in TessellateToScreen); the two inner
// rates are the largest any of kInnerIsoLines - 1 interior iso-lines, or the edges along
// them, need, raised for the twist across the diagonals (the normal part of p_uv) and
// near a cone point (rings of at most 2 px around a collapsed edge whose normal turns
// along it). A collapsed edge, and a quadric's straight edge, take the inner rate along
// them; where the pattern is not uniform the inner rates are at least 2 (Bfr fans an
// inner rate of 1 to the domain's centre).
constexpr int kInnerIsoLines = 4;
// The iso-lines are held to this share of the error asked: a triangle's diagonal bends in
// both directions at once, and 16 samples miss a curve's sharpest point; with a share of 1
// triangles of the sphere and the teapot were measured up to 2.3 times the error asked
// (tests/patch/tessellate_test.cpp).
constexpr double kCurveShareOfChordError = 0.4;
// The chord error tess mode asks by default: within half a pixel, with room for the estimate.
constexpr double kDefaultChordErrorPx = 0.4;
// The four edge rates in Bfr's order (v=0, u=1, v=1, u=0), then the inner rates along u
// and along v.
std::array<int, 6> ChordErrorRates(const Surface& s, const Camera& camera, double errorPx);
void TessellateToChordError(const Surface& s, const Camera& camera, double errorPx, std::uint32_t surfaceId,
                            TessMesh* out);

// The world-space unit normal of `s` at (u,v). Where dp/du x dp/dv vanishes (a collapsed
// edge such as the teapot's lid apex), the normal is taken a step kNormalNudge towards
// the domain's centre, its limit along that path.
constexpr double kNormalNudge = 1e-6;
Vec3 WorldNormal(const Surface& s, double u, double v);

}  // namespace patchscan

namespace patchscan {

// Two surfaces that share a boundary curve evaluate it through different arithmetic
// (their own power forms), so their boundary vertices can differ in the last bits. This
// snaps every boundary vertex to the first boundary vertex found within `tolerance` of
// it, so that shared edges have bit-identical end points and the back end's tie rule
// covers each sample on them exactly once. Returns how many vertices moved.
constexpr double kWeldRelTol = 1e-10;  // of the mesh's extent: far above rounding, far below a pixel
std::size_t WeldBoundaryVertices(TessMesh* mesh, double tolerance);

}  // namespace patchscan
