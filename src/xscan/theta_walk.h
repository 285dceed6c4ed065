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
// From one scan line to the next the vertices are θ trackers (§4.1, §3.5): each Table
// vertex follows its own G_i = 0 by bivariate Newton on (y - ys, G_i) from a start
// extrapolated from its last two lines, damped where a step would flip the normal's
// in-plane direction or the sign of T; ends and silhouette vertices are the edge and
// silhouette trackers of the Y scan; a turn vertex follows the zeros of §4.3's turn
// function (θ's derivative along the level curve) by Newton on (y - ys, T). The chain
// keeps its order (the links of §4.2). Where a link looks suspicious — tilt vertices or a
// lost tracker between its ends on the line before, θ or the tilt turning more than a
// table step across it, θ's sense of rotation not reversing at a turn or reversing
// elsewhere, θ's rate at an end against the link (a turn pair born across a vertex), J
// changing sign, x running the other way, the link stretching — it is repaired sideways:
// crawled from its first vertex, creating a tracker at each tabulated angle passed, until
// the existing tracker at its other end is met (§4.2). A turn pair born inside a link and
// not yet reaching a vertex is not seen (nor by Blinn): θ wiggles there by less than the
// angles to the link's ends.
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

#include "tracker/theta_tracker.h"
#include "xscan/level_walk.h"

namespace patchscan {

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

// The side of the domain [0,1]² a boundary point lies on: 0 v = 0, 1 u = 1, 2 v = 1, 3 u = 0.
inline int DomainSide(const Vec2& uv) {
  const double d[4] = {uv.y(), 1.0 - uv.x(), 1.0 - uv.y(), uv.x()};
  return static_cast<int>(std::min_element(d, d + 4) - d);
}

// The chains of one surface on one line: vertices of all chains end to end, and for each
// vertex its (u,v) on the line before if it was advanced from there (NaN if it was made
// on this line), for the next line's extrapolation.
struct ChainSet {
  struct Chain {
    std::uint32_t begin, end;  // into v
    bool closed;
  };
  std::vector<ThetaVertex> v;
  std::vector<Vec2> before;
  std::vector<Chain> chains;
  void Clear() {
    v.clear();
    before.clear();
    chains.clear();
  }
  void Add(std::span<const ThetaVertex> chain, bool closed) {
    chains.push_back({static_cast<std::uint32_t>(v.size()), static_cast<std::uint32_t>(v.size() + chain.size()), closed});
    v.insert(v.end(), chain.begin(), chain.end());
    before.resize(v.size(), Vec2(NAN, NAN));
  }
  std::span<const ThetaVertex> Of(const Chain& c) const { return {v.data() + c.begin, c.end - c.begin}; }
};

// Below this θ did not move (a step, or a link between two vertices).
constexpr double kTurnRad = 1e-9;
// A link crawled sideways has reached its end tracker when the crawl makes the same
// vertex (kind, index) within this many pixels of it: ten times the solves' tolerance.
constexpr double kLinkMatchPx = 1e-5;
// A link longer in (u,v) than twice its length on the line before plus this has jumped
// (a tracker converged onto another stretch of the curve): a ring born at a maximum
// widens as √(Δy), by at most √2 from its first line to its second.
constexpr double kLinkStretchUv = 1e-3;

template <class ShapeT>
class ThetaWalker : public LevelWalker<ShapeT> {
  using Base = LevelWalker<ShapeT>;

 public:
  // `steps`: N, the tabulated angles per turn.
  ThetaWalker(const ShapeT& shape, const ScreenMap& map, double ys, const raster::SampleColumns& cols,
              Counters* counters, WalkEvents* events, int steps, const ThetaFrame& frame)
      : Base(shape, map, ys, cols, counters, events), steps_(steps), frame_(frame),
        table_(2.0 * std::numbers::pi / steps) {}

  using Vertex = ThetaVertex;

