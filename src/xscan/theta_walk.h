// The θ-sampled X scan of one surface on one scan line (paper 001 §4). The cross-section
// of the surface in the scan plane (the plane through the eye and the scan line) is
// sampled where the angle θ of its normal takes one of N tabulated values, θ_i = 2πi/N
// (§4.1: points cluster where the curve turns fast). In perspective (DESIGN.md) the
// surface normal N is resolved in the scan plane into T = -N·r, towards the eye along the
// view ray r (zero on the silhouette), and S = N·s, sideways along s = r × n, n the scan
// plane's normal; θ = atan2(T, S) and G_i = S sin θ_i - T cos θ_i.
//
// Each curve is crawled along at constant y ("sideways", §4.2) from its boundary end or,
// closed, from a silhouette tracker, taking steps in which θ turns by at most half a table
// step; a vertex is made where θ passes a tabulated angle, at every silhouette point (θ = 0
// or π: where the x extent of the section ends, so coverage along the row is exact), at
// both boundary ends, and where the normal has turned a table step out of the scan plane
// since the last vertex (a turn θ does not see). The chain of vertices, in order along the curve, is the polygon that
// approximates the section; each sample between two vertices gets a fragment interpolated
// perspective-correctly along that chord.
//
// Chord error: a section of radius of curvature R (pixels) sampled every Δθ = 2π/N is
// approximated by chords whose largest distance from the arc is R (1 - cos(π/N)) ≈
// R π² / (2 N²) pixels; with the silhouette points as vertices that error is in depth and
// normal, not in the row's coverage.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <span>
#include <vector>

#include "xscan/level_walk.h"

namespace patchscan {

// Counters of the θ chains.
struct ThetaStats {
  long nChains = 0, nVertices = 0, nSteps = 0;
  long nTurnPoints = 0;  // vertices where θ turned back (§4.3)
  long nTilts = 0;       // vertices where the normal turned out of the scan plane
};

// A vertex of a θ chain: its screen x, its surface point, and why it is a vertex: an end
// on the boundary (or a closed chain's start), a tabulated angle θ_index, a silhouette
// point (θ = 0 or π), a turn point (§4.3), or a tilt: the normal turned out of the scan
// plane by a table step since the last vertex.
struct ThetaVertex {
  enum class Kind : std::uint8_t { End, Table, Silhouette, Turn, Tilt };
  double x;
  raster::Fragment f;
  Kind kind = Kind::End;
  int index = -1;  // Table: i in θ_i = 2πi/N, 0 < i < N, i != N/2
};

// Receives every θ chain as it is made (tests and diagnostics): one call per chain.
class ThetaChainSink {
 public:
  virtual void Chain(double ys, int steps, std::span<const ThetaVertex> chain) = 0;

 protected:
  ~ThetaChainSink() = default;
};

// The frame the angle θ is measured in: the eye and the camera's right vector (world).
struct ThetaFrame {
  Vec3 eye, right, forward;
  bool orthographic = false;  // view rays all along `forward`
  // θ of world normal n at world point p, in (-π, π].
  double Theta(const Vec3& p, const Vec3& n) const {
    const Vec3 r = orthographic ? forward : Vec3((p - eye).normalized());
    const Vec3 plane = right.cross(r).normalized();
    const Vec3 side = r.cross(plane);
    return std::atan2(-n.dot(r), n.dot(side));
  }
  // The angle of unit normal n out of the scan plane at p, in [-π/2, π/2]: what θ does
  // not see.
  double Tilt(const Vec3& p, const Vec3& n) const {
    const Vec3 r = orthographic ? forward : Vec3((p - eye).normalized());
    return std::asin(std::clamp(n.dot(right.cross(r).normalized()), -1.0, 1.0));
  }
};

template <class ShapeT>
class ThetaWalker : public LevelWalker<ShapeT> {
  using Base = LevelWalker<ShapeT>;

 public:
  // `steps`: N, the tabulated angles per turn.
  ThetaWalker(const ShapeT& shape, const ScreenMap& map, double ys, const raster::SampleColumns& cols,
              WalkStats* stats, WalkEvents* events, ThetaStats* theta, int steps, const ThetaFrame& frame)
      : Base(shape, map, ys, cols, stats, events), theta_(theta), steps_(steps), frame_(frame),
        table_(2.0 * std::numbers::pi / steps) {}

