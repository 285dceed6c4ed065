#include "patch/tessellate.h"

#include <opensubdiv/bfr/tessellation.h>

#include <algorithm>
#include <cmath>

#include <Eigen/Geometry>

namespace patchscan {

namespace Bfr = OpenSubdiv::Bfr;

Vec3 WorldNormal(const Surface& s, double u, double v) {
  const Mat3 normalFromObject = s.worldFromObject.linear().inverse().transpose();
  SurfaceDerivs d;
  EvaluateObject(s, u, v, DerivOrder::First, &d);
  // A collapsed edge: the cross product is rounding.
  if (NormalVanishes(d.dpdu, d.dpdv)) {
    auto inward = [](double t) { return t < 0.5 ? kNormalNudge : (t > 0.5 ? -kNormalNudge : 0.0); };
    EvaluateObject(s, u + inward(u), v + inward(v), DerivOrder::First, &d);
  }
  const Vec3 n = d.dpdu.cross(d.dpdv);
  const Vec3 w = normalFromObject * n;
  const double len = w.norm();
  return len > 0.0 ? Vec3(w / len) : Vec3(0, 0, 1);
}

namespace {

// Appends the vertices and triangles of one Bfr tessellation pattern of s's domain.
void AppendPattern(const Surface& s, const Bfr::Tessellation& tess, std::uint32_t surfaceId,
                   TessMesh* out) {
  std::vector<double> coords(2 * static_cast<size_t>(tess.GetNumCoords()));
  std::vector<int> facets(3 * static_cast<size_t>(tess.GetNumFacets()));
  tess.GetCoords(coords.data());
  tess.GetFacets(facets.data());

  const auto base = static_cast<std::uint32_t>(out->vertices.size());
  for (int k = 0; k < tess.GetNumCoords(); ++k) {
    const double u = coords[2 * k], v = coords[2 * k + 1];
    SurfaceDerivs d;
    EvaluateObject(s, u, v, DerivOrder::Position, &d);
    out->vertices.push_back({s.worldFromObject * d.p, WorldNormal(s, u, v), Vec2(u, v), TextureCoordsAt(s, u, v).st});
  }
  // A trimmed NURBS piece keeps the triangles whose centroid in (u,v) its trim keeps: the
  // cut edge is as fine as the tessellation, and two pieces sharing a knot line decide
  // each side by the same rule.
  const PieceTrim* trim = TrimOf(s);
  for (int f = 0; f < tess.GetNumFacets(); ++f) {
    if (trim) {
      Vec2 c = Vec2::Zero();
      for (int i = 0; i < 3; ++i) c += Vec2(coords[2 * facets[3 * f + i]], coords[2 * facets[3 * f + i] + 1]) / 3.0;
      if (!trim->Kept(c)) continue;
    }
    out->triangles.push_back({base + static_cast<std::uint32_t>(facets[3 * f]),
                              base + static_cast<std::uint32_t>(facets[3 * f + 1]),
                              base + static_cast<std::uint32_t>(facets[3 * f + 2])});
    out->surfaceOf.push_back(surfaceId);
  }
}

// Screen length in pixels of a world-space polyline; infinity if a point is not in front
// of the eye.
double ScreenLength(const std::array<Vec3, 17>& world, const Mat4& screenFromWorld) {
  double len = 0.0;
  Vec2 prev;
  for (size_t k = 0; k < world.size(); ++k) {
    const Vec4 h = screenFromWorld * world[k].homogeneous();
    if (!(h.w() > 0.0)) return INFINITY;
    const Vec2 q = h.head<2>() / h.w();
    if (k > 0) len += (q - prev).norm();
    prev = q;
  }
  return len;
}

}  // namespace

void TessellateUniform(const Surface& s, int rate, std::uint32_t surfaceId, TessMesh* out) {
  const SurfaceHold hold(s);
  rate = std::clamp(rate, 1, kMaxTessRate);
  const Bfr::Parameterization quad(OpenSubdiv::Sdc::SCHEME_CATMARK, 4);
  AppendPattern(s, Bfr::Tessellation(quad, rate, Bfr::Tessellation::Options().SetFacetSize(3)),
                surfaceId, out);
}

namespace {

// Bfr's quad edge order: v=0, u=1, v=1, u=0.
constexpr PatchEdge kBfrEdges[4] = {PatchEdge::V0, PatchEdge::U1, PatchEdge::V1, PatchEdge::U0};
// Points sampled along a curve of the surface to size its tessellation: 16 segments.
constexpr int kRateSegments = 16;
using CurvePoints = std::array<Vec3, kRateSegments + 1>;

// World points along boundary edge e. For a bicubic patch the edge's Bézier points are
// taken in a canonical order and evaluated by de Casteljau: the same arithmetic in both
// patches that share the edge, so both give it the same rate.
CurvePoints EdgePoints(const Surface& s, PatchEdge e) {
  CurvePoints world;
  if (const auto* bicubic = std::get_if<BicubicPatch>(&s.shape)) {
    const auto& b = bicubic->BezierPoints();
    std::array<Vec3, 4> cv;
    for (int k = 0; k < 4; ++k) {
      const int i = e == PatchEdge::U0 ? 0 : e == PatchEdge::U1 ? 3 : k;
      const int j = e == PatchEdge::V0 ? 0 : e == PatchEdge::V1 ? 3 : k;
      cv[k] = s.worldFromObject * b[4 * j + i];
    }
    if (std::lexicographical_compare(cv[3].data(), cv[3].data() + 3, cv[0].data(), cv[0].data() + 3))
      std::reverse(cv.begin(), cv.end());
    for (int k = 0; k <= kRateSegments; ++k) {
      const double t = double(k) / kRateSegments;
      std::array<Vec3, 4> q = cv;
      for (int m = 3; m > 0; --m)
        for (int i = 0; i < m; ++i) q[i] = (1 - t) * q[i] + t * q[i + 1];
      world[k] = q[0];
    }
    return world;
  }
  for (int k = 0; k <= kRateSegments; ++k) {
    const double t = double(k) / kRateSegments;
    const double u = e == PatchEdge::U0 ? 0 : e == PatchEdge::U1 ? 1 : t;
    const double v = e == PatchEdge::V0 ? 0 : e == PatchEdge::V1 ? 1 : t;
    SurfaceDerivs d;
    EvaluateObject(s, u, v, DerivOrder::Position, &d);
    world[k] = s.worldFromObject * d.p;
  }
  return world;
}

// World points along the iso-line v = c (alongU) or u = c of the surface.
CurvePoints IsoPoints(const Surface& s, bool alongU, double c) {
  CurvePoints world;
  for (int k = 0; k <= kRateSegments; ++k) {
    const double t = double(k) / kRateSegments;
    SurfaceDerivs d;
    EvaluateObject(s, alongU ? t : c, alongU ? c : t, DerivOrder::Position, &d);
    world[k] = s.worldFromObject * d.p;
  }
  return world;
}

// Pixels per world unit at world point p, across the view (the larger row of the screen
// map's Jacobian); infinity at or behind the eye.
double PixelsPerUnit(const Mat4& screenFromWorld, const Vec3& p) {
  const Vec4 h = screenFromWorld * p.homogeneous();
  if (!(h.w() > 0.0)) return INFINITY;
  const Eigen::Matrix<double, 1, 3> w = screenFromWorld.block<1, 3>(3, 0);
  const double jx = (screenFromWorld.block<1, 3>(0, 0) - (h.x() / h.w()) * w).norm() / h.w();
  const double jy = (screenFromWorld.block<1, 3>(1, 0) - (h.y() / h.w()) * w).norm() / h.w();
  return std::max(jx, jy);
}

// The segments a curve needs for a chord error of at most `errorPx` pixels: a chord over a
// parameter step h of a curve with second derivative c'' is off by h^2 |c''| / 8; c'' in
// pixels comes from the points' second differences (3D, so that depth and the normals'
// turn count too, not just the outline) scaled by the pixels per unit there.
int ChordRate(const CurvePoints& world, const Mat4& screenFromWorld, double errorPx) {
  double worst = 0.0;  // max |c''| in pixels per unit parameter squared
  for (int k = 0; k <= kRateSegments; ++k) {
    const double ppu = PixelsPerUnit(screenFromWorld, world[k]);
    if (!std::isfinite(ppu)) return kMaxAdaptiveRate;
    if (k == 0 || k == kRateSegments) continue;
    const double d2 = (world[k - 1] - 2.0 * world[k] + world[k + 1]).norm() * kRateSegments * kRateSegments;
    worst = std::max(worst, d2 * ppu);
  }
  const double wanted = std::ceil(std::sqrt(worst / (8.0 * errorPx)));
  return wanted < kMaxAdaptiveRate ? std::max(1, static_cast<int>(wanted)) : kMaxAdaptiveRate;
}

// The segments a curve needs for tessellation edges about `pixels` long on the screen.
int LengthRate(const CurvePoints& world, const Mat4& screenFromWorld, double pixels) {
  const double wanted = std::ceil(ScreenLength(world, screenFromWorld) / pixels);  // infinite behind the eye
  return wanted < kMaxAdaptiveRate ? std::max(1, static_cast<int>(wanted)) : kMaxAdaptiveRate;
}

// True when the curve is one point (a collapsed edge: a sphere's pole, a cone's apex), to
// kCollapsedRel of the surface's size.
bool Collapsed(const CurvePoints& world, double size) {
  for (const Vec3& p : world)
    if ((p - world[0]).norm() > kCollapsedRel * size) return false;
  return true;
}

// True when the normal of `s` turns along its collapsed edge `e` (a cone point): the
// limits from inside at a quarter, half and three quarters along differ by more than
// kConePointTurnRad.
constexpr double kConePointTurnRad = 1e-3;
bool NormalTurnsAlong(const Surface& s, PatchEdge e) {
  auto at = [&](double t) {
    const double u = e == PatchEdge::U0 ? 0 : e == PatchEdge::U1 ? 1 : t;
    const double v = e == PatchEdge::V0 ? 0 : e == PatchEdge::V1 ? 1 : t;
    return WorldNormal(s, u, v);
  };
  const Vec3 mid = at(0.5);
  return std::max(at(0.25).cross(mid).norm(), at(0.75).cross(mid).norm()) > kConePointTurnRad;
}

// The cells of a trimmed NURBS piece's inner grid are at most this long on the screen.
constexpr double kTrimTessPx = 1.0;

// Rings around a cone point are at most this wide on the screen.
constexpr double kConePointRingPx = 2.0;

// The edge rates of `s` by rateOf(curve points), then its two inner rates: the most any
// of kInnerIsoLines - 1 interior iso-lines needs, and no fewer than the edges along them
// (a collapsed edge's rate 1 must not set the inner rate: Bfr would infer it so).
// `refineInner(rates)` may raise the inner rates further; then a collapsed edge takes the
// inner rate along it (so does a quadric's straight edge, below): its vertices are one point but carry the normal and uv of their
// own u (a cone's apex has a normal for each direction; with two vertices there every
// triangle at the apex took the normal of u = 0). Its neighbours meet it at that one point
// whatever its rate, so no crack opens.
template <class RateOf, class RefineInner>
std::array<int, 6> RatesOf(const Surface& s, const Mat4& screenFromWorld, RateOf&& rateOf, RefineInner&& refineInner) {
  std::array<int, 6> rates;
  std::array<bool, 4> collapsed;
  const double size = WorldBounds(s).Diagonal().norm();
  for (int e = 0; e < 4; ++e) {
    const CurvePoints edge = EdgePoints(s, kBfrEdges[e]);
    rates[e] = rateOf(edge);
    collapsed[e] = Collapsed(edge, size);
  }
  rates[4] = std::max(collapsed[0] ? 1 : rates[0], collapsed[2] ? 1 : rates[2]);
  rates[5] = std::max(collapsed[1] ? 1 : rates[1], collapsed[3] ? 1 : rates[3]);
  for (int k = 1; k < kInnerIsoLines; ++k) {
    const double c = double(k) / kInnerIsoLines;
    rates[4] = std::max(rates[4], rateOf(IsoPoints(s, true, c)));
    rates[5] = std::max(rates[5], rateOf(IsoPoints(s, false, c)));
  }
  refineInner(&rates);
  // A trimmed NURBS piece keeps whole triangles (AppendPattern): its inner grid is made
  // fine enough on the screen for the cut edge to be a staircase of kTrimTessPx steps.
  // Its edges take the inner rates too: Bfr would stitch a coarser edge to the grid in
  // slivers whose centroid the trim may keep though they run far outside it (a flat CAD
  // face's rectangle, its edges of rate 1, drew its outline round its round trim).
  if (TrimOf(s)) {
    for (int k = 0; k <= kInnerIsoLines; ++k) {
      const double c = double(k) / kInnerIsoLines;
      rates[4] = std::max(rates[4], LengthRate(IsoPoints(s, true, c), screenFromWorld, kTrimTessPx));
      rates[5] = std::max(rates[5], LengthRate(IsoPoints(s, false, c), screenFromWorld, kTrimTessPx));
    }
    for (int e = 0; e < 4; ++e) rates[e] = std::max(rates[e], rates[e % 2 == 0 ? 4 : 5]);
  }
  // A cone point: a collapsed edge whose normal turns along it (a cone's apex, unlike a
  // sphere's pole). Flat triangles there interpolate the normals of two directions over a
  // whole ring, a sawtooth of shading around the point; rings of kConePointRingPx keep it
  // within the pixels next to the point.
  for (int e = 0; e < 4; ++e)
    if (collapsed[e] && NormalTurnsAlong(s, kBfrEdges[e])) {
      const bool alongU = e % 2 == 0;
      const double across = ScreenLength(IsoPoints(s, !alongU, 0.5), screenFromWorld);
      const double wanted = std::ceil(across / kConePointRingPx);
      int& rate = rates[alongU ? 5 : 4];
      if (wanted > rate) rate = wanted < kMaxAdaptiveRate ? static_cast<int>(wanted) : kMaxAdaptiveRate;
    }
  // A quadric's edges meet no other surface's but its own seam (u = 0 and u = 1 are one
  // curve, given one rate here): a straight edge of one (rate 1: a ruling) takes the inner
  // rate along it, or Bfr fans it to the inner grid in long slivers across the twist (a
  // hyperboloid's, 1.4 px off at 0.4 asked). Patches and subdivision faces keep rates
  // from the edge alone, which their neighbours share.
  const bool ownEdges = !std::holds_alternative<BicubicPatch>(s.shape) && !std::holds_alternative<BilinearPatch>(s.shape) &&
                        !std::holds_alternative<SubdivFace>(s.shape) && !std::holds_alternative<NurbsPiece>(s.shape) &&
                        !std::holds_alternative<CurveRibbon>(s.shape);
  for (int e = 0; e < 4; ++e)
    if (collapsed[e] || (ownEdges && rates[e] == 1)) rates[e] = rates[e % 2 == 0 ? 4 : 5];  // 0 and 2 run along u
  // Where the edges differ from the inner rates, Bfr stitches the edges to an inner grid,
  // and with an inner rate of 1 that grid is one point, the domain's centre: every
  // triangle a fan to it. A cylinder (its straight v-lines rate 1) became a disc, each
  // triangle spanning half a turn. Two inner rows keep the stitching local along each edge.
  const bool uniform = rates[0] == rates[4] && rates[2] == rates[4] && rates[1] == rates[5] && rates[3] == rates[5];
  if (!uniform) {
    rates[4] = std::max(rates[4], 2);
    rates[5] = std::max(rates[5], 2);
  }
  return rates;
}

// The largest twist of `s` in pixels per unit parameter squared: |n . p_uv| from the
// mixed differences of a kTwistCells x kTwistCells grid, n the normal at each cell's
// centre, scaled by the pixels per unit at its corner; infinity if a point is not in front
// of the eye. A triangle's diagonal crosses its quad's twist: its midpoint is off the
// surface by h_u h_v |n . p_uv| / 4 (a hyperboloid's straight rulings need rate 1 along
// them, yet its quads are twisted). Only the normal part counts: a cone's or a disk's
// p_uv lies along the surface (their flat fans are on it).
constexpr int kTwistCells = 8;
double MaxTwistPx(const Surface& s, const Mat4& screenFromWorld) {
  std::array<std::array<Vec3, kTwistCells + 1>, kTwistCells + 1> p;
  for (int i = 0; i <= kTwistCells; ++i)
    for (int j = 0; j <= kTwistCells; ++j) {
      SurfaceDerivs d;
      EvaluateObject(s, double(i) / kTwistCells, double(j) / kTwistCells, DerivOrder::Position, &d);
      p[i][j] = s.worldFromObject * d.p;
    }
  double worst = 0.0;
  for (int i = 0; i < kTwistCells; ++i)
    for (int j = 0; j < kTwistCells; ++j) {
      const double ppu = PixelsPerUnit(screenFromWorld, p[i][j]);
      if (!std::isfinite(ppu)) return INFINITY;
      const Vec3 n = WorldNormal(s, (i + 0.5) / kTwistCells, (j + 0.5) / kTwistCells);
      const double twist =
          std::abs(n.dot(p[i + 1][j + 1] - p[i + 1][j] - p[i][j + 1] + p[i][j])) * kTwistCells * kTwistCells;
      worst = std::max(worst, twist * ppu);
    }
  return worst;
}

void AppendRates(const Surface& s, const std::array<int, 6>& rates, std::uint32_t surfaceId, TessMesh* out) {
  const Bfr::Parameterization quad(OpenSubdiv::Sdc::SCHEME_CATMARK, 4);
  AppendPattern(s, Bfr::Tessellation(quad, 6, rates.data(), Bfr::Tessellation::Options().SetFacetSize(3)),
                surfaceId, out);
}

}  // namespace

std::array<int, 4> ScreenEdgeRates(const Surface& s, const Camera& camera, double pixels) {
  const SurfaceHold hold(s);
  const Mat4 screenFromWorld = ScreenFromWorld(camera);
  std::array<int, 4> rates;
  for (int e = 0; e < 4; ++e) rates[e] = LengthRate(EdgePoints(s, kBfrEdges[e]), screenFromWorld, pixels);
  return rates;
}

std::array<int, 6> ChordErrorRates(const Surface& s, const Camera& camera, double errorPx) {
  const SurfaceHold hold(s);
  const Mat4 screenFromWorld = ScreenFromWorld(camera);
  const double curveErrorPx = kCurveShareOfChordError * errorPx;
  // The twist's error h_u h_v T / 4 held to the same share: the smaller inner rate is
  // raised first (it is the one the iso-lines found straight).
  auto twist = [&](std::array<int, 6>* rates) {
    const double t = MaxTwistPx(s, screenFromWorld);
    if (!std::isfinite(t)) {
      (*rates)[4] = (*rates)[5] = kMaxAdaptiveRate;
      return;
    }
    int& lo = (*rates)[4] <= (*rates)[5] ? (*rates)[4] : (*rates)[5];
    const int hi = std::max((*rates)[4], (*rates)[5]);
    const double wanted = std::ceil(t / (4.0 * curveErrorPx * hi));
    if (wanted > lo) lo = wanted < kMaxAdaptiveRate ? static_cast<int>(wanted) : kMaxAdaptiveRate;
  };
  return RatesOf(s, screenFromWorld, [&](const CurvePoints& c) { return ChordRate(c, screenFromWorld, curveErrorPx); },
                 twist);
}

void TessellateToChordError(const Surface& s, const Camera& camera, double errorPx, std::uint32_t surfaceId,
                            TessMesh* out) {
  const SurfaceHold hold(s);
  AppendRates(s, ChordErrorRates(s, camera, errorPx), surfaceId, out);
}

void TessellateToScreen(const Surface& s, const Camera& camera, double pixels,
                        std::uint32_t surfaceId, TessMesh* out) {
  const SurfaceHold hold(s);
  const Mat4 screenFromWorld = ScreenFromWorld(camera);
  AppendRates(s,
              RatesOf(s, screenFromWorld, [&](const CurvePoints& c) { return LengthRate(c, screenFromWorld, pixels); },
                      [](std::array<int, 6>*) {}),
              surfaceId, out);
}

}  // namespace patchscan

