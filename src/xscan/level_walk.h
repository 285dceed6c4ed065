// The exact X scan of one surface on one scan line (Blinn 1978 §3.3). The scan line's
// level curve y(u,v) = ys in the domain is a set of curves that end on the boundary
// (where the edge trackers are) or close on themselves; the silhouette points on them
// (J = 0, where the silhouette trackers are) cut them into x-monotone segments.
//
// Each curve is walked from one end (an edge tracker; for a closed curve, a silhouette
// tracker) to the other, in order along it: this links the scan line's trackers (§3.2.3)
// and finds every silhouette point between them by the sign of J. On each x-monotone
// piece every sample column is solved by bivariate Newton on x = xs, y = ys from the
// neighbouring sample (§3.3). A silhouette point found by the walk that no tracker holds,
// or an exit through the boundary that no edge tracker holds, is a tracker miss: the walk
// repairs it (the point is found by Newton from a bracket, never guessed) and counts it.
#pragma once

#include <algorithm>
#include <cmath>
#include <optional>
#include <cstdint>
#include <utility>
#include <vector>

#include "core/counters.h"
#include "core/hermite.h"
#include "patch/screen.h"
#include "raster/fragment.h"
#include "tracker/edge_scan.h"
#include "xscan/level_curve.h"
#include "tracker/newton.h"
#include "tracker/level_point.h"
#include "tracker/silhouette_scan.h"
#include "tracker/surface_scan.h"

namespace patchscan {

// A walk's step in the domain: first tries, largest, smallest before giving up.
constexpr double kWalkStepStart = 1.0 / 64;
constexpr double kWalkStepMax = 1.0 / 16;
constexpr double kWalkStepMin = 1e-11;
// Largest turn of the curve's tangent over one step (radians): beyond it the predictor
// could land on a neighbouring branch.
constexpr double kWalkMaxTurn = 0.5;
// A walk longer than this many steps is lost (a curve has finitely many columns; at the
// largest step the domain's diagonal takes 23 steps).
constexpr long kWalkMaxStepsPerColumn = 4;
constexpr long kWalkMaxStepsBase = 4096;

// Trimmed NURBS pieces (tracker/trim_scan.h): whether a walk is in the kept region is
// decided once, at a point this far (in (u,v)) along the curve from where it starts, and
// from there toggled at every trim crossing the walk passes; crossings nearer the start
// than this (a trim curve through the start, or along the boundary) are in that first
// decision. Far above the crossings' own uncertainty (1e-7 px over the gradient).
constexpr double kTrimStartUv = 1e-6;
// A trim crossing lies on the arc being walked when Newton on the arc at its x lands this
// close to it (in (u,v)): its uncertainty, plus a thousandth of the arc, far less than
// the distance to any other branch the walk could take for this one.
constexpr double kTrimMatchUv = 1e-5;
constexpr double kTrimMatchArc = 1e-3;

// Scratch the walks of a trimmed surface use, kept by the scan (no allocation per row).
struct TrimScratch {
  std::vector<char> used;     // per trim crossing of the row: passed already
  std::vector<std::pair<double, int>> arc;  // the crossings on the current arc (x, index), in walk order
  std::vector<std::pair<int, LevelPoint>> fills;  // columns reaching to shared edges (LevelWalker::FillToEdge)
};

// What one try at a step along a level curve came to (LevelWalker::TryStep).
enum class StepResult { Moved, Exit, Rejected };

template <class ShapeT>
class LevelWalker : public LevelCurve<ShapeT> {
  using Curve = LevelCurve<ShapeT>;

 public:
  // Emit(column, const LevelPoint&): the surface point at sample column `column` of the row.
  // `events` may be null.
  LevelWalker(const ShapeT& shape, const ScreenMap& map, double ys,
              const raster::SampleColumns& cols, Counters* counters, WalkEvents* events = nullptr)
      : Curve(shape, map, ys, cols, counters, events) {}
  using Curve::Eval;