  using Vertex = ThetaVertex;

  // Walks every chain of the row: Make(const WalkPoint&) -> raster::Fragment;
  // Take(std::span<const Vertex> chain, bool closed) receives each chain. `chain` is
  // scratch.
  template <class Make, class Take>
  void WalkAll(const RowTrackers& t, std::vector<char>* edgeUsed, std::vector<char>* silUsed,
               std::vector<Vertex>* chain, Make&& make, Take&& take);

  // Every chain made is also shown to `sink` (none by default).
  void SetChainSink(ThetaChainSink* sink) { sink_ = sink; }

 private:
  template <class Make>
  Vertex MakeVertex(const WalkPoint& p, Make& make, ThetaVertex::Kind kind = ThetaVertex::Kind::End,
                    int index = -1) const {
    return {p.x, make(p), kind, index};
  }
  double ThetaOf(const raster::Fragment& f) const { return frame_.Theta(f.position, f.normal); }
  static double Wrap(double a) {  // into (-π, π]
    while (a > std::numbers::pi) a -= 2.0 * std::numbers::pi;
    while (a <= -std::numbers::pi) a += 2.0 * std::numbers::pi;
    return a;
  }

  // Walks one chain from `start` with `sense`, appending its vertices to *chain.
  template <class Make>
  void Crawl(const WalkPoint& start, double sense, bool closed, std::vector<Vertex>* chain, Make& make);