#include <cmath>
#include <unordered_map>

namespace patchscan {

std::size_t WeldBoundaryVertices(TessMesh* mesh, double tolerance) {
  // A hash grid of cell size `tolerance`: a match lies in one of the 27 cells around. Cells
  // are indexed by the floored quotients kept as doubles, which hold any magnitude (far
  // beyond 2^63 / tolerance, where an integer index would overflow); the hash mixes their
  // bits in unsigned arithmetic.
  struct Key {
    double x, y, z;
    bool operator==(const Key&) const = default;
  };
  struct KeyHash {
    size_t operator()(const Key& k) const {
      const std::hash<double> h;
      return h(k.x) * 73856093u ^ h(k.y) * 19349663u ^ h(k.z) * 83492791u;
    }
  };
  if (!(tolerance > 0.0)) return 0;
  std::unordered_map<Key, std::vector<std::uint32_t>, KeyHash> grid;
  auto cell = [&](const Vec3& p) {
    return Key{std::floor(p.x() / tolerance), std::floor(p.y() / tolerance), std::floor(p.z() / tolerance)};
  };
  std::size_t moved = 0;
  for (std::uint32_t i = 0; i < mesh->vertices.size(); ++i) {
    TessVertex& v = mesh->vertices[i];
    if (!(v.uv.x() == 0 || v.uv.x() == 1 || v.uv.y() == 0 || v.uv.y() == 1)) continue;
    const Key c = cell(v.position);
    const TessVertex* match = nullptr;
    for (double dz = -1; dz <= 1 && !match; ++dz)
      for (double dy = -1; dy <= 1 && !match; ++dy)
        for (double dx = -1; dx <= 1 && !match; ++dx) {
          auto it = grid.find({c.x + dx, c.y + dy, c.z + dz});
          if (it == grid.end()) continue;
          for (std::uint32_t j : it->second)
            if ((mesh->vertices[j].position - v.position).norm() <= tolerance) {
              match = &mesh->vertices[j];
              break;
            }
        }
    if (match) {
      if (match->position != v.position) ++moved;
      v.position = match->position;
    } else {
      grid[c].push_back(i);
    }
  }
  return moved;
}

}  // namespace patchscan
