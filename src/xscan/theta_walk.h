// The θ-sampled X scan of one surface on one scan line (Blinn 1978 §4). The cross-section
// of the surface in the scan plane (the plane through the eye and the scan line) is
// sampled where the angle θ of its normal takes one of N tabulated values, θ_i = 2πi/N
// (§4.1: points cluster where the curve turns fast). In perspective the
// surface normal N is resolved in the scan plane into T = -N·r, towards the eye along the
// view ray r (zero on the silhouette), and S = N·s, sideways along s = r × n, n the scan
// plane's normal; θ = atan2(T, S) and G_i = S sin θ_i - T cos θ_i.
//
// Each curve is crawled along at constant y ("sideways", §4.2) from its boundary end or,
// closed, from a silhouette tracker, taking steps in which θ turns by at most half a table
// step; a vertex is made where θ passes a tabulated angle, at every silhouette point (θ = 0
// or π: where the x extent of the section ends, so coverage along the row is exact), at
// both boundary ends, and where the normal has turned a table step out of the scan plane,
// or in all (in 3-D), since the last vertex (a turn θ does not see). The chain of
// vertices, in order along the curve, is the polygon that approximates the section; each
// sample between two vertices gets a fragment interpolated perspective-correctly along
// that chord.
//
// From one scan line to the next the vertices are θ trackers (§4.1, §3.5): each Table
// vertex follows its own G_i = 0 by bivariate Newton on (y - ys, G_i) from a start
// extrapolated from its last two lines, damped where a step would flip the normal's
// in-plane direction or the sign of T; ends and silhouette vertices are the edge and
// silhouette trackers of the Y scan; a turn vertex follows the zeros of §4.3's turn
// function (θ's derivative along the level curve) by Newton on (y - ys, T). The chain
// keeps its order (the links of §4.2). Where a link looks suspicious — tilt vertices or a
// lost tracker between its ends on the line before, θ, the tilt or the normal in all
// turning more than a table step across it, θ's sense of rotation not reversing at a turn
// or reversing elsewhere, θ's rate at an end against the link (a turn pair born across a
// vertex), J
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
#include "xscan/theta_chain.h"

namespace patchscan {

// Below this θ did not move (a step, or a link between two vertices).
constexpr double kTurnRad = 1e-9;
// A link crawled sideways has reached its end tracker when the crawl makes the same
// vertex (kind, index) within this many pixels of it: ten times the solves' tolerance.
constexpr double kLinkMatchPx = 1e-5;
// A link longer in (u,v) than twice its length on the line before plus this has jumped
// (a tracker converged onto another stretch of the curve): a ring born at a maximum
// widens as √(Δy), by at most √2 from its first line to its second.
constexpr double kLinkStretchUv = 1e-3;
// A link missing tabulated vertices is filled by Newton (ThetaWalker::FillLink) only while
// θ turns less than this many table steps along it; a longer one is crawled.
constexpr double kFillMaxTurnSteps = 3.0;
// A link whose normal has come to turn a table step or more along it, or whose chord
// misses the normal in its middle (and is sound otherwise), is split in halves by tilt
// vertices (ThetaWalker::SplitLink) at most this deep (up to 2^depth - 1 vertices); one
// still unsound is crawled. A link changes little from one line to the next: one split
// nearly always does.
constexpr int kSplitMaxDepth = 2;

// The table of N angles per turn (§4.1) as a walker judges turns by it: its step 2π/N, and
// the cosines of a step and of a step with a rounding margin beyond it (-1 for N < 2).
// Made once per scan: a walker lives for one surface's row, and the cosines of every
// walker were a measurable share of a scene of many small surfaces.
struct ThetaTable {
  static constexpr double kTurnSlackRad = 1e-6;
  // A crawl's link whose chord misses the surface's normal by more than this many table
  // steps somewhere between its ends gets a vertex there (theta_crawl.h, Crawler::Split).
  static constexpr double kChordSplitStep = 1.0 / 8;
  explicit ThetaTable(int n)
      : steps(n), step(2.0 * std::numbers::pi / n), cosStep(std::cos(std::min(std::numbers::pi, step))),
        cosTurn(std::cos(std::min(std::numbers::pi, step + kTurnSlackRad))), cosChordSplit(std::cos(kChordSplitStep * step)) {}
  int steps;
  double step, cosStep, cosTurn, cosChordSplit;
};

template <class ShapeT>
class ThetaWalker : public LevelWalker<ShapeT> {
  using Base = LevelWalker<ShapeT>;

