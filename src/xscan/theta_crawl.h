// The θ walker's crawl (Blinn 1978 §4.1–4.3): one chain walked sideways along its level
// curve from a boundary end or a silhouette, or one link of a chain crawled from its first
// vertex to the tracker at its other end (§4.2). Each step of the walk (LevelWalker::
// TryStep) turns θ, and the normal out of the scan plane, by at most half a table step; a
// vertex is made where θ passes a tabulated angle (the θ tracker there, by Newton), where
// θ turns back (the turn tracker), at each silhouette (found by the sign of J), where the
// normal has turned a table step out of the plane, or in all (in 3-D), since the last
// vertex (a tilt), where a link's chord would miss the normal by more than an eighth of a
// step (Push), and at the boundary. Included by theta_walk.h; not for use on its own.
#pragma once

#include <algorithm>
#include <cmath>
#include <optional>
#include <tuple>
#include <vector>

namespace patchscan {

// A crawl's step may grow past kWalkStepMax up to kSmallStepMax while a step covers less
// than kSmallStepPx pixels of the scan line (a surface seen small).
constexpr double kSmallStepPx = 2.0;
constexpr double kSmallStepMax = 1.0 / 4;

template <class ShapeT>
template <class Make>
class ThetaWalker<ShapeT>::Crawler {
 public:
  Crawler(ThetaWalker& w, const LevelPoint& start, double sense, bool closed, std::vector<Vertex>* chain, Make& make,
          const Vertex* target, double turning)
      : w_(w), start_(start), sense_(sense), closed_(closed), chain_(*chain), make_(make), target_(target),
        points_(ThetaWalker::CrawlPoints()) {
    points_.clear();
    chain_.push_back(w_.MakeVertex(start, make_, closed ? ThetaVertex::Kind::Silhouette : ThetaVertex::Kind::End));
    checked_ = chain_.size();
    p_ = before_ = start;
    th_ = chain_.back().theta, tilt_ = chain_.back().tilt;
    tiltAtVertex_ = tilt_;
    inViewAtVertex_ = chain_.back().inView;
    vertexCount_ = chain_.size();
    // The sense θ last moved in (0: not known); at the start θ's rate along the walk, so
    // that a turn within the first step is seen.
    lastTurn_ = turning;
    if (lastTurn_ == 0.0) {
      const double r = sense * w_.TurnAt(start.uv);
      if (std::isfinite(r)) lastTurn_ = r;
    }
    // A link ending at a turn tracker ends on the step that passes it.
    if (target_ && target_->kind == ThetaVertex::Kind::Turn) turnTarget_ = w_.Eval(target_->uv);
  }

  // Walks until the boundary, the start again (a ring) or the link's target: true then;
  // false if lost, or (a link) at any other anchor.
  bool Run() {
    for (long k = 0; k < w_.MaxSteps(); ++k) {
      if (h_ < kWalkStepMin) break;
      ++w_.Count(Counter::ThetaSteps);
      LevelPoint next;
      const StepResult r = w_.TryStep(p_, sense_, h_, -1, &next);
      if (r == StepResult::Rejected) {
        h_ *= 0.5;
        continue;
      }
      // A step that turned θ too far is tried again at half the length (AtExit, AtStep).
      if (const std::optional<bool> done = r == StepResult::Exit ? AtExit(next) : AtStep(next)) return *done;
    }
    w_.Failed(p_.uv);
    return false;
  }

 private:
  // A link's crawl: done at its target, lost at any other anchor. Whether the vertices made
  // since the last call hold either (*found: the target).
  bool LinkEnd(bool* found) {
    for (; checked_ < chain_.size(); ++checked_) {
      const Vertex& v = chain_[checked_];
      if (SameVertex(v, *target_)) {
        chain_.resize(checked_ + 1);
        *found = true;
        return true;
      }
      if (v.kind == ThetaVertex::Kind::End || v.kind == ThetaVertex::Kind::Silhouette) {
        *found = false;
        return true;
      }
    }
    return false;
  }