  // Walks every curve of the row. `edgeUsed` and `silUsed` are scratch (resized here).
  // On a trimmed surface (SetTrim) only the samples the trim keeps are emitted.
  template <class Emit>
  void WalkAll(const RowTrackers& t, std::vector<char>* edgeUsed, std::vector<char>* silUsed,
               Emit&& emit) {
    Bind(t, edgeUsed, silUsed, /*fills=*/true);
    auto kept = [&](int column, const LevelPoint& p) {
      if (KeptAt(cols_.At(column))) emit(column, p);
    };
    for (size_t k = 0; k < t.edgePoints.size(); ++k) {
      if ((*edgeUsed)[k]) continue;
      (*edgeUsed)[k] = 1;
      WalkFromEdge(t.edgePoints[k], t.edgeOf[k], kept);
    }
    // Closed curves: no boundary end, so a silhouette tracker no walk has passed.
    for (size_t k = 0; k < t.silhouettePoints.size(); ++k) {
      if ((*silUsed)[k]) continue;
      (*silUsed)[k] = 1;
      WalkClosed(t.silhouettePoints[k], kept);
    }
    if (trim_) {
      for (const auto& [column, p] : trimScratch_->fills) emit(column, p);
      trimScratch_->fills.clear();
    }
  }

  // The walks are of a trimmed NURBS piece: `trim` its trim, `scratch` kept by the caller.
  void SetTrim(const PieceTrim* trim, TrimScratch* scratch) {
    trim_ = trim;
    trimScratch_ = scratch;
  }

 protected:
  using typename Curve::CurvePoint;
  using Curve::Correct, Curve::DirX, Curve::Failed, Curve::Inside, Curve::InwardSense, Curve::LocateSilhouette,
      Curve::NextColumn, Curve::PredictColumn, Curve::Repaired, Curve::SolveColumn, Curve::SolveX, Curve::Tangent,
      Curve::UseTracker;
  using Curve::cols_, Curve::counters_, Curve::events_, Curve::map_, Curve::shape_, Curve::ys_;


  // Emits the columns passed going from a to b along an x-monotone arc of the curve:
  // those in (x_a, x_b] (kColumnEpsPx beyond each). Seeds interpolate a and b by x; a
  // failed solve splits the arc at its midpoint on the curve.
  template <class Emit>
  void EmitBetween(const LevelPoint& a, const LevelPoint& b, Emit& emit) {
    BeginArc(a.uv, a.x, b.uv, b.x);
    EmitArc(a, b, emit, 0);
    EndArc();
  }

  template <class Emit>
  void EmitArc(const LevelPoint& a, const LevelPoint& b, Emit& emit, int depth) {
    const int dir = b.x > a.x ? 1 : -1;
    int c = NextColumn(a.x, dir);
    for (; c >= 0 && c < cols_.n && dir * (cols_.At(c) - b.x) <= kColumnEpsPx; c += dir) {
      const double t = (cols_.At(c) - a.x) / (b.x - a.x);
      LevelPoint p;
      const double reach = (b.uv - a.uv).norm();
      if (SolveColumn(c, a.uv + std::clamp(t, 0.0, 1.0) * (b.uv - a.uv), &p) &&
          (p.uv - a.uv).norm() <= 2.0 * reach + kSameCrossingUv) {
        ++(*counters_)[Counter::ColumnsSolved];
        emit(c, p);
        continue;
      }
      // Split the arc at its midpoint and emit the rest of it in two halves.
      const LevelPoint m = Correct(0.5 * (a.uv + b.uv));
      if (depth < 16 && m.ok && dir * (m.x - a.x) >= 0 && dir * (b.x - m.x) >= 0) {
        LevelPoint start = a;
        if (c != NextColumn(a.x, dir)) {  // columns before c are done: start just before c
          start.x = cols_.At(c - dir);
        }
        EmitArc(start, m, emit, depth + 1);
        EmitArc(m, b, emit, depth + 1);
      } else {
        Failed(c >= 0 && c < cols_.n ? a.uv : b.uv);
      }
      return;
    }
  }