  // Walks every chain of the row: Make(const LevelPoint&) -> raster::Fragment;
  // Take(std::span<const Vertex> chain, bool closed) receives each chain. `chain` is
  // scratch.
  template <class Make, class Take>
  void WalkAll(const RowTrackers& t, std::vector<char>* edgeUsed, std::vector<char>* silUsed,
               std::vector<Vertex>* chain, Make&& make, Take&& take);

  // Every chain made is also shown to `sink` (none by default).
  void SetChainSink(ThetaChainSink* sink) { sink_ = sink; }

  // Advances the chains `from` of the line before to this line as θ trackers, in the same
  // order, into *to (the trackers of this line in `t`): false if a chain cannot be
  // advanced (a tracker lost, an end or silhouette with no tracker, a link whose sideways
  // repair does not meet its other end, a tracker of the line left over), and the line
  // must be crawled afresh. `extrapolate`: start each Newton iteration from the last two
  // lines' positions (§3.5), else from the last. `scratch` is scratch.
  template <class Make>
  bool Advance(const ChainSet& from, const RowTrackers& t, bool extrapolate, std::vector<char>* edgeUsed,
               std::vector<char>* silUsed, std::vector<Vertex>* scratch, ChainSet* to, Make&& make);

  // The θ tracker of table angle i on this line, and the turn tracker, from `start`
  // (tracker/theta_tracker.h).
  bool SolveTable(int i, const Vec2& start, LevelPoint* out, std::int64_t* iterations,
                  TableResidual* residual = nullptr) const {
    return SolveThetaTracker(this->shape_, this->map_, this->ys_, frame_, Angle(i), start, out, iterations, residual);
  }
  bool SolveTurn(const Vec2& start, LevelPoint* out, std::int64_t* iterations) const {
    return SolveTurnTracker(this->shape_, this->map_, this->ys_, frame_, start, out, iterations);
  }

  // (cos θ_i, sin θ_i).
  Vec2 Angle(int i) const {
    if (static_cast<std::size_t>(i) < frame_.angles.size()) return frame_.angles[static_cast<std::size_t>(i)];
    return Vec2(std::cos(i * table_), std::sin(i * table_));
  }

 private:
  template <class Make>
  Vertex MakeVertex(const LevelPoint& p, Make& make, ThetaVertex::Kind kind = ThetaVertex::Kind::End,
                    int index = -1) const {
    return {p.x, make(p), kind, index};
  }
  double ThetaOf(const raster::Fragment& f) const { return frame_.Theta(f.position, f.normal); }
  // The turn function at (u,v) (NaN where undefined).
  double TurnAt(const Vec2& uv) const { return patchscan::TurnAt(this->shape_, this->map_, frame_, uv); }
  static double Wrap(double a) {  // into (-π, π]
    while (a > std::numbers::pi) a -= 2.0 * std::numbers::pi;
    while (a <= -std::numbers::pi) a += 2.0 * std::numbers::pi;
    return a;
  }