  // The tabulated angles passed going from θ = a by d (|d| < π), silhouettes aside (they are
  // found by the sign of J), each as a vertex on the arc from `from` to `to`.
  void PassTable(const LevelPoint& from, double a, const LevelPoint& to, double d) {
    // A crawl that starts at a tracker (a link's repair) starts on its angle: that vertex
    // is the start itself, not passed.
    w_.ForEachTableAngle(a, d, true, [&](double angle, int k) {
      if (SilhouetteAngle(angle)) return true;
      // The vertex is the θ tracker itself (G_i = 0 on the line), by Newton from the
      // interpolated point; if that lands outside the step (near a turn point θ_i may be
      // crossed again close by), the interpolated point. It must also lie on from's side
      // of `to` after the chain's last vertex (x runs one way between anchors; a turn just
      // placed beyond `from` may have passed it).
      const Vec2 guess = from.uv + (angle - a) / d * (to.uv - from.uv);
      LevelPoint v;
      auto inOrder = [&](const LevelPoint& q) {
        return q.ok && (q.x == chain_.back().x || Between(q.x, chain_.back().x, to.x));
      };
      if (!w_.SolveTable(k, guess, &v, &w_.Count(Counter::ThetaCrawlIterations)) || !WithinStep(from, to, v) ||
          !inOrder(v))
        v = w_.Correct(guess);
      if (inOrder(v)) Add(w_.MakeVertex(v, make_, ThetaVertex::Kind::Table, k));
      return true;
    });
  }

  // A turn point (§4.3: θ's derivative along the curve vanishes) between two steps is a
  // vertex, so the chain follows the crinkle even when no tabulated angle is passed: the
  // turn tracker itself, by Newton from the crawl point `at` (if that lands off the two
  // steps around it, the crawl point). Every step that passes table angles notes its
  // change of θ, d, here first.
  void NoteTurn(const LevelPoint& at, const LevelPoint& to, double d) {
    if (std::abs(d) <= kTurnRad) return;
    if (lastTurn_ != 0.0 && (d > 0) != (lastTurn_ > 0) && std::abs(at.jn) > ThetaWalker::kOnSilhouetteJn) {
      // A tilt vertex made at `at` gives way to the turn.
      const bool tiltAt =
          chain_.size() > 1 && chain_.back().kind == ThetaVertex::Kind::Tilt && chain_.back().uv == at.uv;
      if (tiltAt) {
        chain_.pop_back();
        --w_.Count(Counter::ThetaTilts);
        checked_ = std::min(checked_, chain_.size());
      }
      // x runs one way between anchors: the turn tracker must lie between the chain's last
      // vertex and the next crawl point (else it is another turn, and the crawl point is
      // taken).
      LevelPoint v;
      if (!w_.SolveTurn(at.uv, &v, &w_.Count(Counter::ThetaCrawlIterations)) || !WithinStep(before_, to, v) ||
          std::abs(v.jn) <= ThetaWalker::kOnSilhouetteJn || !Between(v.x, chain_.back().x, to.x))
        v = at;
      Add(w_.MakeVertex(v, make_, ThetaVertex::Kind::Turn));
      ++w_.Count(Counter::ThetaTurnPoints);
    }
    lastTurn_ = d;
  }

  // A link ending at a turn tracker ends on the step that passes it: θ may turn back within
  // a step and the crawl not see it (a turn point one step from the boundary).
  bool EndsAtTurn(const LevelPoint& to) {
    if (!turnTarget_.ok || !WithinStep(p_, to, turnTarget_)) return false;
    PassTable(p_, th_, turnTarget_, Wrap(target_->theta - th_));
    Add(*target_);
    return true;
  }

