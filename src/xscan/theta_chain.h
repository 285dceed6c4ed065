// θ chains (Blinn 1978 §4): a chain's vertices, a scan line's chains of one surface, and a
// chain handed to the back end as chords, each sample between two vertices interpolated
// perspective-correctly along its chord (xscan/theta_walk.h makes the chains).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <span>
#include <vector>

#include "raster/fragment.h"
#include "tracker/level_point.h"

namespace patchscan {

// A vertex of a θ chain: its screen x, its surface point, and why it is a vertex: an end
// on the boundary (or a closed chain's start), a tabulated angle θ_index, a silhouette
// point (θ = 0 or π), a turn point (§4.3), or a tilt: the normal turned out of the scan
// plane by a table step since the last vertex.
struct ThetaVertex {
  enum class Kind : std::uint8_t { End, Table, Silhouette, Turn, Tilt };
  double x;
  raster::Fragment f;  // f.uv: the texture coordinates (a face's "st" where it has them)
  Kind kind = Kind::End;
  int index = -1;  // Table: i in θ_i = 2πi/N, 0 < i < N, i != N/2
  // The unit normal's and the eye distance's derivatives per pixel along the row, the
  // tangents of its chords' interpolation (raster::Chord); NaN where unknown or not wanted.
  // On a silhouette, where they are infinite, per root pixel (d/d√|x - xs|) on the side
  // facing the eye (ThetaWalker::RootSlopes); negated for a chord to the side facing away.
  Vec3 dndx = Vec3::Constant(NAN);
  double dwdx = NAN;
  // θ and the tilt of f's normal (ThetaFrame::Angles), found once when the vertex is made:
  // the advance's and the crawl's tests ask for them several times a vertex; and the
  // tilt's rate along the row, radians per pixel of x (NaN without slopes, or on a
  // silhouette, where x stands still).
  double theta = NAN, tilt = NAN, tiltRate = NAN;
  // The unit normal in the view's frame (ThetaFrame::InView): (S, T, sin tilt).
  Vec3 inView = Vec3::Constant(NAN);
  // Where along the row the section's silhouette nearest the vertex is estimated to lie
  // (x itself on one; NaN without slopes): its chords take their attributes as roots of
  // the distance from it when it is near (raster::Chord).
  double silhouetteX = NAN;
  // The surface's parameters (u,v) at the vertex: what the trackers, the crawls and the
  // trim curves work in. Not f.uv, which is the texture coordinates.
  Vec2 uv = Vec2::Constant(NAN);
};

// Receives every θ chain as it is made (tests and diagnostics): one call per chain.
class ThetaChainSink {
 public:
  virtual void Chain(double ys, int steps, std::span<const ThetaVertex> chain) = 0;

 protected:
  ~ThetaChainSink() = default;
};

// The side of the domain [0,1]² a boundary point lies on: 0 v = 0, 1 u = 1, 2 v = 1, 3 u = 0.
inline int DomainSide(const Vec2& uv) {
  const double d[4] = {uv.y(), 1.0 - uv.x(), 1.0 - uv.y(), uv.x()};
  return static_cast<int>(std::min_element(d, d + 4) - d);
}

// The chains of one surface on one line: vertices of all chains end to end, and for each
// vertex its (u,v) on the line before if it was advanced from there and its tracker's
// rate d(u,v)/d(ys) if a tracker solved it (NaN if not), for the next line's prediction.
struct ChainSet {
  struct Chain {
    std::uint32_t begin, end;  // into v
    bool closed;
  };
  std::vector<ThetaVertex> v;
  std::vector<Vec2> before, rate;
  std::vector<Chain> chains;
  void Clear() {
    v.clear();
    before.clear();
    rate.clear();
    chains.clear();
  }
  void Add(std::span<const ThetaVertex> chain, bool closed) {
    chains.push_back({static_cast<std::uint32_t>(v.size()), static_cast<std::uint32_t>(v.size() + chain.size()), closed});
    v.insert(v.end(), chain.begin(), chain.end());
    before.resize(v.size(), Vec2(NAN, NAN));
    rate.resize(v.size(), Vec2(NAN, NAN));
  }
  std::span<const ThetaVertex> Of(const Chain& c) const { return {v.data() + c.begin, c.end - c.begin}; }
};

// θ's distance from the nearest silhouette angle, 0 or π.
inline double SilhouetteAngle(double theta) {
  const double a = std::abs(theta);
  return std::min(a, std::numbers::pi - a);
}

// How far past vertex v, away from its chord's other end `to`, the silhouette nearest it
// lies (ThetaVertex::silhouetteX): 0 on one; infinite where it lies the other way, is not
// known, or `to` is no farther from a silhouette in θ (v then lies nearer the middle of
// the section, where the estimate says little).
inline double SilhouetteGap(const ThetaVertex& v, const ThetaVertex& to) {
  if (v.kind == ThetaVertex::Kind::Silhouette) return 0.0;
  if (!(SilhouetteAngle(v.theta) < SilhouetteAngle(to.theta))) return INFINITY;
  const double gap = (v.x - v.silhouetteX) * (to.x > v.x ? 1.0 : -1.0);
  return gap >= 0.0 ? gap : INFINITY;  // false for NaN
}

// A turn point (θ standing still) this near a silhouette angle in θ (radians): the section
// there is all but edge-on, its x all but still, and its slopes per pixel, steep, hold
// only near it, as a silhouette's do; its silhouette estimate says nothing (θ does not move
// towards it). A chord from it takes no slopes there (a quadratic from its other end, or
// the blend): a tangent of several times the chord's turn swung the normal of a whole
// chord 25° off on one row of the teapot's base (θ4, turn at 0.047 rad). How the angle
// was chosen: docs/tuning.md.
constexpr double kTurnNearSilhouetteRad = 0.1;

// Vertex v's slopes for its chord to `to`: a silhouette's toward the side `to` lies on
// (θ > 0 faces the eye); none at a turn point all but on a silhouette.
inline raster::ChordSlope ChordSlopeOf(const ThetaVertex& v, const ThetaVertex& to) {
  const double gap = SilhouetteGap(v, to);
  if (v.kind == ThetaVertex::Kind::Turn && SilhouetteAngle(v.theta) < kTurnNearSilhouetteRad)
    return {Vec3::Constant(NAN), NAN, gap};
  if (gap != 0.0 || to.theta > 0.0) return {v.dndx, v.dwdx, gap};
  return {-v.dndx, -v.dwdx, gap};
}

// The fragments of a chain on its own scan line, handed to `out` as chords (raster::Chord):
// the first vertex's own column, then each link's columns, interpolated perspective-
// correctly (orthographic: linearly). Returns the number of samples covered.
inline long EmitThetaChain(std::span<const ThetaVertex> chain, const raster::SampleColumns& cols, bool orthographic,
                           raster::FragmentRow& out) {
  if (chain.empty()) return 0;
  const raster::Chord first(chain.front().x, chain.front().f, orthographic);
  long covered = first.ColumnsOn(cols).count;
  if (covered > 0) out.AddChord(first, cols);
  for (size_t k = 1; k < chain.size(); ++k) {
    const ThetaVertex &a = chain[k - 1], &b = chain[k];
    if (!(a.f.w > 0.0 && b.f.w > 0.0) || a.x == b.x) continue;
    const raster::Chord c(a.x, a.f, b.x, b.f, orthographic, ChordSlopeOf(a, b), ChordSlopeOf(b, a));
    const int n = c.ColumnsOn(cols).count;
    covered += n;
    if (n > 0) out.AddChord(c, cols);
  }
  return covered;
}

}  // namespace patchscan