  ThetaStats* theta_;
  int steps_;
  ThetaFrame frame_;
  double table_;  // 2π / N
  ThetaChainSink* sink_ = nullptr;
};

template <class ShapeT>
template <class Make, class Take>
void ThetaWalker<ShapeT>::WalkAll(const RowTrackers& t, std::vector<char>* edgeUsed,
                                  std::vector<char>* silUsed, std::vector<Vertex>* chain,
                                  Make&& make, Take&& take) {
  this->trackers_ = &t;
  this->edgeUsed_ = edgeUsed;
  this->silUsed_ = silUsed;
  edgeUsed->assign(t.edgePoints.size(), 0);
  silUsed->assign(t.silhouettePoints.size(), 0);
  for (size_t k = 0; k < t.edgePoints.size(); ++k) {
    if ((*edgeUsed)[k]) continue;
    (*edgeUsed)[k] = 1;
    ++this->stats_->nWalks;
    const WalkPoint p = this->Eval(t.edgePoints[k]);
    if (!p.ok) {
      this->Failed(t.edgePoints[k]);
      continue;
    }
    const double sense = Base::InwardSense(p, t.edgeOf[k]);
    if (sense == 0.0) continue;
    chain->clear();
    Crawl(p, sense, false, chain, make);
    if (sink_) sink_->Chain(this->ys_, steps_, *chain);
    theta_->nVertices += static_cast<long>(chain->size());
    take(std::span<const Vertex>(*chain), false);
  }
  for (size_t k = 0; k < t.silhouettePoints.size(); ++k) {
    if ((*silUsed)[k]) continue;
    (*silUsed)[k] = 1;
    WalkPoint p = this->Eval(t.silhouettePoints[k]);
    if (!p.ok || std::abs(p.y - this->ys_) > 1e3 * kEdgeTolPx) continue;  // not a crossing
    ++this->stats_->nWalks;
    ++this->stats_->nClosedWalks;
    p.jn = 0.0;  // on the silhouette whatever rounding says
    chain->clear();
    Crawl(p, 1.0, true, chain, make);
    if (sink_) sink_->Chain(this->ys_, steps_, *chain);
    theta_->nVertices += static_cast<long>(chain->size());
    take(std::span<const Vertex>(*chain), true);
  }
}

template <class ShapeT>
template <class Make>
void ThetaWalker<ShapeT>::Crawl(const WalkPoint& start, double sense, bool closed,
                                std::vector<Vertex>* chain, Make& make) {
  ++theta_->nChains;
  chain->push_back(MakeVertex(start, make, closed ? ThetaVertex::Kind::Silhouette : ThetaVertex::Kind::End));
  WalkPoint p = start;
  double th = ThetaOf(chain->back().f);
  double lastTurn = 0.0;  // the sign θ last moved with (0: not yet)
  double tilt = frame_.Tilt(chain->back().f.position, chain->back().f.normal);  // at p
  std::size_t tiltCount = chain->size();  // chain size when tiltAtVertex was taken
  double tiltAtVertex = tilt;             // the tilt of the chain's last vertex
  double h = kWalkStepStart;
  const double cosTurn = std::cos(kWalkMaxTurn);
  // The tabulated angles passed going from θ = a by d (|d| < π), silhouettes aside
  // (they are found by the sign of J), each as a vertex on the arc from p to q.
  auto passTable = [&](const WalkPoint& from, double a, const WalkPoint& to, double d) {
    const double lo = std::min(a, a + d), hi = std::max(a, a + d);
    for (double i = std::floor(lo / table_) + 1.0; i * table_ <= hi; i += 1.0) {
      const double angle = Wrap(i * table_);
      if (std::abs(std::sin(angle)) < 1e-12) continue;  // 0 or π: a silhouette
      const double t = (i * table_ - a) / d;
      const WalkPoint v = this->Correct(from.uv + t * (to.uv - from.uv));
      const long index = static_cast<long>(i) % steps_;
      if (v.ok) chain->push_back(MakeVertex(v, make, ThetaVertex::Kind::Table, static_cast<int>(index < 0 ? index + steps_ : index)));
    }
  };
  // A turn point (§4.3: T = 0, the derivative of θ along the curve vanishes) between two
  // steps: the crawl point there is a vertex, within one step of it, so the chain follows
  // the crinkle even when no tabulated angle is passed. Every step that passes table
  // angles notes its change of θ, d, here first.
  auto noteTurn = [&](const WalkPoint& at, double d) {
    constexpr double kTurnRad = 1e-9;  // below this θ did not move
    if (std::abs(d) <= kTurnRad) return;
    if (lastTurn != 0.0 && (d > 0) != (lastTurn > 0) && std::abs(at.jn) > 1e-9) {
      chain->push_back(MakeVertex(at, make, ThetaVertex::Kind::Turn));
      ++theta_->nTurnPoints;
    }
    lastTurn = d;
  };
  for (long k = 0; k < this->MaxSteps(); ++k) {
    if (h < kWalkStepMin) break;
    ++theta_->nSteps;
    const Vec2d tan = Base::Tangent(p, sense);
    const Vec2d q = p.uv + h * tan;
    WalkPoint next;
    bool ok = false;
    if (Base::Inside(q)) {
      next = this->Correct(q);
      ok = next.ok;
    }
    if (!Base::Inside(q) || (ok && !Base::Inside(next.uv))) {
      WalkPoint e;
      if (this->ExitPoint(p, Base::Inside(q) ? next.uv : q, &e) &&
          (e.uv - p.uv).norm() <= 2.0 * h + kSameCrossingUv && Base::Tangent(e, sense).dot(tan) >= cosTurn) {
        const Vertex ve = MakeVertex(e, make);
        const double d = Wrap(ThetaOf(ve.f) - th);
        const double dTilt = frame_.Tilt(ve.f.position, ve.f.normal) - tilt;
        if ((std::abs(d) <= table_ && std::abs(dTilt) <= table_) || h <= 4.0 * kWalkStepMin) {
          WalkPoint s;
          if (std::abs(p.jn) > 1e-9 && (p.j > 0) != (e.j > 0) && this->LocateSilhouette(p, e, &s)) {
            if (!this->UseSilhouetteTracker(s.uv)) this->Repaired(s.uv, &WalkStats::nUntrackedSilhouettes);
            chain->push_back(MakeVertex(s, make, ThetaVertex::Kind::Silhouette));
          } else {
            noteTurn(p, d);
            passTable(p, th, e, d);
          }
          chain->push_back(ve);
          if (!this->UseEdgeTracker(e.uv)) this->Repaired(e.uv, &WalkStats::nUntrackedExits);
          return;
        }
      }
      h *= 0.5;
      continue;
    }
    if (!ok || (next.uv - p.uv).norm() > 2.0 * h + kSameCrossingUv ||
        Base::Tangent(next, sense).dot(tan) < cosTurn) {
      h *= 0.5;
      continue;
    }
    const raster::Fragment fn = make(next);
    const double thn = ThetaOf(fn);
    const double d = Wrap(thn - th);
    const double tiltNext = frame_.Tilt(fn.position, fn.normal);
    // Steps turn θ, and the normal out of the scan plane, by at most half a table step.
    if ((std::abs(d) > 0.5 * table_ || std::abs(tiltNext - tilt) > 0.5 * table_) && h > 4.0 * kWalkStepMin) {
      h *= 0.5;
      continue;
    }
    const bool onSil = std::abs(p.jn) <= 1e-9;
    WalkPoint s;
    if (!onSil && (p.j > 0) != (next.j > 0) && std::abs(next.jn) > 1e-9 && this->LocateSilhouette(p, next, &s)) {
      // The silhouette vertex; the table angles near it are within half a step of it.
      ++this->stats_->nSilhouettes;
      if (closed && (s.uv - start.uv).norm() <= kSameCrossingUv) {
        chain->push_back(chain->front());  // round: back at the start
        return;
      }
      if (!this->UseSilhouetteTracker(s.uv)) {
        this->Repaired(s.uv, &WalkStats::nUntrackedSilhouettes);
        if (this->events_) this->events_->untrackedSilhouettes.push_back(s.uv);
      }
      chain->push_back(MakeVertex(s, make, ThetaVertex::Kind::Silhouette));
    } else {
      noteTurn(p, d);
      passTable(p, th, next, d);
    }
    // The chord interpolates normals between its vertices: where θ stays within a table
    // step but the normal leaves the scan plane (a section crossing a ridge of the surface
    // at a slant), a vertex once it has turned a table step out of the plane bounds that
    // error too.
    if (chain->size() != tiltCount) {
      tiltCount = chain->size();
      tiltAtVertex = frame_.Tilt(chain->back().f.position, chain->back().f.normal);
    }
    if (std::abs(tiltNext - tiltAtVertex) >= table_) {
      chain->push_back({next.x, fn, ThetaVertex::Kind::Tilt, -1});
      ++theta_->nTilts;
    }
    p = next;
    th = thn;
    tilt = tiltNext;
    h = std::min(2.0 * h, kWalkStepMax);
  }
  this->Failed(p.uv);
}

// The fragments of a chain on its own scan line: one per sample column along its chords,
// interpolated perspective-correctly (orthographic: linearly). Emit(column, fragment).
template <class Emit>
void EmitThetaChain(std::span<const ThetaVertex> chain, const raster::SampleColumns& cols, bool orthographic,
                    Emit& emit) {
  if (chain.empty()) return;
  // A column exactly at the first vertex belongs to this chain.
  const int c0 = cols.Ceil(chain.front().x - kColumnEpsPx);
  if (c0 < cols.n && std::abs(cols.At(c0) - chain.front().x) <= kColumnEpsPx) emit(c0, chain.front().f);
  for (size_t k = 1; k < chain.size(); ++k) {
    const ThetaVertex &a = chain[k - 1], &b = chain[k];
    if (!(a.f.w > 0.0 && b.f.w > 0.0) || a.x == b.x) continue;
    const int dir = b.x > a.x ? 1 : -1;
    for (int c = dir > 0 ? cols.Ceil(a.x + kColumnEpsPx) : cols.Floor(a.x - kColumnEpsPx);
         c >= 0 && c < cols.n && dir * (cols.At(c) - b.x) <= kColumnEpsPx; c += dir) {
      // Along a straight chord 1/w is affine in screen x: perspective-correct weights
      // (orthographic: w itself is affine, and the weights are linear).
      const double t = std::clamp((cols.At(c) - a.x) / (b.x - a.x), 0.0, 1.0);
      const bool affine = orthographic;
      const double ia = affine ? 1.0 - t : (1.0 - t) / a.f.w, ib = affine ? t : t / b.f.w;
      const double inv = affine ? ia * a.f.w + ib * b.f.w : 1.0 / (ia + ib);
      const double wa = affine ? ia : ia * inv, wb = affine ? ib : ib * inv;
      raster::Fragment f = a.f;
      f.w = inv;
      f.position = wa * a.f.position + wb * b.f.position;
      f.normal = (wa * a.f.normal + wb * b.f.normal).normalized();
      if (!f.normal.allFinite()) f.normal = a.f.normal;
      f.uv = wa * a.f.uv + wb * b.f.uv;
      if (t > 0.5) f.duvdx = b.f.duvdx, f.duvdy = b.f.duvdy;
      emit(c, f);
    }
  }
}

}  // namespace patchscan
