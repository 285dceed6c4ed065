#include "xscan/theta_slab.h"

#include <algorithm>
#include <cmath>

namespace patchscan {
namespace {

std::size_t CountAnchors(std::span<const ThetaVertex> c) {
  if (c.size() < 2) return c.size();
  std::size_t n = 2;
  for (std::size_t k = 1; k + 1 < c.size(); ++k) n += c[k].kind == ThetaVertex::Kind::Silhouette;
  return n;
}

// The chord's parameter t along x where its cubics' parameter is p (raster::Chord::Cubics:
// p = R(t) near a silhouette at a, 1 - R(1 - t) near one at b, else t).
double ChordTAt(const raster::Chord::Cubics& c, double p) {
  if (c.root == 0) return p;
  const double r = c.root == 1 ? p : 1.0 - p;
  const double r0 = std::sqrt(c.u0), q = r * (1.0 - r0) + r0;
  const double s = c.u0 < 1.0 ? (q * q - c.u0) / (1.0 - c.u0) : r;
  return c.root == 1 ? s : 1.0 - s;
}

}  // namespace

void RefineChains(const ChainSet& in, const raster::SampleColumns& cols, bool orthographic, ChainSet* out) {
  out->v.clear();
  out->chains.clear();
  for (const ChainSet::Chain& chain : in.chains) {
    const auto c = in.Of(chain);
    const auto begin = static_cast<std::uint32_t>(out->v.size());
    for (std::size_t k = 0; k < c.size(); ++k) {
      if (k > 0) {
        const ThetaVertex &a = c[k - 1], &b = c[k];
        if (a.f.w > 0.0 && b.f.w > 0.0 && a.x != b.x) {
          const raster::Chord chord(a.x, a.f, b.x, b.f, orthographic, ChordSlopeOf(a, b), ChordSlopeOf(b, a));
          if (const raster::Chord::Cubics* cubics = chord.cubics()) {
            const double lo = std::min(a.x, b.x), hi = std::max(a.x, b.x);
            const int between = cols.Floor(hi - raster::kColumnEpsPx) - cols.Ceil(lo + raster::kColumnEpsPx) + 1;
            const auto xAt = [&](double p) { return a.x + ChordTAt(*cubics, p) * (b.x - a.x); };
            const double tMid = ChordTAt(*cubics, 0.5);
            const double stray = (chord.At(xAt(0.5)).normal - chord.BlendedNormal(tMid)).norm();
            const int pieces = std::min({static_cast<int>(std::ceil(std::sqrt(stray / kSlabNormalTolRad))),
                                         kMaxLinkPieces, std::max(between, 0) + 1});
            for (int i = 1; i < pieces; ++i) {
              ThetaVertex m;
              m.x = xAt(static_cast<double>(i) / pieces);
              m.f = chord.At(m.x);
              m.kind = ThetaVertex::Kind::Table;
              out->v.push_back(m);
            }
          }
        }
      }
      out->v.push_back(c[k]);
    }
    out->chains.push_back({begin, static_cast<std::uint32_t>(out->v.size()), chain.closed});
  }
}

raster::RasterVertex SlabVertex(const ThetaVertex& v, double y, bool orthographic) {
  raster::RasterVertex r;
  double w = v.f.w, x = v.x;
  // A chain's end on a boundary edge is a vertex of both surfaces sharing that edge, each
  // from its own tracker: equal to rounding, not bit for bit, and a sample lying on the
  // edge (a boundary seen exactly vertical, as a symmetric view puts it at a sample column)
  // fell between the two slabs' edge functions. Rounded to a grid (x to 2^-16 px, depth to
  // float), both surfaces' vertices are the same numbers, so one slab takes that sample
  // by the back end's tie rule; the vertex moves by under 1e-5 px.
  if (v.kind == ThetaVertex::Kind::End) {
    x = SlabEndX(x);
    w = static_cast<double>(static_cast<float>(w));
  }
  r.h = orthographic ? Vec3(x, y, 1.0) : Vec3(x * w, y * w, w);
  r.position = v.f.position;
  r.normal = v.f.normal;
  r.uv = v.f.uv;
  r.depth = w;
  return r;
}

void ChainAnchors(std::span<const ThetaVertex> chain, std::vector<std::uint32_t>* anchors) {
  anchors->clear();
  if (chain.empty()) return;
  anchors->push_back(0);
  for (std::size_t k = 1; k + 1 < chain.size(); ++k)
    if (chain[k].kind == ThetaVertex::Kind::Silhouette) anchors->push_back(static_cast<std::uint32_t>(k));
  if (chain.size() > 1) anchors->push_back(static_cast<std::uint32_t>(chain.size() - 1));
}

bool PairChains(const ChainSet& top, const ChainSet& bottom, std::vector<ChainPair>* pairs,
                std::vector<ThetaVertex>* ordered) {
  pairs->clear();
  ordered->clear();
  if (top.chains.size() != bottom.chains.size()) return false;
  for (const ChainSet* set : {&top, &bottom})
    for (const ThetaVertex& v : set->v)
      if (!(v.f.w > 0.0)) return false;
  std::vector<char> used(bottom.chains.size(), 0);
  for (std::uint32_t t = 0; t < top.chains.size(); ++t) {
    const auto a = top.Of(top.chains[t]);
    if (a.size() < 2) return false;
    const std::size_t anchors = CountAnchors(a);
    int best = -1;
    bool bestReversed = false;
    std::size_t bestStart = 0;
    double bestCost = INFINITY;
    for (std::uint32_t b = 0; b < bottom.chains.size(); ++b) {
      if (used[b] || bottom.chains[b].closed != top.chains[t].closed) continue;
      const auto c = bottom.Of(bottom.chains[b]);
      if (c.size() < 2 || CountAnchors(c) != anchors) continue;
      if (!top.chains[t].closed) {
        // The same boundary sides at the same ends, one way round or the other.
        const int s0 = DomainSide(a.front().uv), s1 = DomainSide(a.back().uv);
        for (const bool reversed : {false, true}) {
          const ThetaVertex& first = reversed ? c.back() : c.front();
          const ThetaVertex& last = reversed ? c.front() : c.back();
          if (DomainSide(first.uv) != s0 || DomainSide(last.uv) != s1) continue;
          const double cost = (first.uv - a.front().uv).norm() + (last.uv - a.back().uv).norm();
          if (cost < bestCost) bestCost = cost, best = static_cast<int>(b), bestReversed = reversed;
        }
      } else {
        // A closed chain starts and ends at a silhouette vertex: start the partner at its
        // silhouette vertex nearest this chain's start (both run the same way round).
        for (std::size_t k = 0; k + 1 < c.size(); ++k) {
          if (c[k].kind != ThetaVertex::Kind::Silhouette) continue;
          const double cost = (c[k].uv - a.front().uv).norm();
          if (cost < bestCost) bestCost = cost, best = static_cast<int>(b), bestStart = k;
        }
      }
    }
    if (best < 0) return false;
    used[best] = 1;
    const auto c = bottom.Of(bottom.chains[best]);
    const auto begin = static_cast<std::uint32_t>(ordered->size());
    if (!top.chains[t].closed) {
      ordered->insert(ordered->end(), c.begin(), c.end());
      if (bestReversed) std::reverse(ordered->begin() + begin, ordered->end());
    } else {
      // c.back() repeats c.front(): rotate the ring c[0..n-2] to start at bestStart, closed.
      const std::size_t n = c.size() - 1;
      for (std::size_t k = 0; k < n; ++k) ordered->push_back(c[(bestStart + k) % n]);
      ordered->push_back(c[bestStart]);
    }
    pairs->push_back({t, begin, static_cast<std::uint32_t>(ordered->size())});
  }
  return true;
}

}  // namespace patchscan