  // Marks the silhouette tracker at s as passed; false if none holds it.
  bool UseSilhouetteTracker(const Vec2& uv) { return UseTracker(trackers_->silhouettePoints, silUsed_, uv); }
  bool UseEdgeTracker(const Vec2& uv) { return UseTracker(trackers_->edgePoints, edgeUsed_, uv); }
  // Takes the line's trackers `t` as the walks' starting points, none used yet.
  void Bind(const RowTrackers& t, std::vector<char>* edgeUsed, std::vector<char>* silUsed, bool fills = false) {
    fills_ = fills;
    trackers_ = &t;
    edgeUsed_ = edgeUsed;
    silUsed_ = silUsed;
    edgeUsed->assign(t.edgePoints.size(), 0);
    silUsed->assign(t.silhouettePoints.size(), 0);
    if (trim_) {
      trimScratch_->used.assign(t.trimPoints.size(), 0);
      trimScratch_->fills.clear();
    }
  }

  // ---- trims (SetTrim) ----
  // A walk starts at p going with `sense`: whether it is in the kept region, decided
  // kTrimStartUv along the curve, and the trim crossings nearer the start than that passed.
  void StartTrim(const LevelPoint& p, double sense) {
    if (!trim_) return;
    StartTrimToward(p.uv, Tangent(p, sense));
    if (kept_)  // the walk enters the kept region at its start: it reaches back to an edge there
      for (std::size_t k = 0; k < trackers_->trimPoints.size(); ++k)
        if ((trackers_->trimPoints[k] - p.uv).norm() <= kTrimStartUv) FillToEdge(k, -DirX(p, sense));
  }

  // ---- shared edges (tracker/edge_crossings.h) ----
  // Where trim crossing k runs along a B-rep edge, the face reaches at least to the edge's
  // crossing: when that lies past the face's own end, on the side `outward` (+1: greater x)
  // of it, the columns between take the face's point at its own end (a sliver as wide as
  // the gap between the two faces' surfaces there; a column within kColumnEpsPx of the end
  // is the walk's). The neighbour does the same from its side, so no column between them is
  // left uncovered; where a face overshoots the edge, the two overlap by the gap.
  void FillToEdge(std::size_t k, double outward) {
    if (!fills_) return;
    const double own = trackers_->trimX[k], edge = trackers_->trimEdgeX[k];
    if (!std::isfinite(edge) || outward * (edge - own) <= kColumnEpsPx) return;
    const int lo = cols_.Ceil(std::min(own, edge) - kColumnEpsPx), hi = cols_.Floor(std::max(own, edge) + kColumnEpsPx);
    if (lo > hi) return;
    const LevelPoint q = Eval(trackers_->trimPoints[k]);
    if (!q.ok) return;
    for (int c = lo; c <= hi; ++c) {
      const double x = cols_.At(c);
      if (outward * (x - own) > kColumnEpsPx && outward * (x - edge) <= kColumnEpsPx) trimScratch_->fills.emplace_back(c, q);
    }
  }
  // The same, for a walk leaving uv in the unit direction `dir`.
  void StartTrimToward(const Vec2& uv, const Vec2& dir) {
    kept_ = trim_->Kept(uv + kTrimStartUv * dir);
    for (std::size_t k = 0; k < trackers_->trimPoints.size(); ++k)
      if ((trackers_->trimPoints[k] - uv).norm() <= kTrimStartUv) trimScratch_->used[k] = 1;
  }
  // Whether the walk keeps a sample at x on the current arc: the arc's crossings before x
  // toggle the state. A sample within kColumnEpsPx of a crossing is on the trim curve, which
  // bounds the kept side: kept (as EmitArc emits a column that close past an arc's end; a
  // trim curve along the boundary crosses the line where the walk leaves the domain, and a
  // column on that boundary would otherwise fall to the rounding of the two crossings).
  bool KeptAt(double x) {
    if (!trim_) return true;
    auto& arc = trimScratch_->arc;
    bool onCurve = false;
    for (; arcNext_ < arc.size() && arcDir_ * (x - arc[arcNext_].first) > -kColumnEpsPx; ++arcNext_) {
      onCurve = onCurve || arcDir_ * (x - arc[arcNext_].first) <= kColumnEpsPx;
      kept_ = !kept_;
    }
    return kept_ || onCurve;
  }
  // The walk passes the arc of the level curve from a to b (x-monotone): the trim
  // crossings on it, not yet passed, in walk order. Each is confirmed by Newton on the
  // curve at its x from the arc's chord (another branch of the curve may pass there).
  void BeginArc(const Vec2& a, double xa, const Vec2& b, double xb) {
    if (!trim_) return;
    auto& arc = trimScratch_->arc;
    arc.clear();
    arcNext_ = 0;
    arcDir_ = xb >= xa ? 1.0 : -1.0;
    const double lo = std::min(xa, xb) - kColumnEpsPx, hi = std::max(xa, xb) + kColumnEpsPx;
    const double reach = kTrimMatchUv + kTrimMatchArc * (b - a).norm();
    for (std::size_t k = 0; k < trackers_->trimPoints.size(); ++k) {
      const double x = trackers_->trimX[k];
      if (trimScratch_->used[k] || x < lo || x > hi) continue;
      const double t = xb != xa ? std::clamp((x - xa) / (xb - xa), 0.0, 1.0) : 0.5;
      LevelPoint q;
      std::int64_t iterations = 0;
      if (!SolveX(x, a + t * (b - a), &q, &iterations) || (q.uv - trackers_->trimPoints[k]).norm() > reach) continue;
      trimScratch_->used[k] = 1;
      ++(*counters_)[Counter::TrimCrossings];
      arc.emplace_back(x, static_cast<int>(k));
    }
    std::sort(arc.begin(), arc.end(), [&](const auto& p, const auto& q) { return arcDir_ * p.first < arcDir_ * q.first; });
    // An exit from the kept region reaches on to its edge, an entry back to its edge.
    bool kept = kept_;
    for (const auto& [x, k] : arc) {
      FillToEdge(static_cast<std::size_t>(k), kept ? arcDir_ : -arcDir_);
      kept = !kept;
    }
  }
  // The rest of the arc's crossings, after its last sample.
  void EndArc() {
    if (!trim_) return;
    KeptAt(arcDir_ * INFINITY);
    trimScratch_->arc.clear();
    arcNext_ = 0;
  }