 public:
  // `table`: N, the tabulated angles per turn, and what follows from it.
  ThetaWalker(const ShapeT& shape, const ScreenMap& map, double ys, const raster::SampleColumns& cols,
              Counters* counters, WalkEvents* events, const ThetaTable& table, const ThetaFrame& frame)
      : Base(shape, map, ys, cols, counters, events), steps_(table.steps), frame_(frame), table_(table.step),
        cosTable_(table.cosStep), cosTurn_(table.cosTurn), cosChordSplit_(table.cosChordSplit) {}

  using Vertex = ThetaVertex;

  // Walks every chain of the row: Make(const LevelPoint&) -> raster::Fragment;
  // Take(std::span<const Vertex> chain, bool closed) receives each chain. `chain` is
  // scratch.
  template <class Make, class Take>
  void WalkAll(const RowTrackers& t, std::vector<char>* edgeUsed, std::vector<char>* silUsed,
               std::vector<Vertex>* chain, Make&& make, Take&& take);

  // A trimmed surface's chains are cut at its trim crossings (LevelWalker::SetTrim): these
  // hold the pieces as they are made. Scratch kept by the caller.
  void SetTrimPieces(std::vector<Vertex>* piece, std::vector<Vertex>* first) {
    piece_ = piece;
    first_ = first;
  }

  // Every chain made is also shown to `sink` (none by default).
  void SetChainSink(ThetaChainSink* sink) { sink_ = sink; }

  // Whether vertices carry their normal's slope along the row (ThetaVertex::dndx), the
  // tangents of the chords' cubics (rows, and the links slabs refine): off by default.
  void SetNormalSlopes(bool on) { slopes_ = on; }
  // Whether the chains are interpolated on their own row only (θ rows: a link with no
  // sample column between its ends is never interpolated, and its turn is not judged), not
  // between lines (slabs): off by default.
  void SetRowChords(bool on) { rowChords_ = on; }

  // Advances the chains `from` of the line before, `dy` above this one, to this line as θ
  // trackers, in the same order, into *to (the trackers of this line in `t`): false if a
  // chain cannot be advanced (a tracker lost, an end or silhouette with no tracker, a link
  // whose sideways repair does not meet its other end, a tracker of the line left over),
  // and the line must be crawled afresh. `extrapolate`: start each Newton iteration from a
  // prediction (PredictedStart), else from the last line's position. `scratch` is scratch.
  template <class Make>
  bool Advance(const ChainSet& from, double dy, const RowTrackers& t, bool extrapolate, std::vector<char>* edgeUsed,
               std::vector<char>* silUsed, std::vector<Vertex>* scratch, ChainSet* to, Make&& make);

  // The θ tracker of table angle i on this line, and the turn tracker, from `start`
  // (tracker/theta_tracker.h).
  bool SolveTable(int i, const Vec2& start, LevelPoint* out, std::int64_t* iterations,
                  TableResidual* residual = nullptr, Vec2* rate = nullptr) const {
    return SolveThetaTracker(this->shape_, this->map_, this->ys_, frame_, Angle(i), start, out, iterations, residual,
                             rate);
  }
  bool SolveTurn(const Vec2& start, LevelPoint* out, std::int64_t* iterations, Vec2* rate = nullptr) const {
    return SolveTurnTracker(this->shape_, this->map_, this->ys_, frame_, start, out, iterations, rate);
  }

  // Where a tracker at uv on the line before, `dy` above this one, is looked for on this
  // line (Blinn 1978 §3.5's extrapolation): with its position `before` on the line before
  // that and its rate d(u,v)/d(ys) at uv, the quadratic through both with that slope at uv
  // (before + 2 dy rate, for equally spaced lines: its error O(dy³)); with one of them, the
  // line (O(dy²)); with neither, uv.
  static Vec2 PredictedStart(const Vec2& uv, const Vec2& before, const Vec2& rate, double dy) {
    const bool hasBefore = before.allFinite(), hasRate = rate.allFinite() && std::isfinite(dy);
    if (hasBefore && hasRate) return before + 2.0 * dy * rate;
    if (hasBefore) return 2.0 * uv - before;
    if (hasRate) return uv + dy * rate;
    return uv;
  }

  // (cos θ_i, sin θ_i).
  Vec2 Angle(int i) const {
    if (static_cast<std::size_t>(i) < frame_.angles.size()) return frame_.angles[static_cast<std::size_t>(i)];
    return Vec2(std::cos(i * table_), std::sin(i * table_));
  }

