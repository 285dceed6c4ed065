// The back end's second input: exact per-sample fragments, for renders whose
// front end finds each visible sample's surface point itself (Blinn 1978 §3.3, the exact
// X scan) instead of handing over triangles.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <utility>

#include "core/hermite.h"
#include "raster/mesh.h"

namespace patchscan::raster {

// One surface point seen at one sample.
struct Fragment {
  double w = 0.0;      // eye distance along the view axis (> 0 in front of the eye)
  Vec3 position;       // world space
  Vec3 normal;         // world space, unit
  Vec2 uv;
  Vec2 duvdx, duvdy;   // change of uv per pixel in screen x and y (texture footprint)
  std::uint32_t surfaceId = 0;
  Vec3 colour = Vec3::Ones();  // multiplies the surface's colour (a polygon's "Cs")
};

// The sample columns of one sample row: x = x0 + i dx, i in [0, n).
struct SampleColumns {
  double x0 = 0.0, dx = 1.0;
  int n = 0;
  double At(int i) const { return x0 + i * dx; }
  // First column at or right of x, clamped to [0, n]; last at or left of x, clamped to
  // [-1, n - 1]. NaN gives an empty range.
  int Ceil(double x) const {
    const double k = std::ceil((x - x0) / dx);
    return k >= 0.0 ? (k <= n ? static_cast<int>(k) : n) : (k < 0.0 ? 0 : n);
  }
  int Floor(double x) const {
    const double k = std::floor((x - x0) / dx);
    return k <= n - 1 ? (k >= -1.0 ? static_cast<int>(k) : -1) : (k > n - 1 ? n - 1 : -1);
  }
};

// A sample column this close to a point in x (pixels) counts as reached: ten times the
// front end's solves' tolerance, far below the 1e-3 px within which coverage may differ.
constexpr double kColumnEpsPx = 1e-6;

// A chord end's unit normal and eye distance derivatives per pixel along the row (NaN:
// unknown), and how far past it, away from the chord, the section has a silhouette: x
// stands still there, the slopes are infinite, and the attributes go as the square root
// of the distance in x from it (0: the end lies on one, and its slopes are per root pixel,
// d/d√|x - xs|, finite; infinite: none near).
struct ChordSlope {
  Vec3 normal = Vec3::Constant(NAN);
  double depth = NAN;
  double silhouette = INFINITY;  // pixels
};

// A chord of a surface's section along one sample row (θ mode, Blinn 1978 §4: the link
// between two chain vertices): the screen x and fragment of each end, in front of the eye.
// It covers the columns past xa up to xb (within kColumnEpsPx), or, a point chord (xa ==
// xb), the one column at xa. Along it the attributes are blended perspective-correctly
// (1/w affine in screen x; orthographic: w), except where the ends' slopes along the row
// are known (Slope): there the normal and the eye distance (its inverse, in
// perspective) follow cubics in screen x with those tangents (Hermite), whose error falls
// as the fourth power of the chord's length where the blend's falls as the square. Near a
// silhouette they follow cubics in the square root of the distance from it. Made whole by
// a constructor (its cubics follow from its ends), then only read.
class Chord {
 public:
  using Slope = ChordSlope;
  Chord() = default;
  // A point chord: the one column at x.
  Chord(double x, const Fragment& f, bool orthographic) : xa_(x), xb_(x), a_(f), b_(f), orthographic_(orthographic) {}
  // From xa to xb. An end's normal slope is kept where it would turn the normal by at most
  // kNormalTurnRatio times the turn between the ends across the chord (plus kSlopeFloor
  // radians), its depth slope where the normal's would turn it by at most kSlopeTurnRatio
  // times that and, along the depth's change, it is at most kDepthSlopeRatio times that
  // change: on a silhouette, or near one, the section turns as the square root of x and
  // the slopes there are infinite or huge, no tangents for a cubic in x.
  Chord(double xa, const Fragment& a, double xb, const Fragment& b, bool orthographic, const Slope& slopeA = {},
        const Slope& slopeB = {})
      : xa_(xa), xb_(xb), invSpan_(1.0 / (xb - xa)), invWa_(1.0 / a.w), invWb_(1.0 / b.w), a_(a), b_(b),
        orthographic_(orthographic) {
    TextureCubic();
    const double span = xb - xa, turn = (b.normal - a.normal).norm();
    const Vec3 ta = span * slopeA.normal, tb = span * slopeB.normal;
    const double sa = span * (orthographic ? slopeA.depth : -slopeA.depth / (a.w * a.w));
    const double sb = span * (orthographic ? slopeB.depth : -slopeB.depth / (b.w * b.w));
    const auto fits = [&](const Vec3& t, double s, double ratio) {
      return TangentFits(t.norm(), turn, ratio) && std::isfinite(s);
    };
    const bool nearA = slopeA.silhouette <= kSilhouetteNear * std::abs(span);
    const bool nearB = slopeB.silhouette <= kSilhouetteNear * std::abs(span);
    if (nearA != nearB) {
      // One end on a silhouette or near one, where the view ray is the section's tangent:
      // near it the section is a parabola in (screen x, depth), and x - xs goes as the
      // square of the distance along it, so the normal and the depth are smooth in
      // √(x - xs) (their Puiseux series), not in x (their tangents at xs are infinite).
      // With the silhouette a gap g past the end (a fraction u0 = g / (g + |span|) of the
      // way from it to the far end), the parameter is p = √(u0 + (1 - u0) t') mapped onto
      // [0, 1] (t' = t from that end), and the cubics in it take both ends' tangents,
      // dt'/dp = 2 √u0 / (1 + √u0) at the near end (on the silhouette, where that is 0
      // against an infinite slope, its slope per root pixel instead) and 2 / (1 + √u0) at
      // the far end. A blend in t is off near the silhouette by a fifth of the depth across
      // the chord.
      const double g = nearA ? slopeA.silhouette : slopeB.silhouette;
      cubics_.u0 = g / (g + std::abs(span));
      r0_ = std::sqrt(cubics_.u0), inv1r0_ = 1.0 / (1.0 - r0_);
      const double r0 = r0_, atNear = 2.0 * r0 / (1.0 + r0), atFar = 2.0 / (1.0 + r0);
      const double fa = nearA ? atNear : atFar, fb = nearA ? atFar : atNear;
      Vec3 pa = fa * ta, pb = fb * tb;
      double qa = fa * sa, qb = fb * sb;
      if (g == 0.0) {
        // An end on the silhouette has its slopes per root pixel (d/d√|x - xs|, away from
        // it): t' = p² there, so its tangent in p is they times √|span|, signed as p runs
        // (from a to b: away from the silhouette at a, towards it at b).
        const Slope& on = nearA ? slopeA : slopeB;
        const Fragment& end = nearA ? a : b;
        const double root = (nearA ? 1.0 : -1.0) * std::sqrt(std::abs(span));
        (nearA ? pa : pb) = root * on.normal;
        (nearA ? qa : qb) = root * (orthographic ? on.depth : -on.depth / (end.w * end.w));
      }
      const bool ka = fits(pa, qa, kNormalTurnRatio), kb = fits(pb, qb, kNormalTurnRatio);
      const bool da = fits(pa, qa, kSlopeTurnRatio), db = fits(pb, qb, kSlopeTurnRatio);
      cubic_ = true;
      cubics_.root = nearA ? 1 : 2;
      HermiteCoefficients(a.normal, b.normal, pa, pb, ka, kb, cubics_.normal);
      HermiteCoefficients(Depth(a.w), Depth(b.w), qa, qb, da, db, cubics_.depth);
      return;
    }
    // An end on the silhouette gives no tangent in x (its slopes are per root pixel). A
    // depth tangent along the depth's change across the chord and steeper than
    // kDepthSlopeRatio times it is no tangent of the chord either: the section's depth is
    // steep only over a part of it near that end (a turn point all but on a silhouette,
    // whose estimate of the silhouette's place says nothing, θ standing still there), and
    // the cubic through it overshot both ends. One against the change (the depth's
    // extremum within the chord) is kept as the normal's bound allows.
    const bool onA = slopeA.silhouette == 0.0, onB = slopeB.silhouette == 0.0;
    const double depthChange = Depth(b.w) - Depth(a.w);
    const double depthFloor = kSlopeFloor * std::max(std::abs(Depth(a.w)), std::abs(Depth(b.w)));
    const auto depthFits = [&](double s) {
      return s * depthChange <= 0.0 || std::abs(s) <= kDepthSlopeRatio * std::abs(depthChange) + depthFloor;
    };
    const bool ka = !onA && fits(ta, sa, kNormalTurnRatio), kb = !onB && fits(tb, sb, kNormalTurnRatio);
    const bool da = !onA && fits(ta, sa, kSlopeTurnRatio) && depthFits(sa);
    const bool db = !onB && fits(tb, sb, kSlopeTurnRatio) && depthFits(sb);
    cubic_ = ka || kb;  // kNormalTurnRatio >= kSlopeTurnRatio: da implies ka
    if (!cubic_) return;
    HermiteCoefficients(a.normal, b.normal, ta, tb, ka, kb, cubics_.normal);
    HermiteCoefficients(Depth(a.w), Depth(b.w), sa, sb, da, db, cubics_.depth);
  }
  static constexpr double kSlopeTurnRatio = 2.0, kSlopeFloor = 1e-3;
  // The normal's own bound is looser: a section whose normal turns fast at one end and
  // slowly at the other (a dome's, from its rim to its crown) has one end's tangent several
  // times the turn across the chord, and a blend there was wrong by up to 20° in the middle
  // (the teapot's lid at 4 θ steps). Measured at 4 and 8 steps on the teapot, teacup and
  // teaspoon (1024x768, against the exact render), the ratios 2, 4, 8 and 16 gave 99th-
  // percentile normal errors of 22.2, 20.4, 12.5, 14.2° (teapot, 4 steps) and maxima of
  // 28.5, 14.9, 10.8, 12.2° (teapot, 8 steps): 8 is best or near it on each; unbounded,
  // single pixels overshot to 40°. The depth's tangents keep the tighter bound: with the
  // normal's, the cubic in 1/w overshot by 29% of the depth beside the spout's silhouette.
  static constexpr double kNormalTurnRatio = 8.0;
  static_assert(kNormalTurnRatio >= kSlopeTurnRatio);
  // A cubic whose end tangents are at most 3 times its secant's slope, and of its sign,
  // stays between its end values (Fritsch and Carlson's condition for a monotone cubic,
  // SIAM J. Numer. Anal. 17(2), 1980): the bound on a depth tangent against the depth's
  // change across the chord (plus kSlopeFloor of the depth), in the chord's own parameter.
  static constexpr double kDepthSlopeRatio = 3.0;
  // A silhouette this many times the chord's length past an end, or nearer, makes the
  // chord's parameter the root of the distance from it.
  static constexpr double kSilhouetteNear = 1.0;