  // Where the straight step from a to q (outside) crosses the boundary, the crossing of
  // the level curve with that edge, by Newton along the edge.
  bool ExitPoint(const LevelPoint& a, const Vec2& q, LevelPoint* e) const {
    double tHit = 1.0;
    PatchEdge edge = PatchEdge::U0;
    const Vec2 d = q - a.uv;
    auto consider = [&](int axis, double bound, PatchEdge which) {
      if (d[axis] == 0.0) return;
      const double t = (bound - a.uv[axis]) / d[axis];
      if (t >= 0.0 && t < tHit) {
        tHit = t;
        edge = which;
      }
    };
    if (q.x() < 0.0) consider(0, 0.0, PatchEdge::U0);
    if (q.x() > 1.0) consider(0, 1.0, PatchEdge::U1);
    if (q.y() < 0.0) consider(1, 0.0, PatchEdge::V0);
    if (q.y() > 1.0) consider(1, 1.0, PatchEdge::V1);
    const Vec2 hit = a.uv + tHit * d;
    const bool alongU = edge == PatchEdge::V0 || edge == PatchEdge::V1;  // t runs along u
    const auto r = SolveNewton1(
        [&](double t, double* f, double* df) {
          const LevelPoint p = Eval(EdgePoint(edge, t));
          *f = p.ok ? p.y - ys_ : NAN;
          *df = alongU ? p.gradY.x() : p.gradY.y();
        },
        alongU ? hit.x() : hit.y(), 0.0, 1.0, kEdgeTolPx);
    if (r.status != NewtonStatus::Converged) return false;
    *e = Eval(EdgePoint(edge, r.t));
    return e->ok;
  }

  // Passes from a to b, an arc of the curve: emits its columns, splitting it at a
  // silhouette point where J changes sign. Returns the silhouette point when one was
  // passed (for closed walks), via *passed.
  template <class Emit>
  bool Pass(const LevelPoint& a, const LevelPoint& b, Emit& emit, LevelPoint* passed) {
    const bool aOnSil = std::abs(a.jn) <= kOnSilhouetteJn;
    if (!aOnSil && (a.j > 0) != (b.j > 0) && std::abs(b.jn) > kOnSilhouetteJn) {
      LevelPoint s;
      if (!LocateSilhouette(a, b, &s)) {
        Failed(a.uv);
        EmitBetween(a, b, emit);
        return false;
      }
      ++(*counters_)[Counter::SilhouettePoints];
      if (!UseSilhouetteTracker(s.uv)) {
        Repaired(s.uv, Counter::UntrackedSilhouettes);
        if (events_) events_->untrackedSilhouettes.push_back(s.uv);
      }
      EmitBetween(a, s, emit);
      EmitBetween(s, b, emit);
      *passed = s;
      return true;
    }
    EmitBetween(a, b, emit);
    return false;
  }