  // The step left the domain at e: the chain's last vertices and its end there. The crawl's
  // result, or nothing if the step turned θ too far (halved).
  std::optional<bool> AtExit(const LevelPoint& e) {
    const Vertex ve = w_.MakeVertex(e, make_);
    const double the = ve.theta, tilte = ve.tilt;
    const double d = Wrap(the - th_);
    const double dTilt = tilte - tilt_;
    if (!((std::abs(d) <= w_.table_ && std::abs(dTilt) <= w_.table_) || h_ <= 4.0 * kWalkStepMin)) {
      h_ *= 0.5;
      return std::nullopt;
    }
    if (EndsAtTurn(e)) return true;
    LevelPoint s;
    if (std::abs(p_.jn) > ThetaWalker::kOnSilhouetteJn && (p_.j > 0) != (e.j > 0) && w_.LocateSilhouette(p_, e, &s)) {
      if (!w_.UseSilhouetteTracker(s.uv)) w_.Repaired(s.uv, Counter::UntrackedSilhouettes);
      Add(w_.MakeVertex(s, make_, ThetaVertex::Kind::Silhouette));
    } else {
      NoteTurn(p_, e, d);
      // A turn within the last step, before the boundary (θ's rate along the curve changes
      // sign between p and e): the steps are not continued to see it.
      LevelPoint v;
      const double rp = w_.TurnAt(p_.uv), re = w_.TurnAt(e.uv);
      if (rp * re < 0.0 && w_.SolveTurn(0.5 * (p_.uv + e.uv), &v, &w_.Count(Counter::ThetaCrawlIterations)) &&
          WithinStep(p_, e, v) && std::abs(v.jn) > ThetaWalker::kOnSilhouetteJn && Between(v.x, chain_.back().x, e.x)) {
        const Vertex vt = w_.MakeVertex(v, make_, ThetaVertex::Kind::Turn);
        const double tv = vt.theta;
        PassTable(p_, th_, v, Wrap(tv - th_));
        Add(vt);
        ++w_.Count(Counter::ThetaTurnPoints);
        PassTable(v, tv, e, Wrap(ve.theta - tv));
      } else {
        PassTable(p_, th_, e, d);
      }
    }
    Add(ve);
    bool found = true;
    if (target_) {
      LinkEnd(&found);  // the exit is an anchor: the link ends here or before
      if (found && chain_.back().kind != ThetaVertex::Kind::End) return true;  // before the exit
    }
    if (!w_.UseEdgeTracker(e.uv)) w_.Repaired(e.uv, Counter::UntrackedExits);
    return found;
  }