  // Walks one chain from `start` with `sense`, appending its vertices to *chain. With a
  // `target`, crawls one link sideways instead: stops at the first vertex that is the
  // target (true), or fails at any other end or silhouette (false).
  template <class Make>
  // `turning`: the sense θ was turning in on arrival at `start` (0: unknown), so that a
  // turn point within the first step is seen.
  bool Crawl(const LevelPoint& start, double sense, bool closed, std::vector<Vertex>* chain, Make& make,
             const Vertex* target = nullptr, double turning = 0.0);
  // Whether v lies on the step from a to b: along the chord between its ends, and
  // within a quarter of its length off it.
  static bool WithinStep(const LevelPoint& a, const LevelPoint& b, const LevelPoint& v) {
    const Vec2 d = b.uv - a.uv;
    const double len2 = d.squaredNorm();
    if (!(len2 > 0.0)) return (v.uv - a.uv).norm() <= kSameCrossingUv;
    const double t = (v.uv - a.uv).dot(d) / len2;
    const double off = std::abs((v.uv - a.uv).x() * d.y() - (v.uv - a.uv).y() * d.x()) / std::sqrt(len2);
    constexpr double kSlack = 1e-3;  // of the step: rounding at its ends
    return t >= -kSlack && t <= 1.0 + kSlack && off <= 0.25 * std::sqrt(len2) + kSameCrossingUv;
  }
  // Whether x lies strictly between a and b (the vertices of a chain between anchors
  // run one way in x).
  static bool Between(double x, double a, double b) { return (x - a) * (b - x) > 0.0; }
  // Whether crawl vertex v is the link's target.
  static bool SameVertex(const Vertex& v, const Vertex& target) {
    return v.kind == target.kind && v.index == target.index && std::abs(v.x - target.x) <= kLinkMatchPx;
  }
  // Whether the link a-b advanced from A-B needs a sideways repair (see the top).
  bool Suspicious(const Vertex& A, const Vertex& B, const Vertex& a, const Vertex& b) const;

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
    ++(*this->counters_)[Counter::Walks];
    const LevelPoint p = this->Eval(t.edgePoints[k]);
    if (!p.ok) {
      this->Failed(t.edgePoints[k]);
      continue;
    }
    const double sense = Base::InwardSense(p, t.edgeOf[k]);
    if (sense == 0.0) continue;
    chain->clear();
    Crawl(p, sense, false, chain, make);
    if (sink_) sink_->Chain(this->ys_, steps_, *chain);
    (*this->counters_)[Counter::ThetaVertices] += static_cast<long>(chain->size());
    take(std::span<const Vertex>(*chain), false);
  }
  for (size_t k = 0; k < t.silhouettePoints.size(); ++k) {
    if ((*silUsed)[k]) continue;
    (*silUsed)[k] = 1;
    LevelPoint p = this->Eval(t.silhouettePoints[k]);
    if (!p.ok || std::abs(p.y - this->ys_) > 1e3 * kEdgeTolPx) continue;  // not a crossing
    ++(*this->counters_)[Counter::Walks];
    ++(*this->counters_)[Counter::ClosedWalks];
    p.jn = 0.0;  // on the silhouette whatever rounding says
    chain->clear();
    Crawl(p, 1.0, true, chain, make);
    if (sink_) sink_->Chain(this->ys_, steps_, *chain);
    (*this->counters_)[Counter::ThetaVertices] += static_cast<long>(chain->size());
    take(std::span<const Vertex>(*chain), true);
  }
}