  // The cubics (lowest power first) of the normal and of the interpolated depth (1/w in
  // perspective, w orthographic), when the ends' slopes or a silhouette gave them, in
  // p = t (root 0), or in the root of the distance from a silhouette near a (1) or near b
  // (2): p = R(t) or 1 - R(1 - t), R(t) = (√(u0 + (1 - u0) t) - √u0) / (1 - √u0), u0 the
  // silhouette's gap as a fraction of its distance to the far end. A chord's ends and
  // cubics are the whole of it: a copy made from them (another process's) is the same
  // chord bit for bit.
  struct Cubics {
    Vec3 normal[4] = {Vec3::Zero(), Vec3::Zero(), Vec3::Zero(), Vec3::Zero()};
    double depth[4] = {};
    int root = 0;
    double u0 = 0.0;
  };
  const Cubics* cubics() const { return cubic_ ? &cubics_ : nullptr; }
  bool orthographic() const { return orthographic_; }
  Chord(double xa, const Fragment& a, double xb, const Fragment& b, bool orthographic, const Cubics* cubics)
      : xa_(xa), xb_(xb), invSpan_(1.0 / (xb - xa)), invWa_(1.0 / a.w), invWb_(1.0 / b.w), a_(a), b_(b),
        orthographic_(orthographic), cubic_(cubics != nullptr) {
    TextureCubic();
    if (cubics) cubics_ = *cubics, r0_ = std::sqrt(cubics_.u0), inv1r0_ = 1.0 / (1.0 - r0_);
  }