  // A point with |J| / (|grad x| |grad y|) below this is on the silhouette (the start of a
  // closed walk): its sign says nothing.
  static constexpr double kOnSilhouetteJn = 1e-9;

  // One try at a step of length `step` along the curve from p (aimed at sample column
  // `column` when it is >= 0: the point of the curve on that column), into *next: Moved
  // (the point reached), Exit (the curve left the domain within the step: the exit on the
  // boundary), or Rejected (the correction failed, jumped to another branch, turned the
  // tangent more than kWalkMaxTurn, or an aimed step crossed the silhouette): try again
  // shorter. The one step of both walks, the exact X scan's and the θ crawl's.
  // `before`: the walk's point before p, if the caller has one (PredictColumn's seed for
  // an aimed step; else the tangent step's end).
  StepResult TryStep(const LevelPoint& p, double sense, double step, int column, LevelPoint* next,
                     const CurvePoint* before = nullptr) const {
    const Vec2 tan = Tangent(p, sense);
    const Vec2 q = p.uv + step * tan;
    const double cosTurn = std::cos(kWalkMaxTurn);
    bool ok = false;
    if (Inside(q)) {
      if (column >= 0) {
        const std::optional<Vec2> predicted = before ? PredictColumn(*before, CurvePoint::Of(p), cols_.At(column)) : std::nullopt;
        ok = SolveColumn(column, predicted ? *predicted : q, next);
      } else {
        *next = Correct(q);
        ok = next->ok;
      }
    }
    if (!Inside(q) || (ok && !Inside(next->uv))) {
      LevelPoint e;
      if (ExitPoint(p, Inside(q) ? next->uv : q, &e) && (e.uv - p.uv).norm() <= 2.0 * step + kSameCrossingUv &&
          Tangent(e, sense).dot(tan) >= cosTurn) {
        *next = e;
        return StepResult::Exit;
      }
      return StepResult::Rejected;
    }
    if (!ok || (next->uv - p.uv).norm() > 2.0 * step + kSameCrossingUv || Tangent(*next, sense).dot(tan) < cosTurn ||
        (column >= 0 && (next->j > 0) != (p.j > 0)))
      return StepResult::Rejected;
    return StepResult::Moved;
  }

  // One step of the exact X scan from p along the curve, aimed at the next sample column
  // when it is within *h (emitting it), else an arc step that emits the columns passed on
  // the way. Returns Ok (*p the next point), Exit (*p the exit on the boundary) or Lost.
  // *passed and *didPass: the silhouette point passed on the way, if any (closed walks).
  enum class Step { Ok, Exit, Lost };
  template <class Emit>
  Step Advance(LevelPoint* p, double sense, double* h, Emit& emit, LevelPoint* passed, bool* didPass) {
    *didPass = false;
    for (;;) {
      if (*h < kWalkStepMin) return Step::Lost;
      // Aim at the next column when it is within the step (first order).
      const bool onSil = std::abs(p->jn) <= kOnSilhouetteJn;
      const int c = NextColumn(p->x, DirX(*p, sense));
      double hColumn = INFINITY;
      if (!onSil && c >= 0 && c < cols_.n)
        hColumn = std::abs(cols_.At(c) - p->x) * p->gradY.norm() / std::abs(p->j);
      const bool aimed = hColumn <= *h;
      const double step = aimed ? hColumn : *h;
      ++(*counters_)[aimed ? Counter::ColumnSteps : Counter::ArcSteps];
      LevelPoint next;
      const StepResult r = TryStep(*p, sense, step, aimed ? c : -1, &next, hasBefore_ ? &before_ : nullptr);
      if (r == StepResult::Rejected) {
        *h = 0.5 * step;
        continue;
      }
      if (r == StepResult::Exit) {
        *didPass = Pass(*p, next, emit, passed);
        *p = next;
        return Step::Exit;
      }
      before_ = CurvePoint::Of(*p);
      hasBefore_ = true;
      if (aimed) {
        ++(*counters_)[Counter::ColumnsSolved];
        BeginArc(p->uv, p->x, next.uv, next.x);
        emit(c, next);
        EndArc();
        *p = next;
        return Step::Ok;
      }
      *didPass = Pass(*p, next, emit, passed);
      *p = next;
      *h = std::min(2.0 * *h, kWalkStepMax);
      return Step::Ok;
    }
  }