 private:
  template <class Make>
  class Crawler;  // theta_crawl.h
  std::int64_t& Count(Counter c) { return (*this->counters_)[c]; }

  template <class Make>
  Vertex MakeVertex(const LevelPoint& p, Make& make, ThetaVertex::Kind kind = ThetaVertex::Kind::End,
                    int index = -1) const {
    return MakeVertexOf(p, make(p), kind, index);
  }
  // The vertex at p whose fragment, make(p), is made already.
  Vertex MakeVertexOf(const LevelPoint& p, const raster::Fragment& f, ThetaVertex::Kind kind, int index = -1) const {
    Vertex v{p.x, f, kind, index};
    v.uv = p.uv;
    const Vec3 ray = frame_.Ray(v.f.position), plane = frame_.ScanPlaneNormal(ray);
    v.theta = ThetaFrame::ThetaOn(ray, plane, v.f.normal);
    v.tilt = ThetaFrame::TiltOn(plane, v.f.normal);
    v.inView = ThetaFrame::InView(ray, plane, v.f.normal);
    if (slopes_) {
      SurfaceDerivs second;
      const SurfaceDerivs* o = &p.object;
      if (!p.second) {
        this->shape_.Evaluate(p.uv.x(), p.uv.y(), DerivOrder::Second, &second);
        o = &second;
      }
      if (kind == ThetaVertex::Kind::Silhouette) {
        RootSlopes(p, *o, ray, &v);
      } else {
        const Vec2 duv = p.UvPerPixelAlongRow();
        const Vec3 dpdx = p.object.dpdu * duv.x() + p.object.dpdv * duv.y();  // object space
        v.dwdx = this->map_.ViewDepthChange(dpdx);
        v.dndx = NormalSlope(*o, duv, frame_);
        v.tiltRate = v.dndx.dot(plane) / std::cos(v.tilt);
        v.silhouetteX = SilhouetteX(v, ray, plane, frame_.World().linear() * dpdx);
      }
    }
    if (kind == ThetaVertex::Kind::Silhouette) v.silhouetteX = v.x;
    return v;
  }
  // A silhouette vertex's slopes, per root pixel (ThetaVertex::dndx): there the view ray is
  // the section's tangent, so moving a parameter τ along the section (its direction d in
  // (u,v), y constant) the point moves along the ray, x stands still, and x - xs = x''τ²/2,
  // x'' = d^T (H_x - λ H_y) d with ∇x = λ ∇y (x's second derivative along the level curve:
  // its curvature in (u,v) enters through y's Hessian). Then √|x - xs| = τ √(|x''| / 2) and
  // the normal and eye distance change by their τ-derivatives times √(2 / |x''|) per root
  // pixel, signed for the side where the section faces the eye (its toward-eye component
  // -n·ray rising; the ray itself stands still along τ there). NaN where degenerate.
  void RootSlopes(const LevelPoint& p, const SurfaceDerivs& o, const Vec3& ray, Vertex* v) const {
    ScreenDerivs s;
    this->map_.FromObject(o, DerivOrder::Second, &s);
    const Vec2 d(p.gradY.y(), -p.gradY.x());
    const double lambda = p.gradX.dot(p.gradY) / p.gradY.squaredNorm();
    const auto along = [&](int k) {
      return d.x() * d.x() * s.d2pdu2[k] + 2.0 * d.x() * d.y() * s.d2pduv[k] + d.y() * d.y() * s.d2pdv2[k];
    };
    const double xpp = along(0) - lambda * along(1);
    const Vec3 dn = NormalSlope(o, d, frame_);
    const double facing = -dn.dot(ray);
    if (!(std::abs(xpp) > 0.0) || !(std::abs(facing) > 0.0) || !std::isfinite(xpp)) return;
    const double perRoot = (facing > 0.0 ? 1.0 : -1.0) * std::sqrt(2.0 / std::abs(xpp));
    v->dndx = perRoot * dn;
    v->dwdx = perRoot * this->map_.ViewDepthChange(o.dpdu * d.x() + o.dpdv * d.y());
  }
  // Where along the row the silhouette nearest vertex v lies, from θ's distance ε to the
  // nearest silhouette angle (0 or π) and ε's rate along the row, as if the section were a
  // circle there (orthographic: x - xs = R (1 - cos ε), dε/dx = 1 / (R sin ε)), so that
  // |x - xs| = tan(ε/2) / |dε/dx|; near a silhouette any section is that parabola. θ's rate
  // is the normal's turning in the scan plane less the view ray's (in perspective the ray
  // to the point turns within the plane by dpdx·side / |p - eye| radians per pixel, where
  // `dpdx` is the point's world motion per pixel along the row).
  double SilhouetteX(const Vertex& v, const Vec3& ray, const Vec3& plane, const Vec3& dpdx) const {
    const Vec3 side = ray.cross(plane);
    const double a = -v.f.normal.dot(ray), b = v.f.normal.dot(side);
    double rate = (b * -v.dndx.dot(ray) - a * v.dndx.dot(side)) / (a * a + b * b);  // dθ/dx
    if (!frame_.orthographic) rate -= dpdx.dot(side) / (v.f.position - frame_.eye).norm();
    const double at = std::abs(v.theta);
    const bool toZero = at < 0.5 * std::numbers::pi;
    const double eps = toZero ? at : std::numbers::pi - at;
    const double epsRate = (toZero == (v.theta >= 0.0) ? 1.0 : -1.0) * rate;
    return v.x - std::tan(0.5 * eps) / epsRate;  // NaN or ±inf where ε stands still
  }
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
  // Whether v lies on the step from a to b in (u,v): along the chord between its ends, and
  // within a quarter of its length off it.
  static bool WithinStep(const Vec2& a, const Vec2& b, const Vec2& v) {
    const Vec2 d = b - a;
    const double len2 = d.squaredNorm();
    if (!(len2 > 0.0)) return (v - a).norm() <= kSameCrossingUv;
    const double t = (v - a).dot(d) / len2;
    const double off = std::abs((v - a).x() * d.y() - (v - a).y() * d.x()) / std::sqrt(len2);
    constexpr double kSlack = 1e-3;  // of the step: rounding at its ends
    return t >= -kSlack && t <= 1.0 + kSlack && off <= 0.25 * std::sqrt(len2) + kSameCrossingUv;
  }
  static bool WithinStep(const LevelPoint& a, const LevelPoint& b, const LevelPoint& v) {
    return WithinStep(a.uv, b.uv, v.uv);
  }
  // The tabulated angles i 2π/N passed going from θ = a by d, in that order: those beyond a
  // by more than kOnAngleRad (a vertex made on a tabulated angle has it to within rounding)
  // and short of a + d by as much, or up to a + d itself `withEnd`. visit(angle, k) gets
  // each (unwrapped: a + t d) with its table index k in [0, N), silhouettes' angles (0 and
  // π) included, and returns whether to go on; false if it stopped.
  static constexpr double kOnAngleRad = 1e-8;
  template <class Visit>
  bool ForEachTableAngle(double a, double d, bool withEnd, Visit&& visit) const {
    const double dir = d > 0.0 ? 1.0 : -1.0, reach = std::abs(d);
    const double first = d > 0.0 ? std::floor((a + kOnAngleRad) / table_) + 1.0
                                 : std::ceil((a - kOnAngleRad) / table_) - 1.0;
    for (double i = first;; i += dir) {
      const double along = dir * (i * table_ - a);
      if (!(withEnd ? along <= reach : along < reach - kOnAngleRad)) return true;  // NaN too
      const long index = static_cast<long>(i) % steps_;
      if (!visit(i * table_, static_cast<int>(index < 0 ? index + steps_ : index))) return false;
    }
  }
  // Whether a tabulated angle is a silhouette's (0 or π: those vertices are found by the
  // sign of J, not by θ).
  static bool SilhouetteAngle(double angle) { return std::abs(std::sin(angle)) < 1e-12; }
  // Whether x lies strictly between a and b (the vertices of a chain between anchors
  // run one way in x).
  static bool Between(double x, double a, double b) { return (x - a) * (b - x) > 0.0; }
  // Whether crawl vertex v is the link's target.
  static bool SameVertex(const Vertex& v, const Vertex& target) {
    return v.kind == target.kind && v.index == target.index && std::abs(v.x - target.x) <= kLinkMatchPx;
  }
  // Whether the link a-b advanced from A-B needs a repair (theta_advance.h): sound, missing
  // only tabulated vertices between its ends, sound but for its normal turning a table step
  // or more (TurnsPastStep: to be split), or to be crawled sideways.
  enum class LinkCheck { Sound, MissingTable, Split, Broken };
  LinkCheck CheckLink(const Vertex& A, const Vertex& B, const Vertex& a, const Vertex& b) const;
  // The link a-b's missing tabulated vertices by Newton: *out = a, them, b; false if any is
  // not found where it belongs (theta_advance.h).
  template <class Make>
  bool FillLink(const Vertex& a, const Vertex& b, std::vector<Vertex>* out, Make& make);
  // The link a-b split by tilt vertices until no part turns a table step and each part's
  // chord meets the surface's normal in its middle: *out = a, them, b; false if a vertex is
  // not found where it belongs or the parts are not sound at kSplitMaxDepth
  // (theta_advance.h).
  template <class Make>
  bool SplitLink(const Vertex& a, const Vertex& b, std::vector<Vertex>* out, Make& make);
  template <class Make>
  bool SplitInto(const Vertex& a, const Vertex& b, int depth, std::optional<bool> facing, std::vector<Vertex>* out,
                 Make& make);
  // Whether the vertex's normal faces the eye.
  bool Facing(const Vertex& v) const {
    return v.f.normal.dot(frame_.orthographic ? frame_.forward : Vec3(v.f.position - frame_.eye)) > 0.0;
  }
  // How a link's ends face (a silhouette end faces neither way; none if both are).
  std::optional<bool> LinkFacing(const Vertex& a, const Vertex& b) const {
    if (a.kind != ThetaVertex::Kind::Silhouette) return Facing(a);
    if (b.kind != ThetaVertex::Kind::Silhouette) return Facing(b);
    return std::nullopt;
  }