  double xa() const { return xa_; }
  double xb() const { return xb_; }
  const Fragment& a() const { return a_; }
  const Fragment& b() const { return b_; }

  // The columns it covers: `count` of them from `first`, by `step` (±1, from xa).
  struct Columns {
    int first = 0, step = 1, count = 0;
  };
  Columns ColumnsOn(const SampleColumns& cols) const {
    if (xa_ == xb_) {
      const int c = cols.Ceil(xa_ - kColumnEpsPx);
      if (c >= cols.n || std::abs(cols.At(c) - xa_) > kColumnEpsPx) return {};
      return {c, 1, 1};
    }
    if (xb_ > xa_) {
      const int first = cols.Ceil(xa_ + kColumnEpsPx);
      return {first, 1, std::max(0, cols.Floor(xb_ + kColumnEpsPx) - first + 1)};
    }
    const int first = cols.Floor(xa_ - kColumnEpsPx);
    return {first, -1, std::max(0, first - cols.Ceil(xb_ - kColumnEpsPx) + 1)};
  }
  // Calls f(column) for each column covered, in order from xa; returns how many.
  template <class F>
  int ForEachColumn(const SampleColumns& cols, F&& f) const {
    const Columns r = ColumnsOn(cols);
    for (int k = 0, c = r.first; k < r.count; ++k, c += r.step) f(c);
    return r.count;
  }
  // Calls f(column, 1/w) for each column covered, in order from xa, with the inverse of
  // the eye distance there: the depth test's key, which in perspective is what the chord
  // interpolates (no division; DepthAt's w is its inverse, within rounding). Its choices
  // (point, cubic, root, projection) are made once per chord. Returns how many.
  template <class F>
  int ForEachColumnInverseDepth(const SampleColumns& cols, F&& f) const {
    const Columns r = ColumnsOn(cols);
    const auto each = [&](auto depth) {
      for (int k = 0, c = r.first; k < r.count; ++k, c += r.step) f(c, depth(Along(cols.At(c))));
    };
    const auto key = [this](double d) { return orthographic_ ? 1.0 / d : d; };
    if (xa_ == xb_) {
      const double inv = 1.0 / a_.w;
      each([&](double) { return inv; });
    } else if (!cubic_) {
      const double da = Depth(a_.w), db = Depth(b_.w);
      each([&](double t) { return key((1.0 - t) * da + t * db); });
    } else if (cubics_.root == 0) {
      each([&](double t) { return key(Horner(cubics_.depth, t)); });
    } else {
      each([&](double t) { return key(Horner(cubics_.depth, Param(t))); });
    }
    return r.count;
  }
  // The eye distance at screen x (a column it covers).
  double DepthAt(double x) const { return xa_ == xb_ ? a_.w : DepthAlong(Along(x)); }
  // The fragment at screen x (a column it covers): a point chord's own, or the ends'
  // attributes blended as above (the normal renormalised; the texture footprint blended as
  // the position is: a bump map's gradient is the footprint's, and the nearer end's was off
  // by the perspective's change across the chord, 5% of a bump's tilt on a slanted plane).
  Fragment At(double x) const {
    if (xa_ == xb_) return a_;
    const double t = Along(x);
    const auto [ia, ib] = EndWeights(t);
    const double sum = ia + ib, inv = 1.0 / sum;
    const double wa = ia * inv, wb = ib * inv;
    double root = NAN;
    const double p = cubic_ ? Param(t, &root) : t;
    Fragment f = a_;
    f.w = cubic_ || orthographic_ ? DepthAlong(t, p) : inv;
    f.position = wa * a_.position + wb * b_.position;
    const Vec3 n = cubic_ ? Horner(cubics_.normal, p) : Vec3(wa * a_.normal + wb * b_.normal);
    f.normal = n * (1.0 / n.norm());
    if (!f.normal.allFinite()) f.normal = a_.normal;
    if (cubic_ && cubics_.root != 0) {
      RootTexture(p, root, &f);
      return f;
    }
    f.uv = uvCubic_ ? Horner(uv_, t) : Vec2(wa * a_.uv + wb * b_.uv);
    f.duvdx = wa * a_.duvdx + wb * b_.duvdx;
    f.duvdy = wa * a_.duvdy + wb * b_.duvdy;
    return f;
  }