  long MaxSteps() const { return kWalkMaxStepsBase + kWalkMaxStepsPerColumn * cols_.n; }

  template <class Emit>
  void WalkFromEdge(const Vec2& uv, PatchEdge edge, Emit& emit) {
    ++(*counters_)[Counter::Walks];
    LevelPoint p = Eval(uv);
    if (!p.ok) {
      Failed(uv);
      return;
    }
    const double sense = InwardSense(p, edge);
    if (sense == 0.0) return;
    hasBefore_ = false;
    StartTrim(p, sense);
    // A column exactly at the start belongs to this curve.
    const int c0 = cols_.Ceil(p.x - kColumnEpsPx);
    if (c0 < cols_.n && std::abs(cols_.At(c0) - p.x) <= kColumnEpsPx) emit(c0, p);
    double h = kWalkStepStart;
    LevelPoint passed;
    bool didPass;
    for (long k = 0; k < MaxSteps(); ++k) {
      const Step st = Advance(&p, sense, &h, emit, &passed, &didPass);
      if (st == Step::Lost) break;
      if (st == Step::Exit) {
        if (!UseEdgeTracker(p.uv)) Repaired(p.uv, Counter::UntrackedExits);
        return;
      }
    }
    Failed(p.uv);
  }

  template <class Emit>
  void WalkClosed(const Vec2& uv, Emit& emit) {
    LevelPoint start = Eval(uv);
    if (!start.ok || std::abs(start.y - ys_) > 1e3 * kEdgeTolPx) return;  // not a crossing
    ++(*counters_)[Counter::Walks];
    ++(*counters_)[Counter::ClosedWalks];
    LevelPoint p = start;
    p.jn = 0.0;  // the start is on the silhouette whatever rounding says
    hasBefore_ = false;
    StartTrim(p, 1.0);
    double h = kWalkStepStart;
    LevelPoint passed;
    bool didPass;
    for (long k = 0; k < MaxSteps(); ++k) {
      const Step st = Advance(&p, 1.0, &h, emit, &passed, &didPass);
      if (st == Step::Lost) break;
      if (didPass && (passed.uv - start.uv).norm() <= kSameCrossingUv) return;  // round
      if (st == Step::Exit) {
        // Not closed after all: it reached the boundary, whose edge walks did not reach
        // this tracker. Walk the other way too, and count a miss.
        if (!UseEdgeTracker(p.uv)) Repaired(p.uv, Counter::UntrackedExits);
        LevelPoint back = start;
        back.jn = 0.0;
        hasBefore_ = false;
        StartTrim(back, -1.0);
        double hb = kWalkStepStart;
        for (long kb = 0; kb < MaxSteps(); ++kb) {
          const Step sb = Advance(&back, -1.0, &hb, emit, &passed, &didPass);
          if (sb == Step::Lost) break;
          if (sb == Step::Exit) {
            if (!UseEdgeTracker(back.uv)) Repaired(back.uv, Counter::UntrackedExits);
            return;
          }
        }
        Failed(back.uv);
        return;
      }
    }
    Failed(p.uv);
  }

  const RowTrackers* trackers_ = nullptr;
  std::vector<char>*edgeUsed_ = nullptr, *silUsed_ = nullptr;
  const PieceTrim* trim_ = nullptr;
  TrimScratch* trimScratch_ = nullptr;
  bool kept_ = true;           // the walk is in the kept region
  bool fills_ = false;         // the exact walk: columns reach to shared edges (FillToEdge)
  std::size_t arcNext_ = 0;    // the next crossing of the current arc to toggle at
  double arcDir_ = 1.0;        // the current arc runs this way in x
  CurvePoint before_;          // the walk's point before the current one (TryStep's `before`)
  bool hasBefore_ = false;
};

}  // namespace patchscan