  int steps_;
  ThetaFrame frame_;
  double table_;  // 2π / N
  // A crawl's points since its chain's last vertex, with the surface's normal at each
  // (Crawler::Push judges the link's chord by them). A walker lives for one surface's row
  // and crawls one chain at a time, so the points' storage is the thread's, reused by every
  // crawl on it: no allocation once it has grown.
  struct CrawlPoint {
    LevelPoint p;
    Vec3 normal;
  };
  static std::vector<CrawlPoint>& CrawlPoints() {
    static thread_local std::vector<CrawlPoint> points;
    return points;
  }
  // Whether the normal turns a table step or more between two vertices, given by their
  // tilts and their normals in the view's frame (ThetaVertex::inView): out of the scan
  // plane, or in all (θ and the tilt may each be within a step and together more). The
  // crawl, the advance's link check and FillLink all judge a link by this.
  // A chord (rows, not slabs) with no sample column strictly between its ends is never
  // interpolated on its row, whatever its normal does: not judged.
  bool TurnsPastStep(double xa, double tiltA, const Vec3& inViewA, double xb, double tiltB, const Vec3& inViewB) const {
    if (rowChords_ && !SamplesBetween(xa, xb)) return false;
    return std::abs(tiltB - tiltA) >= table_ || TurnsTooFar(inViewA, inViewB);
  }
  bool TurnsPastStep(const Vertex& a, const Vertex& b) const {
    return TurnsPastStep(a.x, a.tilt, a.inView, b.x, b.tilt, b.inView);
  }
  // Whether a sample column lies strictly between screen x a and b (beyond kColumnEpsPx).
  bool SamplesBetween(double a, double b) const {
    const double lo = std::min(a, b), hi = std::max(a, b);
    return this->cols_.Floor(hi - kColumnEpsPx) >= this->cols_.Ceil(lo + kColumnEpsPx);
  }
  // The turn in all, measured in the view's frame, where θ is the longitude and the tilt
  // the latitude (in perspective the view ray turns along the section too, which θ leaves
  // out), with θ's part at most a step: θ's own overshoot of a table step (a vertex solved
  // a little past its angle) is not a turn the chord misses. For the view-frame normals a
  // and b: cos d = sin t_a sin t_b + cos t_a cos t_b cos(min(|Δθ|, step)), where
  // cos t_a cos t_b cos Δθ is the dot of their (S, T) parts and cos t = |(S, T)|.
  bool TurnsTooFar(const Vec3& a, const Vec3& b) const {
    const double inPlane = a.x() * b.x() + a.y() * b.y();
    const double cc = std::sqrt((a.x() * a.x() + a.y() * a.y()) * (b.x() * b.x() + b.y() * b.y()));
    return a.z() * b.z() + std::max(inPlane, cc * cosTable_) < cosTurn_;
  }
  double cosTable_, cosTurn_, cosChordSplit_;  // ThetaTable's cosStep, cosTurn and cosChordSplit
  ThetaChainSink* sink_ = nullptr;
  bool slopes_ = false, rowChords_ = false;
  std::vector<Vertex>*piece_ = nullptr, *first_ = nullptr;