  // The step reached `next` inside the domain: the vertices on the way. The crawl's result
  // if it ends here, else nothing (the next step is tried).
  std::optional<bool> AtStep(const LevelPoint& next) {
    const raster::Fragment fn = make_(next);
    Vec3 inViewNext;
    const auto [thn, tiltNext] = w_.frame_.Angles(fn.position, fn.normal, &inViewNext);
    const double d = Wrap(thn - th_);
    // Steps turn θ, and the normal out of the scan plane, by at most half a table step.
    if ((std::abs(d) > 0.5 * w_.table_ || std::abs(tiltNext - tilt_) > 0.5 * w_.table_) && h_ > 4.0 * kWalkStepMin) {
      h_ *= 0.5;
      return std::nullopt;
    }
    if (EndsAtTurn(next)) return true;
    // A vertex where the normal has turned a table step out of the plane, or in all, since
    // the last (below): where it would have by `next`, the crawl point before it is one
    // first (within the limit, or it would be one already), so that no link turns further
    // (the vertices the step passes are measured from it) and the next line's check finds
    // the links sound.
    BoundLinkTo(next.x, tiltNext, inViewNext);
    const bool onSil = std::abs(p_.jn) <= ThetaWalker::kOnSilhouetteJn;
    LevelPoint s;
    if (!onSil && (p_.j > 0) != (next.j > 0) && std::abs(next.jn) > ThetaWalker::kOnSilhouetteJn &&
        w_.LocateSilhouette(p_, next, &s)) {
      // The silhouette vertex; the table angles near it are within half a step of it.
      ++w_.Count(Counter::SilhouettePoints);
      if (closed_ && (s.uv - start_.uv).norm() <= kSameCrossingUv) {
        const Vertex front = chain_.front();
        Push(front);  // round: back at the start
        return true;
      }
      if (!w_.UseSilhouetteTracker(s.uv)) {
        w_.Repaired(s.uv, Counter::UntrackedSilhouettes);
        if (w_.events_) w_.events_->untrackedSilhouettes.push_back(s.uv);
      }
      Add(w_.MakeVertex(s, make_, ThetaVertex::Kind::Silhouette));
    } else {
      NoteTurn(p_, next, d);
      PassTable(p_, th_, next, d);
    }
    // The chord interpolates normals between its vertices: where θ stays within a table
    // step but the normal leaves the scan plane (a section crossing a ridge of the surface
    // at a slant), a vertex once it has turned a table step out of the plane bounds that
    // error too; and one once it has turned a table step in all, θ and the tilt each less
    // (the teacup at θ8: colour RMSE against exact 0.0066 -> 0.0022).
    FollowLastVertex();
    if (TurnedTooFar(next.x, inViewNext, tiltNext)) {
      // Made whole, its slopes too: a chord with no tangent at its tilt end blended the
      // normal there (the teapot's spout at θ4 off by 24 degrees across a 45-px chord).
      Add(w_.MakeVertexOf(next, fn, ThetaVertex::Kind::Tilt));
      ++w_.Count(Counter::ThetaTilts);
    }
    bool found = false;
    if (target_ && LinkEnd(&found)) return found;
    // The step grows to kWalkStepMax, and beyond while steps that long cover less than
    // kSmallStepPx of the line: on a surface a few pixels across the crawl then takes a few
    // steps instead of ~20 (its vertices are placed by the θ limit and Newton either way).
    const double hMax = std::abs(next.x - p_.x) < kSmallStepPx ? kSmallStepMax : kWalkStepMax;
    before_ = p_;
    p_ = next;
    points_.push_back({next, fn.normal});
    th_ = thn;
    tilt_ = tiltNext;
    h_ = std::min(2.0 * h_, std::max(hMax, h_));
    return std::nullopt;
  }