  // The unit normal the ends' perspective-correct blend gives at t in [0, 1] (as a slab
  // triangle interpolates it), whatever the chord's cubics.
  Vec3 BlendedNormal(double t) const {
    const auto [ia, ib] = EndWeights(t);
    return (ia * a_.normal + ib * b_.normal).normalized();
  }

 private:
  double xa_ = 0.0, xb_ = 0.0;
  double invSpan_ = 0.0;  // 1 / (xb - xa)
  double invWa_ = 0.0, invWb_ = 0.0;  // 1 / a.w and 1 / b.w
  Fragment a_, b_;
  bool orthographic_ = false;
  // With slopes: the normal's and the depth's (Depth) cubics.
  bool cubic_ = false;
  Cubics cubics_;
  double r0_ = 0.0, inv1r0_ = 1.0;  // √cubics_.u0 and 1 / (1 - √cubics_.u0)
  // The texture coordinates' cubic in t, when the ends' slopes gave one (TextureCubic).
  bool uvCubic_ = false;
  Vec2 uv_[4];

  double Along(double x) const { return std::clamp((x - xa_) * invSpan_, 0.0, 1.0); }
  // The ends' weights at t, unnormalised: 1/w's share in perspective (whose sum is the
  // blended 1/w itself), 1 - t and t orthographic.
  std::pair<double, double> EndWeights(double t) const {
    return orthographic_ ? std::pair{1.0 - t, t} : std::pair{(1.0 - t) * invWa_, t * invWb_};
  }
  // Whether a tangent of this length (per unit t) fits a chord across which the attribute
  // changes by `change`: no longer than `ratio` times it plus kSlopeFloor (false for NaN
  // and infinity).
  static bool TangentFits(double length, double change, double ratio = kSlopeTurnRatio) {
    return length <= ratio * change + kSlopeFloor;
  }
  // The cubics' parameter at t (Cubics::root), and into *root, where given and the
  // parameter is a root's, √(u0 + (1 - u0) s) for s = t's distance from the near end (the
  // texture footprint's growth is its inverse, RootTexture).
  double Param(double t, double* root = nullptr) const {
    if (cubics_.root == 0) return t;
    const double s = cubics_.root == 1 ? t : 1.0 - t;
    const double q = cubics_.u0 == 0.0 ? std::sqrt(s) : std::sqrt(cubics_.u0 + (1.0 - cubics_.u0) * s);
    if (root) *root = q;
    const double r = cubics_.u0 == 0.0 ? q : (q - r0_) * inv1r0_;
    return cubics_.root == 1 ? r : 1.0 - r;
  }
  // The texture coordinates' cubic in t from the ends' own change per pixel along the row
  // (a fragment's duvdx: the surface's, exact), when both are known and fit the chord as
  // its normal's slopes must (no longer than kSlopeTurnRatio times the change across it,
  // plus kSlopeFloor texture units: near a silhouette the front end clamps a footprint,
  // which is then no slope): the texture then lies within the fourth power of the chord's
  // length of the surface's, where the blend's error (the square) moved every texture edge
  // by a fraction of a pixel. Derived from the ends alone, so a decoded copy of a chord
  // has it bit for bit.
  void TextureCubic() {
    if (xa_ == xb_) return;
    const double span = xb_ - xa_, change = (b_.uv - a_.uv).norm();
    const Vec2 ta = span * a_.duvdx, tb = span * b_.duvdx;
    uvCubic_ = TangentFits(ta.norm(), change) && TangentFits(tb.norm(), change);
    if (uvCubic_) HermiteCoefficients(a_.uv, b_.uv, ta, tb, true, true, uv_);
  }
  // A chord near a silhouette: the texture coordinates go as its root parameter p (as the
  // normal and depth do; a blend in t placed the texture by the square of the distance
  // from the silhouette), and the footprint grows towards the silhouette as dt/dp does, as
  // the surface's own does (1/√ of the distance from it): the far end's, scaled by
  // dp/dt there over dp/dt at t, which is 1/√(u0 + (1 - u0) t') (t' the fraction from the
  // near end), and no longer than the near end's (the silhouette's own is clamped by the
  // front end). Taking the nearer end's footprint blurred half the chord with the
  // silhouette's.
  void RootTexture(double p, double root, Fragment* f) const {
    f->uv = a_.uv + p * (b_.uv - a_.uv);
    const bool nearA = cubics_.root == 1;
    const Fragment &nearEnd = nearA ? a_ : b_, &farEnd = nearA ? b_ : a_;
    const double grow = 1.0 / root;
    const auto scaled = [grow](const Vec2& far, const Vec2& near) {
      const Vec2 d = grow * far;
      return d.squaredNorm() <= near.squaredNorm() ? d : near;  // false for NaN
    };
    f->duvdx = scaled(farEnd.duvdx, nearEnd.duvdx);
    f->duvdy = scaled(farEnd.duvdy, nearEnd.duvdy);
  }
  // What is interpolated for the eye distance: 1/w in perspective, w orthographic.
  double Depth(double w) const { return orthographic_ ? w : 1.0 / w; }
  // The eye distance at t, where the cubics' parameter is p = Param(t).
  double DepthAlong(double t, double p) const {
    const double d = cubic_ ? Horner(cubics_.depth, p) : (1.0 - t) * Depth(a_.w) + t * Depth(b_.w);
    return orthographic_ ? d : 1.0 / d;
  }
  double DepthAlong(double t) const { return DepthAlong(t, cubic_ ? Param(t) : t); }
};

// Receives the fragments of one sample row (implemented by the back end), and triangles:
// the slabs of a θ scan (Blinn 1978 §4), one-pixel-high pieces of surface between two
// scan lines whose samples the back end finds and interpolates itself. A triangle handed
// over while sample row y is scanned covers its samples on that row and below; none of it
// may lie above y.
class FragmentRow {
 public:
  virtual void Add(int column, const Fragment& f) = 0;
  // Whether Add would drop any fragment at eye distance w on `column` now (outside the
  // row, nearer than the hither plane, or behind every layer the sample keeps), so that a
  // front end may skip making it. False when unknown.
  virtual bool Hidden(int /*column*/, double /*w*/) const { return false; }
  // A chord's fragments on this row of `columns`: by default each made and added unless
  // Hidden at its depth; a back end may keep the chord and make only those it shades.
  virtual void AddChord(const Chord& c, const SampleColumns& columns) {
    c.ForEachColumn(columns, [&](int column) {
      const double x = columns.At(column);
      if (!Hidden(column, c.DepthAt(x))) Add(column, c.At(x));
    });
  }
  virtual void AddTriangle(const RasterVertex& a, const RasterVertex& b, const RasterVertex& c,
                           std::uint32_t surfaceId) = 0;