  // Hands `chain` to take, or on a trimmed surface the pieces of it the trim keeps, each
  // ending on a vertex at the trim crossing (an End vertex, on the curve exactly): the
  // chain's links are the walk's arcs (x-monotone between vertices), and the crossings on
  // each are found and toggled as the exact walk does. A closed chain cut somewhere is
  // open pieces; its last piece runs on into its first.
  // A piece ending at v on a trim crossing along a shared edge whose crossing edgeX lies
  // past v on the side `outward` reaches on to it: a vertex there with v's attributes (the
  // exact walk's LevelWalker::FillToEdge, as a chord).
  static void ReachEdge(const Vertex& v, double edgeX, double outward, std::vector<Vertex>* piece) {
    if (!std::isfinite(edgeX) || outward * (edgeX - v.x) <= kColumnEpsPx) return;
    Vertex w = v;
    w.x = edgeX;
    piece->push_back(w);
  }

  template <class Make, class Take>
  void TakeTrimmed(const std::vector<Vertex>& chain, bool closed, Make& make, Take& take) {
    if (!this->trim_ || chain.size() < 2) {
      if (!this->trim_ || chain.empty() || this->trim_->Kept(chain.front().uv)) take(std::span<const Vertex>(chain), closed);
      return;
    }
    std::vector<Vertex>& piece = *piece_;
    std::vector<Vertex>& first = *first_;
    piece.clear();
    first.clear();
    const Vec2 d0 = chain[1].uv - chain[0].uv;
    this->StartTrimToward(chain[0].uv, d0.norm() > 0.0 ? Vec2(d0 / d0.norm()) : Vec2(1.0, 0.0));
    const bool startKept = this->kept_;
    bool cut = false;
    if (this->kept_) {
      // The walk enters the kept region at its start: it reaches back to a shared edge there.
      const double outward = chain[1].x >= chain[0].x ? -1.0 : 1.0;
      for (std::size_t k = 0; k < this->trackers_->trimPoints.size(); ++k)
        if ((this->trackers_->trimPoints[k] - chain[0].uv).norm() <= kTrimStartUv)
          ReachEdge(chain[0], this->trackers_->trimEdgeX[k], outward, &piece);
      piece.push_back(chain[0]);
    }
    for (std::size_t k = 1; k < chain.size(); ++k) {
      const Vertex &a = chain[k - 1], &b = chain[k];
      this->BeginArc(a.uv, a.x, b.uv, b.x);
      for (const auto& [x, index] : this->trimScratch_->arc) {
        const LevelPoint q = this->Eval(this->trackers_->trimPoints[static_cast<std::size_t>(index)]);
        if (!q.ok) continue;
        const Vertex v = MakeVertex(q, make);
        const double edgeX = this->trackers_->trimEdgeX[static_cast<std::size_t>(index)];
        if (this->kept_) {
          piece.push_back(v);
          ReachEdge(v, edgeX, this->arcDir_, &piece);
          if (!cut && closed && startKept) first.swap(piece);  // runs on from the last piece
          else take(std::span<const Vertex>(piece), false);
          piece.clear();
        } else {
          piece.clear();
          ReachEdge(v, edgeX, -this->arcDir_, &piece);
          piece.push_back(v);
        }
        this->kept_ = !this->kept_;
        cut = true;
      }
      this->trimScratch_->arc.clear();
      if (this->kept_) piece.push_back(b);
    }
    if (!cut) {
      if (startKept) take(std::span<const Vertex>(chain), closed);
      return;
    }
    if (!first.empty() && this->kept_) piece.insert(piece.end(), first.begin() + 1, first.end());
    else if (!first.empty()) take(std::span<const Vertex>(first), false);  // an odd count: a crossing missed
    if (this->kept_ && piece.size() >= 2) take(std::span<const Vertex>(piece), false);
  }
};

template <class ShapeT>
template <class Make, class Take>
void ThetaWalker<ShapeT>::WalkAll(const RowTrackers& t, std::vector<char>* edgeUsed,
                                  std::vector<char>* silUsed, std::vector<Vertex>* chain,
                                  Make&& make, Take&& take) {
  this->Bind(t, edgeUsed, silUsed);
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
    TakeTrimmed(*chain, false, make, take);
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
    TakeTrimmed(*chain, true, make, take);
  }
}

}  // namespace patchscan

#include "xscan/theta_advance.h"
#include "xscan/theta_crawl.h"