  // Where the link from the chain's last vertex to one at x (its tilt, its normal in the
  // view's frame) would turn a table step, the crawl point before it is a vertex first, if
  // it lies between them. A link no sample column crosses is not judged (TurnsPastStep),
  // so while the crawl stays between two columns the turn since the last vertex grows
  // unchecked; the first vertex beyond a column (a silhouette's x may pass one the crawl
  // points do not) would otherwise close a link turning several steps.
  void BoundLinkTo(double x, double tilt, const Vec3& inView) {
    FollowLastVertex();
    if (chain_.back().uv == p_.uv || !TurnedTooFar(x, inView, tilt)) return;
    if (!(p_.x == chain_.back().x || Between(p_.x, chain_.back().x, x))) return;  // x runs one way
    Push(w_.MakeVertex(p_, make_, ThetaVertex::Kind::Tilt));
    ++w_.Count(Counter::ThetaTilts);
    FollowLastVertex();
  }
  // Adds v to the chain, its link bounded (BoundLinkTo).
  void Add(const Vertex& v) {
    BoundLinkTo(v.x, v.tilt, v.inView);
    Push(v);
  }
  // Adds v to the chain, after a vertex at each crawl point since the last vertex where
  // the link's chord (the Hermite cubics of its ends, as the back end draws it) would miss
  // the surface's normal by more than ThetaTable::kChordSplitStep table steps (Split). The turn and
  // tilt limits bound how far the normal turns between vertices, not how unevenly: a
  // section whose normal swings out of the scan plane and back, or turns most of a step
  // in a short stretch of a long link, leaves a chord whose ends' tangents cannot follow
  // it (the teacup saucer's front rim at 6 steps: 206 px links off by 20-37 degrees).
  void Push(const Vertex& v) {
    Split(0, points_.size(), v);
    chain_.push_back(v);
    points_.clear();
  }
  // The crawl points [lo, hi) lie on the link from the chain's last vertex to e: the one
  // where the chord misses the normal most, if by more than the bound, becomes a vertex,
  // and the links on either side are judged the same way.
  void Split(std::size_t lo, std::size_t hi, const Vertex& e) {
    const Vertex& a = chain_.back();
    if (hi <= lo || !(a.f.w > 0.0 && e.f.w > 0.0) || a.x == e.x) return;
    if (w_.rowChords_ && !w_.SamplesBetween(a.x, e.x)) return;
    const double xa = a.x, xe = e.x;
    // The chord is made only for a link with a crawl point between its ends in x.
    while (lo < hi && !Between(points_[lo].p.x, xa, xe)) ++lo;
    if (lo == hi) return;
    const raster::Chord chord(a.x, a.f, e.x, e.f, w_.frame_.orthographic, ChordSlopeOf(a, e), ChordSlopeOf(e, a));
    double worst = w_.cosChordSplit_;
    std::size_t k = hi;
    for (std::size_t i = lo; i < hi; ++i) {
      const typename ThetaWalker::CrawlPoint& q = points_[i];
      if (!Between(q.p.x, xa, xe)) continue;
      const double c = chord.At(q.p.x).normal.dot(q.normal);
      if (c < worst) worst = c, k = i;
    }
    if (k == hi) return;
    const Vertex m = w_.MakeVertex(points_[k].p, make_, ThetaVertex::Kind::Tilt);
    Split(lo, k, m);
    chain_.push_back(m);
    ++w_.Count(Counter::ThetaTilts);
    ++w_.Count(Counter::ThetaChordSplits);
    Split(k + 1, hi, e);
  }

  // The chain's last vertex's tilt and view-frame normal, if it has grown since they were
  // taken.
  void FollowLastVertex() {
    if (chain_.size() == vertexCount_) return;
    vertexCount_ = chain_.size();
    tiltAtVertex_ = chain_.back().tilt;
    inViewAtVertex_ = chain_.back().inView;
  }
  // Whether the normal (its tilt, and in the view's frame) has turned a table step out of
  // the plane, or in all, since the chain's last vertex.
  bool TurnedTooFar(double x, const Vec3& inView, double tilt) const {
    return w_.TurnsPastStep(chain_.back().x, tiltAtVertex_, inViewAtVertex_, x, tilt, inView);
  }

  ThetaWalker& w_;
  const LevelPoint start_;
  const double sense_;
  const bool closed_;
  std::vector<Vertex>& chain_;
  Make& make_;
  const Vertex* target_;  // a link's crawl: the tracker at its other end
  std::vector<typename ThetaWalker::CrawlPoint>& points_;  // since the last vertex (Push)
  std::size_t checked_;   // chain vertices LinkEnd has looked at
  LevelPoint p_, before_;  // the crawl point, and the one before it
  double th_ = 0.0, tilt_ = 0.0;  // θ and the tilt at p_
  std::size_t vertexCount_;       // the chain's size when the last vertex's angles were taken
  double tiltAtVertex_;           // the tilt of the chain's last vertex
  Vec3 inViewAtVertex_;           // and its normal in the view's frame
  double lastTurn_;               // the sense θ last moved in (0: not known)
  double h_ = kWalkStepStart;
  LevelPoint turnTarget_;  // a link's target that is a turn tracker (ok: there is one)
};

template <class ShapeT>
template <class Make>
bool ThetaWalker<ShapeT>::Crawl(const LevelPoint& start, double sense, bool closed, std::vector<Vertex>* chain,
                                Make& make, const Vertex* target, double turning) {
  if (!target) ++Count(Counter::ThetaChains);
  return Crawler<Make>(*this, start, sense, closed, chain, make, target, turning).Run();
}

}  // namespace patchscan
