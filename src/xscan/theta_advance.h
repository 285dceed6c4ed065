// The θ walker's advance from one scan line to the next (Blinn 1978 §4.1, §4.2, §3.5): each
// chain of the line before is carried over vertex by vertex, its θ and turn trackers
// solved by Newton from extrapolated starts and its ends and silhouettes taken from the Y
// scan's trackers, and a link that looks suspicious is repaired sideways by a crawl
// (theta_crawl.h), or, missing only tabulated vertices, filled by Newton. Included by
// theta_walk.h; not for use on its own.
#pragma once

#include <cmath>
#include <optional>
#include <vector>

#include "core/hermite.h"

namespace patchscan {

template <class ShapeT>
typename ThetaWalker<ShapeT>::LinkCheck ThetaWalker<ShapeT>::CheckLink(const Vertex& A, const Vertex& B, const Vertex& a,
                                                                      const Vertex& b) const {
  // A tabulated angle strictly between the link's ends (θ is monotone along a link with
  // no turn point), or more than a table step between them: vertices are missing, which
  // the link's other tests below may still find sound otherwise.
  const double ta = a.theta, tiltA = a.tilt, tiltB = b.tilt;
  const double d = Wrap(b.theta - ta);
  const bool missing = std::abs(d) > table_ + kOnAngleRad ||
                       !ForEachTableAngle(ta, d, false, [](double angle, int) { return SilhouetteAngle(angle); });
  const bool turnsTooFar = TurnsPastStep(a, b);
  // The tilt out of the scan plane along the link, as the cubic (Hermite's) from the ends'
  // tilts and rates along the row, going a table step beyond both ends' tilts between
  // them: an excursion of the normal the ends do not show, which a crawl would mark with
  // tilt vertices (one wherever the tilt has turned a table step) and the chord would blend
  // across. Not asked where an end's rate is unknown: without slopes (slabs), or at a
  // silhouette (unbounded: x stands still there).
  if (const double dx = b.x - a.x, ma = a.tiltRate * dx, mb = b.tiltRate * dx; std::isfinite(ma) && std::isfinite(mb)) {
    const double lo = std::min(tiltA, tiltB) - table_, hi = std::max(tiltA, tiltB) + table_;
    double cubic[4];
    HermiteCoefficients(tiltA, tiltB, ma, mb, true, true, cubic);
    for (const double t : {0.25, 0.5, 0.75}) {
      const double h = Horner(cubic, t);
      if (h < lo || h > hi) return LinkCheck::Broken;
    }
  }
  // A silhouette between two vertices that are none.
  const bool silA = a.kind == ThetaVertex::Kind::Silhouette, silB = b.kind == ThetaVertex::Kind::Silhouette;
  if (!silA && !silB && Facing(a) != Facing(b)) return LinkCheck::Broken;
  // x running the other way along the link, or the link stretched onto another stretch.
  const double dxTop = B.x - A.x, dx = b.x - a.x;
  if (std::abs(dxTop) > kColumnEpsPx && std::abs(dx) > kColumnEpsPx && (dxTop > 0) != (dx > 0)) return LinkCheck::Broken;
  if ((b.uv - a.uv).norm() > 2.0 * (B.uv - A.uv).norm() + kLinkStretchUv) return LinkCheck::Broken;
  // On slab lines such a link is crawled (below: the tilt tracker).
  if (turnsTooFar) return missing || !rowChords_ ? LinkCheck::Broken : LinkCheck::Split;
  return missing ? LinkCheck::MissingTable : LinkCheck::Sound;
}

template <class ShapeT>
template <class Make>
bool ThetaWalker<ShapeT>::SplitLink(const Vertex& a, const Vertex& b, std::vector<Vertex>* out, Make& make) {
  out->clear();
  out->push_back(a);
  if (!SplitInto(a, b, kSplitMaxDepth, LinkFacing(a, b), out, make)) return false;
  out->push_back(b);
  return true;
}

template <class ShapeT>
template <class Make>
bool ThetaWalker<ShapeT>::SplitInto(const Vertex& a, const Vertex& b, int depth, std::optional<bool> facing,
                                    std::vector<Vertex>* out, Make& make) {
  // A chord no sample column crosses is never interpolated (TurnsPastStep).
  if (!SamplesBetween(a.x, b.x)) return true;
  // The line's point found from the middle of the link's chord in (u,v) as a tilt tracker
  // is, between the ends in x. The link stays whole if its normal turns less than a step
  // and its chord (the ends' Hermite cubics, as the back end draws it) meets the surface's
  // normal there within the crawl's bound (ThetaTable::kChordSplitStep).
  LevelPoint p;
  ++Count(Counter::ThetaTiltTrackers);
  if (!SolveTiltTracker(this->shape_, this->map_, this->ys_, 0.5 * (a.uv + b.uv), &p,
                        &Count(Counter::ThetaTiltIterations), nullptr, DerivOrder::First) ||
      !Between(p.x, a.x, b.x))
    return false;
  const raster::Fragment f = make(p);
  if (!TurnsPastStep(a, b)) {
    const raster::Chord chord(a.x, a.f, b.x, b.f, frame_.orthographic, ChordSlopeOf(a, b), ChordSlopeOf(b, a));
    if (chord.At(p.x).normal.dot(f.normal) >= cosChordSplit_) return true;
  }
  // Else it is a vertex (with its slopes): it must face as the ends do and keep θ running
  // one way (the link has no turn point: no table angle lies between its ends, and none
  // between the vertex and either).
  if (depth == 0) return false;
  p = this->Eval(p.uv, DerivOrder::Second);
  if (!p.ok) return false;
  const Vertex m = MakeVertexOf(p, f, ThetaVertex::Kind::Tilt);
  if (facing && Facing(m) != *facing) return false;
  const double d = Wrap(b.theta - a.theta), da = Wrap(m.theta - a.theta), db = Wrap(b.theta - m.theta);
  if (std::abs(d) > kTurnRad && ((da * d < 0.0 && std::abs(da) > kTurnRad) || (db * d < 0.0 && std::abs(db) > kTurnRad)))
    return false;
  if (!SplitInto(a, m, depth - 1, facing, out, make)) return false;
  out->push_back(m);
  return SplitInto(m, b, depth - 1, facing, out, make);
}

template <class ShapeT>
template <class Make>
bool ThetaWalker<ShapeT>::FillLink(const Vertex& a, const Vertex& b, std::vector<Vertex>* out, Make& make) {
  // θ runs one way from a to b (their rates agree with the link, CheckLink found nothing
  // else amiss): each tabulated angle between is the θ tracker there, by Newton from the
  // point that far along the link's chord in (u,v) by θ (the crawl's PassTable does the
  // same within each of its steps). Each must lie between its neighbours in x and along
  // the chord, face as the ends do, and leave no link turning a table step out of the
  // plane or in all; else false, and the link is crawled.
  const double d = Wrap(b.theta - a.theta);
  if (std::abs(d) <= kTurnRad || std::abs(d) >= kFillMaxTurnSteps * table_) return false;
  const std::optional<bool> facing = LinkFacing(a, b);
  out->clear();
  out->push_back(a);
  const bool placed = ForEachTableAngle(a.theta, d, false, [&](double angle, int k) {
    if (SilhouetteAngle(angle)) return false;  // not a table vertex
    LevelPoint v;
    if (!SolveTable(k, a.uv + (angle - a.theta) / d * (b.uv - a.uv), &v, &Count(Counter::ThetaCrawlIterations)) ||
        !WithinStep(a.uv, b.uv, v.uv) || !Between(v.x, out->back().x, b.x))
      return false;
    out->push_back(MakeVertex(v, make, ThetaVertex::Kind::Table, k));
    const Vertex &p = (*out)[out->size() - 2], &q = out->back();
    return (!facing || Facing(q) == *facing) && !TurnsPastStep(p, q);
  });
  // No tabulated angle passed after all (the ends' θ a table step apart, each within
  // kOnAngleRad of one): nothing to fill, the link is crawled.
  if (!placed || out->size() == 1) return false;
  if (TurnsPastStep(out->back(), b)) return false;
  out->push_back(b);
  return true;
}

template <class ShapeT>
template <class Make>
bool ThetaWalker<ShapeT>::Advance(const ChainSet& from, double dy, const RowTrackers& t, bool extrapolate,
                                  std::vector<char>* edgeUsed, std::vector<char>* silUsed,
                                  std::vector<Vertex>* scratch, ChainSet* to, Make&& make) {
  this->Bind(t, edgeUsed, silUsed);
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
    if (c.closed && (A.back().uv - A.front().uv).norm() > kSameCrossingUv) return false;
    const auto begin = static_cast<std::uint32_t>(to->v.size());
    double sense = 1.0;  // along the chain's order (a ring is crawled with sense 1)
    LevelPoint last;      // the last vertex advanced, and its index in A
    std::size_t lastK = 0;
    bool skipped = false;  // tilt vertices dropped or trackers lost of A since lastK
    double lastD = 0.0;    // θ's change along the chain's last link (0: none yet)
    // θ keeps its sense of rotation through a Table or Tilt vertex and reverses it at a
    // Turn (§4.3): the link from a to b breaks that rule.
    auto turnsWrong = [&](const Vertex& a, const Vertex& b) {
      const double d = Wrap(b.theta - a.theta);
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
      const double d = Wrap(b.theta - a.theta);
      return std::abs(d) > kTurnRad && (lastRate * d < 0.0 || rateB * d < 0.0);
    };
    // The link from `last` to b, repaired sideways if it looks suspicious; then b.
    auto link = [&](std::size_t k, const Vertex& b, const LevelPoint& pb, double rateB, const Vec2& uvRate) {
      if (to->v.size() > begin) {
        const Vertex& a = to->v.back();
        // x runs one way through a vertex that is not an anchor.
        const bool xBack = to->v.size() >= begin + 2 && a.kind != ThetaVertex::Kind::End &&
                           a.kind != ThetaVertex::Kind::Silhouette &&
                           (a.x - to->v[to->v.size() - 2].x) * (b.x - a.x) < 0.0;
        const bool wrongWay = skipped || xBack || turnsWrong(a, b) || againstRate(a, b, rateB);
        LinkCheck check = wrongWay ? LinkCheck::Broken : CheckLink(A[lastK], A[k % A.size()], a, b);
        // A link with a tilt vertex at an end (on rows) was crawled on the line before; now
        // that the tilt has been carried along, its chord is checked against the surface
        // in its middle as the crawl checks its points (SplitLink).
        if (check == LinkCheck::Sound && rowChords_ &&
            (a.kind == ThetaVertex::Kind::Tilt || b.kind == ThetaVertex::Kind::Tilt))
          check = LinkCheck::Split;
        if (check != LinkCheck::Sound) {
          // A link missing only tabulated vertices gets them by Newton, and one whose
          // normal only turns too far is split by tilt vertices; else, or if that fails,
          // it is crawled. A tilt vertex at its end is dropped instead: the crawl across
          // its place to the next vertex puts tilt vertices where they are due (a crawl
          // ends only on a vertex it makes itself, which a tilt's place need not be).
          const bool filled = (check == LinkCheck::MissingTable && FillLink(a, b, scratch, make)) ||
                              (check == LinkCheck::Split && SplitLink(a, b, scratch, make));
          if (!filled && b.kind == ThetaVertex::Kind::Tilt && k < n) {
            skipped = true;
            return true;
          }
          // (A tilt's link whose chord was found sound is no repair.)
          if (!filled || scratch->size() > 2) {
            ++(*this->counters_)[Counter::ThetaLinkRepairs];
            if (filled) ++(*this->counters_)[Counter::ThetaLinksFilled];
          }
          if (!filled) {
            // The crawl starts from the last vertex before any tilt vertices: a tilt
            // vertex, riding the surface, may have overtaken b (the crawl from it would
            // never meet b), and the crawl puts tilt vertices where they are due.
            bool popped = false;
            for (; to->v.back().kind == ThetaVertex::Kind::Tilt && to->v.size() > begin + 1; popped = true) {
              to->v.pop_back();
              to->before.pop_back();
              to->rate.pop_back();
            }
            if (popped) {
              last = this->Eval(to->v.back().uv, DerivOrder::Second);
              if (to->v.back().kind == ThetaVertex::Kind::Silhouette) last.jn = 0.0;
            }
            // Two θ trackers of one angle that have met (their turn pair gone between
            // them) are one vertex.
            if (SameVertex(to->v.back(), b)) return true;
            scratch->clear();
            if (!Crawl(last, sense, false, scratch, make, &b,
                       to->v.back().kind == ThetaVertex::Kind::Turn ? -lastD : lastD)) return false;
          }
          for (std::size_t i = 1; i + 1 < scratch->size(); ++i) {
            to->v.push_back((*scratch)[i]);
            to->before.push_back(Vec2(NAN, NAN));
            to->rate.push_back(Vec2(NAN, NAN));
          }
        }
      }
      to->v.push_back(b);
      to->before.push_back(A[k % A.size()].uv);
      to->rate.push_back(uvRate);
      if (to->v.size() >= begin + 2) {
        const double d = Wrap(b.theta - to->v[to->v.size() - 2].theta);
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
      TableResidual residual;           // a Table vertex's G_i at its solution
      Vec2 uvRate = Vec2(NAN, NAN);     // a tracker's rate along the lines (PredictedStart)
      switch (V.kind) {
        case ThetaVertex::Kind::Tilt: {
          // On rows, kept where the surface carries it (SolveTiltTracker), the links on
          // both sides judged as any; one leaving the patch is dropped, and the link across
          // its place repaired sideways. On slab lines the link across it is crawled
          // afresh (and one turning too far is not split): a slab's normals have no slopes
          // to follow its links' curves, and the crawl checks those against the surface
          // at each of its points (kept tilts made the teapot's 1-px slabs at 8 steps,
          // 256 px, aa 4, miss the normal farther: p99 5.6 -> 6.1 degrees).
          if (!rowChords_) {
            skipped = true;
            continue;
          }
          const Vec2 start = extrapolate ? PredictedStart(V.uv, from.before[c.begin + k], from.rate[c.begin + k], dy)
                                         : V.uv;
          ++(*this->counters_)[Counter::ThetaTiltTrackers];
          if (!SolveTiltTracker(this->shape_, this->map_, this->ys_, start, &p,
                                &(*this->counters_)[Counter::ThetaTiltIterations], &uvRate)) {
            skipped = true;
            continue;
          }
          break;
        }
        case ThetaVertex::Kind::Turn: {
          const Vec2 start = extrapolate ? PredictedStart(V.uv, from.before[c.begin + k], from.rate[c.begin + k], dy)
                                         : V.uv;
          ++(*this->counters_)[Counter::ThetaTurnTrackers];
          // A turn tracker with no root near (its pair has met it and both are gone) is
          // dropped, and the link across its place repaired sideways.
          if (!SolveTurn(start, &p, &(*this->counters_)[Counter::ThetaTurnIterations], &uvRate)) {
            ++(*this->counters_)[Counter::ThetaTurnsLost];
            skipped = true;
            continue;
          }
          break;
        }
        case ThetaVertex::Kind::End: {
          const int e = nearest(t.edgePoints, edgeUsed, V.uv, DomainSide(V.uv));
          if (e < 0) return false;
          p = this->Eval(t.edgePoints[static_cast<std::size_t>(e)], DerivOrder::Second);  // for its slopes and rate
          if (!p.ok) return false;
          if (k == 0) sense = Base::InwardSense(p, t.edgeOf[static_cast<std::size_t>(e)]);
          if (sense == 0.0) return false;
          break;
        }
        case ThetaVertex::Kind::Silhouette: {
          const int e = nearest(t.silhouettePoints, silUsed, V.uv, -1);
          if (e < 0) return false;
          p = this->Eval(t.silhouettePoints[static_cast<std::size_t>(e)], DerivOrder::Second);
          if (!p.ok) return false;
          p.jn = 0.0;  // on the silhouette whatever rounding says
          break;
        }
        case ThetaVertex::Kind::Table: {
          const Vec2 start = extrapolate ? PredictedStart(V.uv, from.before[c.begin + k], from.rate[c.begin + k], dy)
                                         : V.uv;
          ++(*this->counters_)[Counter::ThetaTrackers];
          // A tracker that leaves the patch or does not converge is dropped (§3.2: deleted
          // when it leaves [0,1]²); the link across its place is repaired sideways.
          if (!SolveTable(V.index, start, &p, &(*this->counters_)[Counter::ThetaTrackerIterations], &residual,
                          &uvRate)) {
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
        rate = sense * TurnFunction(p.object, p.gradY, frame_);  // TurnAt(p.uv), p evaluated
      }
      if (!link(k, MakeVertex(p, make, V.kind, V.index), p, rate, uvRate)) return false;
    }
    if (c.closed) {  // back round to the first vertex
      if (n + 1 > A.size() || to->v.size() == begin) return false;
      const Vertex first = to->v[begin];
      LevelPoint p0 = this->Eval(first.uv);
      p0.jn = 0.0;
      if (!link(n, first, p0, NAN, Vec2(NAN, NAN))) return false;
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

}  // namespace patchscan