template <class ShapeT>
template <class Make>
bool ThetaWalker<ShapeT>::Crawl(const LevelPoint& start, double sense, bool closed,
                                std::vector<Vertex>* chain, Make& make, const Vertex* target,
                                double turning) {
  if (!target) ++(*this->counters_)[Counter::ThetaChains];
  chain->push_back(MakeVertex(start, make, closed ? ThetaVertex::Kind::Silhouette : ThetaVertex::Kind::End));
  // A link's crawl: done at its target, lost at any other anchor.
  std::size_t checked = chain->size();
  auto linkEnd = [&](bool* found) {
    for (; checked < chain->size(); ++checked) {
      const Vertex& v = (*chain)[checked];
      if (SameVertex(v, *target)) {
        chain->resize(checked + 1);
        *found = true;
        return true;
      }
      if (v.kind == ThetaVertex::Kind::End || v.kind == ThetaVertex::Kind::Silhouette) {
        *found = false;
        return true;
      }
    }
    return false;
  };
  LevelPoint p = start;
  double th = ThetaOf(chain->back().f);
  double tilt = frame_.Tilt(chain->back().f.position, chain->back().f.normal);  // at p
  std::size_t tiltCount = chain->size();  // chain size when tiltAtVertex was taken
  double tiltAtVertex = tilt;             // the tilt of the chain's last vertex
  double h = kWalkStepStart;
  const double cosTurn = std::cos(kWalkMaxTurn);
  // The tabulated angles passed going from θ = a by d (|d| < π), silhouettes aside
  // (they are found by the sign of J), each as a vertex on the arc from p to q.
  auto passTable = [&](const LevelPoint& from, double a, const LevelPoint& to, double d) {
    const double lo = std::min(a, a + d), hi = std::max(a, a + d);
    for (double i = std::floor(lo / table_) + 1.0; i * table_ <= hi; i += 1.0) {
      const double angle = Wrap(i * table_);
      if (std::abs(std::sin(angle)) < 1e-12) continue;  // 0 or π: a silhouette
      // A crawl that starts at a tracker (a link's repair) starts on its angle: that
      // vertex is the start itself.
      constexpr double kOnAngleRad = 1e-8;
      if (std::abs(i * table_ - a) <= kOnAngleRad) continue;
      const double t = (i * table_ - a) / d;
      const long index = static_cast<long>(i) % steps_;
      const int k = static_cast<int>(index < 0 ? index + steps_ : index);
      // The vertex is the θ tracker itself (G_i = 0 on the line), by Newton from the
      // interpolated point; if that lands outside the step (near a turn point θ_i may be
      // crossed again close by), the interpolated point.
      const Vec2 guess = from.uv + t * (to.uv - from.uv);
      LevelPoint v;
      // It must also lie on from's side of `to` after the chain's last vertex (x runs one
      // way between anchors; a turn just placed beyond `from` may have passed it).
      auto inOrder = [&](const LevelPoint& w) { return w.ok && (w.x == chain->back().x || Between(w.x, chain->back().x, to.x)); };
      if (!SolveTable(k, guess, &v, &(*this->counters_)[Counter::ThetaCrawlIterations]) || !WithinStep(from, to, v) || !inOrder(v))
        v = this->Correct(guess);
      if (inOrder(v)) chain->push_back(MakeVertex(v, make, ThetaVertex::Kind::Table, k));
    }
  };
  // The sense θ last moved in (0: not known), at the start θ's rate along the walk, so that
  // a turn within the first step is seen.
  double lastTurn = turning;
  if (lastTurn == 0.0) {
    const double r = sense * TurnAt(start.uv);
    if (std::isfinite(r)) lastTurn = r;
  }
  LevelPoint before = start;  // the crawl point before p
  // A turn point (§4.3: T = 0, the derivative of θ along the curve vanishes) between two
  // steps is a vertex, so the chain follows the crinkle even when no tabulated angle is
  // passed: the turn tracker itself, by Newton from the crawl point (if that lands off the
  // two steps around it, the crawl point). Every step that passes table angles notes its
  // change of θ, d, here first.
  auto noteTurn = [&](const LevelPoint& at, const LevelPoint& to, double d) {
    if (std::abs(d) <= kTurnRad) return;
    if (lastTurn != 0.0 && (d > 0) != (lastTurn > 0) && std::abs(at.jn) > 1e-9) {
      // A tilt vertex made at `at` gives way to the turn.
      const bool tiltAt = chain->size() > 1 && chain->back().kind == ThetaVertex::Kind::Tilt && chain->back().f.uv == at.uv;
      if (tiltAt) {
        chain->pop_back();
        --(*this->counters_)[Counter::ThetaTilts];
        checked = std::min(checked, chain->size());
      }
      // x runs one way between anchors: the turn tracker must lie between the chain's last
      // vertex and the next crawl point (else it is another turn, and the crawl point is
      // taken).
      LevelPoint v;
      if (!SolveTurn(at.uv, &v, &(*this->counters_)[Counter::ThetaCrawlIterations]) || !WithinStep(before, to, v) || std::abs(v.jn) <= 1e-9 ||
          !Between(v.x, chain->back().x, to.x))
        v = at;
      chain->push_back(MakeVertex(v, make, ThetaVertex::Kind::Turn));
      ++(*this->counters_)[Counter::ThetaTurnPoints];
    }
    lastTurn = d;
  };
  // A link ending at a turn tracker ends on the step that passes it: θ may turn back
  // within a step and the crawl not see it (a turn point one step from the boundary).
  LevelPoint turnTarget;
  if (target && target->kind == ThetaVertex::Kind::Turn) turnTarget = this->Eval(target->f.uv);
  auto endsAtTurn = [&](const LevelPoint& to) {
    if (!turnTarget.ok || !WithinStep(p, to, turnTarget)) return false;
    passTable(p, th, turnTarget, Wrap(ThetaOf(target->f) - th));
    chain->push_back(*target);
    return true;
  };
  for (long k = 0; k < this->MaxSteps(); ++k) {
    if (h < kWalkStepMin) break;
    ++(*this->counters_)[Counter::ThetaSteps];
    const Vec2 tan = Base::Tangent(p, sense);
    const Vec2 q = p.uv + h * tan;
    LevelPoint next;
    bool ok = false;
    if (Base::Inside(q)) {
      next = this->Correct(q);
      ok = next.ok;
    }
    if (!Base::Inside(q) || (ok && !Base::Inside(next.uv))) {
      LevelPoint e;
      if (this->ExitPoint(p, Base::Inside(q) ? next.uv : q, &e) &&
          (e.uv - p.uv).norm() <= 2.0 * h + kSameCrossingUv && Base::Tangent(e, sense).dot(tan) >= cosTurn) {
        const Vertex ve = MakeVertex(e, make);
        const double d = Wrap(ThetaOf(ve.f) - th);
        const double dTilt = frame_.Tilt(ve.f.position, ve.f.normal) - tilt;
        if ((std::abs(d) <= table_ && std::abs(dTilt) <= table_) || h <= 4.0 * kWalkStepMin) {
          if (endsAtTurn(e)) return true;
          LevelPoint s;
          if (std::abs(p.jn) > 1e-9 && (p.j > 0) != (e.j > 0) && this->LocateSilhouette(p, e, &s)) {
            if (!this->UseSilhouetteTracker(s.uv)) this->Repaired(s.uv, Counter::UntrackedSilhouettes);
            chain->push_back(MakeVertex(s, make, ThetaVertex::Kind::Silhouette));
          } else {
            noteTurn(p, e, d);
            // A turn within the last step, before the boundary (θ's rate along the curve
            // changes sign between p and e): the steps are not continued to see it.
            LevelPoint v;
            const double rp = TurnAt(p.uv), re = TurnAt(e.uv);
            if (rp * re < 0.0 && SolveTurn(0.5 * (p.uv + e.uv), &v, &(*this->counters_)[Counter::ThetaCrawlIterations]) &&
                WithinStep(p, e, v) && std::abs(v.jn) > 1e-9 && Between(v.x, chain->back().x, e.x)) {
              const Vertex vt = MakeVertex(v, make, ThetaVertex::Kind::Turn);
              const double tv = ThetaOf(vt.f);
              passTable(p, th, v, Wrap(tv - th));
              chain->push_back(vt);
              ++(*this->counters_)[Counter::ThetaTurnPoints];
              passTable(v, tv, e, Wrap(ThetaOf(ve.f) - tv));
            } else {
              passTable(p, th, e, d);
            }
          }
          chain->push_back(ve);
          bool found = true;
          if (target) {
            linkEnd(&found);  // the exit is an anchor: the link ends here or before
            if (found && chain->back().kind != ThetaVertex::Kind::End) return true;  // before the exit
          }
          if (!this->UseEdgeTracker(e.uv)) this->Repaired(e.uv, Counter::UntrackedExits);
          return found;
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
    if (endsAtTurn(next)) return true;
    const bool onSil = std::abs(p.jn) <= 1e-9;
    LevelPoint s;
    if (!onSil && (p.j > 0) != (next.j > 0) && std::abs(next.jn) > 1e-9 && this->LocateSilhouette(p, next, &s)) {
      // The silhouette vertex; the table angles near it are within half a step of it.
      ++(*this->counters_)[Counter::SilhouettePoints];
      if (closed && (s.uv - start.uv).norm() <= kSameCrossingUv) {
        chain->push_back(chain->front());  // round: back at the start
        return true;
      }
      if (!this->UseSilhouetteTracker(s.uv)) {
        this->Repaired(s.uv, Counter::UntrackedSilhouettes);
        if (this->events_) this->events_->untrackedSilhouettes.push_back(s.uv);
      }
      chain->push_back(MakeVertex(s, make, ThetaVertex::Kind::Silhouette));
    } else {
      noteTurn(p, next, d);
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
      ++(*this->counters_)[Counter::ThetaTilts];
    }
    bool found = false;
    if (target && linkEnd(&found)) return found;
    before = p;
    p = next;
    th = thn;
    tilt = tiltNext;
    h = std::min(2.0 * h, kWalkStepMax);
  }
  this->Failed(p.uv);
  return false;
}

template <class ShapeT>
bool ThetaWalker<ShapeT>::Suspicious(const Vertex& A, const Vertex& B, const Vertex& a, const Vertex& b) const {
  // A tabulated angle strictly between the link's ends (θ is monotone along a link with
  // no turn point), or the tilt turning a table step: a vertex is missing.
  constexpr double kOnAngleRad = 1e-8;
  const double ta = ThetaOf(a.f), d = Wrap(ThetaOf(b.f) - ta);
  if (std::abs(d) > table_ + kOnAngleRad) return true;
  const double lo = std::min(ta, ta + d) + kOnAngleRad, hi = std::max(ta, ta + d) - kOnAngleRad;
  for (double i = std::floor(lo / table_) + 1.0; i * table_ < hi; i += 1.0)
    if (std::abs(std::sin(i * table_)) > 1e-12) return true;  // 0 and π are silhouettes
  if (std::abs(frame_.Tilt(b.f.position, b.f.normal) - frame_.Tilt(a.f.position, a.f.normal)) >= table_) return true;
  // A silhouette between two vertices that are none.
  const bool silA = a.kind == ThetaVertex::Kind::Silhouette, silB = b.kind == ThetaVertex::Kind::Silhouette;
  if (!silA && !silB && (a.f.normal.dot(frame_.orthographic ? frame_.forward : Vec3(a.f.position - frame_.eye)) > 0.0) !=
                            (b.f.normal.dot(frame_.orthographic ? frame_.forward : Vec3(b.f.position - frame_.eye)) > 0.0))
    return true;
  // x running the other way along the link, or the link stretched onto another stretch.
  const double dxTop = B.x - A.x, dx = b.x - a.x;
  if (std::abs(dxTop) > kColumnEpsPx && std::abs(dx) > kColumnEpsPx && (dxTop > 0) != (dx > 0)) return true;
  return (b.f.uv - a.f.uv).norm() > 2.0 * (B.f.uv - A.f.uv).norm() + kLinkStretchUv;
}

template <class ShapeT>
template <class Make>
bool ThetaWalker<ShapeT>::Advance(const ChainSet& from, const RowTrackers& t, bool extrapolate,
                                  std::vector<char>* edgeUsed, std::vector<char>* silUsed,
                                  std::vector<Vertex>* scratch, ChainSet* to, Make&& make) {
  this->trackers_ = &t;
  this->edgeUsed_ = edgeUsed;
  this->silUsed_ = silUsed;
  edgeUsed->assign(t.edgePoints.size(), 0);
  silUsed->assign(t.silhouettePoints.size(), 0);
  to->Clear();
  // The unused tracker of the line nearest to uv: an edge tracker on the same side of
  // the domain, or a silhouette tracker.
  auto nearest = [&](const std::vector<Vec2>& points, std::vector<char>* used, const Vec2& uv, int side) {
    int best = -1;
    double bestD = INFINITY;
    for (std::size_t k = 0; k < points.size(); ++k) {
      if ((*used)[k] || (side >= 0 && DomainSide(points[k]) != side)) continue;
      const double d = (points[k] - uv).squaredNorm();
      if (d < bestD) bestD = d, best = static_cast<int>(k);
    }
    if (best >= 0) (*used)[static_cast<std::size_t>(best)] = 1;
    return best;
  };
  for (const ChainSet::Chain& c : from.chains) {
    const auto A = from.Of(c);
    if (A.size() < 2) return false;
    // A ring's last vertex repeats its first.
    const std::size_t n = c.closed ? A.size() - 1 : A.size();
    if (c.closed && (A.back().f.uv - A.front().f.uv).norm() > kSameCrossingUv) return false;
    const auto begin = static_cast<std::uint32_t>(to->v.size());
    double sense = 1.0;  // along the chain's order (a ring is crawled with sense 1)
    LevelPoint last;      // the last vertex advanced, and its index in A
    std::size_t lastK = 0;
    bool skipped = false;  // tilt vertices or lost trackers of A since lastK
    double lastD = 0.0;    // θ's change along the chain's last link (0: none yet)
    // θ keeps its sense of rotation through a Table or Tilt vertex and reverses it at a
    // Turn (§4.3): the link from a to b breaks that rule.
    auto turnsWrong = [&](const Vertex& a, const Vertex& b) {
      const double d = Wrap(ThetaOf(b.f) - ThetaOf(a.f));
      if (std::abs(d) <= kTurnRad || lastD == 0.0) return false;
      const bool flips = (d > 0.0) != (lastD > 0.0);
      if (a.kind == ThetaVertex::Kind::Turn) return !flips;
      return (a.kind == ThetaVertex::Kind::Table || a.kind == ThetaVertex::Kind::Tilt) && flips;
    };
    // θ's rate along the chain at a vertex other than a turn must have the sense of the
    // links on both sides: against it, a turn has been born between (a pair across a
    // Table vertex, or one come in across the boundary beside an end).
    double lastRate = NAN;  // at `last` (NaN: a turn)
    auto againstRate = [&](const Vertex& a, const Vertex& b, double rateB) {
      const double d = Wrap(ThetaOf(b.f) - ThetaOf(a.f));
      return std::abs(d) > kTurnRad && (lastRate * d < 0.0 || rateB * d < 0.0);
    };
    // The link from `last` to b, repaired sideways if it looks suspicious; then b.
    auto link = [&](std::size_t k, const Vertex& b, const LevelPoint& pb, double rateB) {
      if (to->v.size() > begin) {
        const Vertex& a = to->v.back();
        // x runs one way through a vertex that is not an anchor.
        const bool xBack = to->v.size() >= begin + 2 && a.kind != ThetaVertex::Kind::End &&
                           a.kind != ThetaVertex::Kind::Silhouette &&
                           (a.x - to->v[to->v.size() - 2].x) * (b.x - a.x) < 0.0;
        if (skipped || xBack || turnsWrong(a, b) || againstRate(a, b, rateB) ||
            Suspicious(A[lastK], A[k % A.size()], a, b)) {
          ++(*this->counters_)[Counter::ThetaLinkRepairs];
          scratch->clear();
          if (!Crawl(last, sense, false, scratch, make, &b,
                     a.kind == ThetaVertex::Kind::Turn ? -lastD : lastD)) return false;
          for (std::size_t i = 1; i + 1 < scratch->size(); ++i) {
            to->v.push_back((*scratch)[i]);
            to->before.push_back(Vec2(NAN, NAN));
          }
        }
      }
      to->v.push_back(b);
      to->before.push_back(A[k % A.size()].f.uv);
      if (to->v.size() >= begin + 2) {
        const double d = Wrap(ThetaOf(b.f) - ThetaOf(to->v[to->v.size() - 2].f));
        if (std::abs(d) > kTurnRad) lastD = d;
      }
      last = pb;
      lastRate = rateB;
      lastK = k;
      skipped = false;
      return true;
    };
    for (std::size_t k = 0; k < n; ++k) {
      const Vertex& V = A[k];
      LevelPoint p;
      TableResidual residual;  // a Table vertex's G_i at its solution
      switch (V.kind) {
        case ThetaVertex::Kind::Tilt:
          skipped = true;
          continue;
        case ThetaVertex::Kind::Turn: {
          const Vec2& prev = from.before[c.begin + k];
          const Vec2 start = extrapolate && prev.allFinite() ? Vec2(2.0 * V.f.uv - prev) : V.f.uv;
          ++(*this->counters_)[Counter::ThetaTurnTrackers];
          // A turn tracker with no root near (its pair has met it and both are gone) is
          // dropped, and the link across its place repaired sideways.
          if (!SolveTurn(start, &p, &(*this->counters_)[Counter::ThetaTurnIterations])) {
            ++(*this->counters_)[Counter::ThetaTurnsLost];
            skipped = true;
            continue;
          }
          break;
        }
        case ThetaVertex::Kind::End: {
          const int e = nearest(t.edgePoints, edgeUsed, V.f.uv, DomainSide(V.f.uv));
          if (e < 0) return false;
          p = this->Eval(t.edgePoints[static_cast<std::size_t>(e)]);
          if (!p.ok) return false;
          if (k == 0) sense = Base::InwardSense(p, t.edgeOf[static_cast<std::size_t>(e)]);
          if (sense == 0.0) return false;
          break;
        }
        case ThetaVertex::Kind::Silhouette: {
          const int e = nearest(t.silhouettePoints, silUsed, V.f.uv, -1);
          if (e < 0) return false;
          p = this->Eval(t.silhouettePoints[static_cast<std::size_t>(e)]);
          if (!p.ok) return false;
          p.jn = 0.0;  // on the silhouette whatever rounding says
          break;
        }
        case ThetaVertex::Kind::Table: {
          const Vec2& prev = from.before[c.begin + k];
          const Vec2 start = extrapolate && prev.allFinite() ? Vec2(2.0 * V.f.uv - prev) : V.f.uv;
          ++(*this->counters_)[Counter::ThetaTrackers];
          // A tracker that leaves the patch or does not converge is dropped (§3.2: deleted
          // when it leaves [0,1]²); the link across its place is repaired sideways.
          if (!SolveTable(V.index, start, &p, &(*this->counters_)[Counter::ThetaTrackerIterations], &residual)) {
            ++(*this->counters_)[Counter::ThetaTrackersLost];
            skipped = true;
            continue;
          }
          break;
        }
      }
      // θ's rate along the chain (the sense it is walked in), but at a turn.
      double rate = NAN;
      if (V.kind == ThetaVertex::Kind::Table) {
        rate = sense * TurnRate(residual, p.gradY);
      } else if (V.kind != ThetaVertex::Kind::Turn) {
        rate = sense * TurnAt(p.uv);
      }
      if (!link(k, MakeVertex(p, make, V.kind, V.index), p, rate)) return false;
    }
    if (c.closed) {  // back round to the first vertex
      if (n + 1 > A.size() || to->v.size() == begin) return false;
      const Vertex first = to->v[begin];
      LevelPoint p0 = this->Eval(first.f.uv);
      p0.jn = 0.0;
      if (!link(n, first, p0, NAN)) return false;
    }
    to->chains.push_back({begin, static_cast<std::uint32_t>(to->v.size()), c.closed});
    (*this->counters_)[Counter::ThetaVertices] += static_cast<long>(to->v.size() - begin);
    if (sink_) sink_->Chain(this->ys_, steps_, to->Of(to->chains.back()));
  }
  // Every tracker of the line must be on a chain: one left over starts a chain the line
  // before did not have.
  for (char used : *edgeUsed)
    if (!used) return false;
  for (std::size_t k = 0; k < t.silhouettePoints.size(); ++k)
    if (!(*silUsed)[k]) {
      const LevelPoint p = this->Eval(t.silhouettePoints[k]);
      if (p.ok && std::abs(p.y - this->ys_) <= 1e3 * kEdgeTolPx) return false;  // a crossing (as WalkAll)
    }
  return true;
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