 protected:
  ~FragmentRow() = default;
};

// What the back end keeps of a sample whatever the fragment (a front end may drop the rest
// before handing them over): its `layers` nearest fragments at eye distance `hither` or
// more. layers 0: unknown (some fragments are dropped for their side, so depth alone does
// not tell), keep everything.
struct KeptDepths {
  double hither = 0.0;
  int layers = 0;
};

// Where sample row j of the rows BeginRows announced lies: y0 + j dy, always in this form,
// so that a row is the same double whichever thread or batch scans it (y + k dy from a
// batch's first row is a rounding off at a spacing that is not a binary fraction).
inline double RowY(double y0, double dy, int j) { return y0 + j * dy; }

// The batch rule of a source whose batches are only a size: batches of whole pixel rows
// (`perPixel` new sample rows each) end on the pixel row whose last sample row `row` is the
// last in its block of `rows` sample rows, so a batch holds at most rows + perPixel - 1
// sample rows (for FragmentSource::EndsBatch).
inline bool EndsRowBlock(int row, int perPixel, int rows) { return row / rows != (row + perPixel) / rows; }

// Produces, row by row from the top, every fragment of every surface at the samples of
// a row, in any order and including hidden ones: the back end keeps the nearest.
class FragmentSource {
 public:
  virtual ~FragmentSource() = default;
  // Called once before the first row: the rows will be y0 + k dy for k in [0, nRows), each
  // with `columns`, and the back end will keep `kept` of each sample. A source may scan
  // ahead on that knowledge; the default does nothing.
  virtual void BeginRows(const SampleColumns& /*columns*/, double /*y0*/, double /*dy*/, int /*nRows*/,
                         const KeptDepths& /*kept*/) {}
  // Sample rows come in increasing y. Returns false to stop the render (an error the
  // source reports itself).
  virtual bool ScanRow(double y, const SampleColumns& columns, FragmentRow& out) = 0;

  // A source whose rows, once prepared in order, are scanned on any threads at once
  // (xscan/row_scan.h). The back end then prepares a batch of sample rows, scans them on its
  // threads, finishes the batch and only then prepares the next; a batch ends on a row that
  // EndsBatch (or the frame's last). Rows are numbered from BeginRows' y0: row j at y0 + j dy.
  virtual bool ScansInBatches() const { return false; }
  virtual bool EndsBatch(int /*row*/) const { return true; }
  // Rows [first, first + count), in order, after the batch before is finished; called in
  // the back end's arena, so that it may run parts on its threads.
  virtual void PrepareRows(int /*first*/, int /*count*/) {}
  // The triangles of the k-th row prepared, into `out`: called for each row in order, on
  // the calling thread, before any row's ScanPreparedRow, which then hands over only the
  // row's fragments and chords.
  virtual void PreparedTriangles(int /*k*/, FragmentRow& /*out*/) {}
  // The k-th row prepared, into `out` (its own for each row); false stops the render.
  virtual bool ScanPreparedRow(int /*k*/, FragmentRow& /*out*/) { return false; }
  // After every row prepared is scanned.
  virtual void FinishRows() {}
};

}  // namespace patchscan::raster
