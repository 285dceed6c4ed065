#include "patch/subdiv.h"

#include <Eigen/Dense>
#include <opensubdiv/bfr/refinerSurfaceFactory.h>
#include <opensubdiv/bfr/surface.h>
#include <opensubdiv/bfr/tessellation.h>
#include <opensubdiv/far/error.h>
#include <opensubdiv/far/topologyDescriptor.h>
#include <opensubdiv/far/topologyRefinerFactory.h>

#include <algorithm>
#include <atomic>
#include <bitset>
#include <cmath>
#include <cstdint>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <unordered_map>

#include "patch/bicubic.h"

namespace patchscan {

namespace osd = OpenSubdiv;

namespace {

// Step of the differences that give an irregular face's second derivatives
// (SubdivFace::Evaluate): truncation ~step times the third derivative, ~1e-6 of the
// second's size on faces of size ~1; rounding ~1e-16 / step far below.
constexpr double kSecondDiffStep = 1e-6;

// A bicubic fitted to Bfr agrees with it to rounding (~1e-15 of the face's size, the
// collocation matrix's condition number being ~10); a surface of higher degree (Loop's
// quartic box splines, a Gregory patch) differs by a sizeable fraction of it. Position
// and derivatives up to the second must agree this closely, relative to the patch points'
// extent (a fitted Gregory patch: position and first derivatives, its fit agreeing to
// ~1e-15 as well where the cell is one, and by ~1e-6 of the extent where it is not).
constexpr double kBicubicFitRel = 1e-9;

using SubFaceMap = SubdivFace::SubFaceMap;

// Bfr's evaluation at (u, v) of a (sub-)face through its map to the face's coordinates.
void EvaluateMapped(const osd::Bfr::Surface<double>& surface, const double* pts, const SubFaceMap& map, double u,
                    double v, DerivOrder order, SurfaceDerivs* out) {
  const SubFaceMap::Point m = map.At(u, v);
  const double* uv = m.uv;
  const osd::Bfr::Surface<double>::PointDescriptor desc(3);
  double p[3], du[3], dv[3], duu[3], duv[3], dvv[3];
  if (Wants(order, DerivOrder::Second)) surface.Evaluate(uv, pts, desc, p, du, dv, duu, duv, dvv);
  else if (Wants(order, DerivOrder::First)) surface.Evaluate(uv, pts, desc, p, du, dv);
  else surface.Evaluate(uv, pts, desc, p);
  out->p = Vec3(p[0], p[1], p[2]);
  if (!Wants(order, DerivOrder::First)) return;
  const Vec3 Du(du[0], du[1], du[2]), Dv(dv[0], dv[1], dv[2]);
  // The chain rule through the map (u, v) -> (U, V); its only second derivative is
  // d2U/dudv = twist.
  const double a00 = m.a00, a10 = m.a10, a01 = m.a01, a11 = m.a11;
  out->dpdu = m.AlongU(Du, Dv);
  out->dpdv = m.AlongV(Du, Dv);
  if (!Wants(order, DerivOrder::Second)) return;
  const Vec3 Duu(duu[0], duu[1], duu[2]), Duv(duv[0], duv[1], duv[2]), Dvv(dvv[0], dvv[1], dvv[2]);
  out->d2pdu2 = a00 * a00 * Duu + 2.0 * a00 * a10 * Duv + a10 * a10 * Dvv;
  out->d2pduv = a00 * a01 * Duu + (a00 * a11 + a10 * a01) * Duv + a10 * a11 * Dvv + map.twist[0] * Du + map.twist[1] * Dv;
  out->d2pdv2 = a01 * a01 * Duu + 2.0 * a01 * a11 * Duv + a11 * a11 * Dvv;
}

// The map of sub-face `subFace` (-1: the face itself) of a face so parameterized.
SubFaceMap MapOf(const osd::Bfr::Parameterization& param, int subFace) {
  SubFaceMap map;
  if (subFace < 0) return map;
  double c00[2], c10[2], c01[2], c11[2];
  if (param.GetType() == osd::Bfr::Parameterization::TRI) {
    // The kite at corner k of the triangle (0,0), (1,0), (0,1): the corner, the midpoint of
    // the edge after it, the centre, the midpoint of the edge before it.
    const double corner[3][2] = {{0.0, 0.0}, {1.0, 0.0}, {0.0, 1.0}};
    const double* a = corner[subFace];
    const double* b = corner[(subFace + 1) % 3];
    const double* c = corner[(subFace + 2) % 3];
    for (int i = 0; i < 2; ++i) {
      c00[i] = a[i];
      c10[i] = 0.5 * (a[i] + b[i]);
      c11[i] = (a[i] + b[i] + c[i]) / 3.0;
      c01[i] = 0.5 * (a[i] + c[i]);
    }
  } else {
    // Bfr's quadrangulated sub-face: an affine map, read off at its corners.
    const double s00[2] = {0.0, 0.0}, s10[2] = {1.0, 0.0}, s01[2] = {0.0, 1.0};
    param.ConvertNormalizedSubFaceToCoord(subFace, s00, c00);
    param.ConvertNormalizedSubFaceToCoord(subFace, s10, c10);
    param.ConvertNormalizedSubFaceToCoord(subFace, s01, c01);
    for (int i = 0; i < 2; ++i) c11[i] = c10[i] + c01[i] - c00[i];
  }
  for (int i = 0; i < 2; ++i) {
    map.c00[i] = c00[i];
    map.eu[i] = c10[i] - c00[i];
    map.ev[i] = c01[i] - c00[i];
    map.twist[i] = c11[i] - c10[i] - c01[i] + c00[i];
  }
  return map;
}

// Whether a patch fitted to `at` matches it within `tol`, position and derivatives up to
// `order`, at the 9 points (s, t in {1/6, 1/2, 5/6}) between the fits' nodes.
template <class At, class Patch>
bool MatchesBetweenNodes(const At& at, const Patch& patch, DerivOrder order, double tol) {
  const auto off = [&](const Vec3& a, const Vec3& b) { return !((a - b).cwiseAbs().maxCoeff() <= tol); };
  for (const double s : {0.5, 1.0 / 6.0, 5.0 / 6.0})
    for (const double t : {0.5, 1.0 / 6.0, 5.0 / 6.0}) {
      SurfaceDerivs d, e;
      at(s, t, order, &d);
      patch.Evaluate(s, t, order, &e);
      if (off(d.p, e.p) || off(d.dpdu, e.dpdu) || off(d.dpdv, e.dpdv)) return false;
      if (Wants(order, DerivOrder::Second) &&
          (off(d.d2pdu2, e.d2pdu2) || off(d.d2pduv, e.d2pduv) || off(d.d2pdv2, e.d2pdv2)))
        return false;
    }
  return true;
}

// The bicubic polynomial `at` (position and derivatives, at (s, t) in [0,1]^2) is, if it is
// one: its values at the 4 x 4 nodes s, t in {0, 1/3, 2/3, 1} give the Bézier points (b =
// M^-1 P M^-T, M the Bernstein collocation matrix), kept only if they match `at`'s position
// and first and second derivatives within `tol` at 9 points between the nodes.
//
// `node(i, j)` is `at`'s position at (i/3, j/3), which the caller may have in hand.
template <class At, class Node>
std::optional<BicubicPatch> FitBicubic(const At& at, const Node& node, double tol) {
  static const Eigen::Matrix4d kInverse = [] {
    Eigen::Matrix4d m;
    for (int i = 0; i < 4; ++i) {
      const double t = i / 3.0, s = 1.0 - t;
      m.row(i) << s * s * s, 3.0 * t * s * s, 3.0 * t * t * s, t * t * t;
    }
    return Eigen::Matrix4d(m.inverse());
  }();
  Vec3 nodes[4][4];  // [j][i] at (s, t) = (i/3, j/3)
  for (int j = 0; j < 4; ++j)
    for (int i = 0; i < 4; ++i) nodes[j][i] = node(i, j);
  std::array<Vec3, 16> bezier;
  for (int l = 0; l < 4; ++l)      // along t
    for (int k = 0; k < 4; ++k) {  // along s
      Vec3 b = Vec3::Zero();
      for (int j = 0; j < 4; ++j)
        for (int i = 0; i < 4; ++i) b += kInverse(l, j) * kInverse(k, i) * nodes[j][i];
      bezier[static_cast<std::size_t>(4 * l + k)] = b;
    }
  BicubicPatch patch(bezier);
  if (!MatchesBetweenNodes(at, patch, DerivOrder::Second, tol)) return std::nullopt;
  return patch;
}

// Which quarter of [0, 1] u lies in (0 to 3; outside, the nearest; NaN: 3).
int QuarterOf(double u) { return u < 0.25 ? 0 : u < 0.5 ? 1 : u < 0.75 ? 2 : 3; }

// The cubic Bernstein polynomials at x and their first and second derivatives.
void Bernstein3(double x, double b[4], double d[4], double dd[4]) {
  const double y = 1.0 - x;
  b[0] = y * y * y, b[1] = 3.0 * x * y * y, b[2] = 3.0 * x * x * y, b[3] = x * x * x;
  d[0] = -3.0 * y * y, d[1] = 3.0 * y * (y - 2.0 * x), d[2] = 3.0 * x * (2.0 * y - x), d[3] = 3.0 * x * x;
  dd[0] = 6.0 * y, dd[1] = 6.0 * (3.0 * x - 2.0), dd[2] = 6.0 * (1.0 - 3.0 * x), dd[3] = 6.0 * x;
}

// A Gregory patch, as OpenSubdiv makes its irregular patches (Bfr's cells at an
// extraordinary corner, below its approximation level): a bicubic Bézier patch over
// (s, t) in [0,1]^2 whose four interior points are each a blend of two, F_a and F_b,
// weighted by the distances σ and τ from the nearest corner's two edges: (σ F_a + τ F_b) /
// (σ + τ), with (σ, τ) = (s, t), (1 - s, t), (s, 1 - t) or (1 - s, 1 - t). Its position is
// that rational function exactly. Its first derivatives are OpenSubdiv's, the Bézier
// patch's with the blend weights held where they are (what Bfr returns, and what Newton's
// iterations on it have always taken), and its second derivatives are those of that
// first-derivative field (the cross one the mean of its two), which the forward
// differences of Bfr's first derivatives approximated before: consistent with the first
// derivatives, as the silhouette trackers need.
class GregoryPatch {
 public:
  // Points 0-15: the Bézier grid, [4 j + i] for s index i and t index j (an interior one
  // is F_a); 16-19: F_b of the interior points (1,1), (2,1), (1,2), (2,2).
  static constexpr int kPoints = 20;
  explicit GregoryPatch(const std::array<Vec3, kPoints>& points) : p_(points) {}

  // The blend of interior point (i, j) (i, j in {1, 2}) at (s, t): F_a's weight G and its
  // derivatives (F_b's are 1 - G and the negated derivatives). At the corner itself, where
  // the blend is undefined, G = 0 (its Bernstein product vanishes there).
  struct Blend {
    double g, gs, gt;
  };
  static Blend BlendAt(int i, int j, double s, double t) {
    const double sigma = i == 1 ? s : 1.0 - s, tau = j == 1 ? t : 1.0 - t;
    const double ds = i == 1 ? 1.0 : -1.0, dt = j == 1 ? 1.0 : -1.0;
    const double sum = sigma + tau, inv = sum > 0.0 ? 1.0 / sum : 1.0;
    return {sigma * inv, ds * tau * inv * inv, -dt * sigma * inv * inv};
  }
  static int Second(int i, int j) { return 16 + (i - 1) + 2 * (j - 1); }

  // The weights of the 20 points in the position at (s, t).
  static void PositionWeights(double s, double t, double w[kPoints]) {
    double bs[4], ds[4], dds[4], bt[4], dt[4], ddt[4];
    Bernstein3(s, bs, ds, dds);
    Bernstein3(t, bt, dt, ddt);
    for (int j = 0; j < 4; ++j)
      for (int i = 0; i < 4; ++i) w[4 * j + i] = bs[i] * bt[j];
    for (int j = 1; j < 3; ++j)
      for (int i = 1; i < 3; ++i) {
        const double g = BlendAt(i, j, s, t).g, b = w[4 * j + i];
        w[4 * j + i] = b * g;
        w[Second(i, j)] = b * (1.0 - g);
      }
  }

  void Evaluate(double s, double t, DerivOrder order, SurfaceDerivs* out) const {
    const bool first = Wants(order, DerivOrder::First), second = Wants(order, DerivOrder::Second);
    double bs[4], ds[4], dds[4], bt[4], dt[4], ddt[4];
    Bernstein3(s, bs, ds, dds);
    Bernstein3(t, bt, dt, ddt);
    // The Bézier patch with the blends where they are at (s, t): its interior points.
    Blend blend[4];
    Vec3 inner[4];
    for (int m = 0; m < 4; ++m) {
      const int i = 1 + (m & 1), j = 1 + (m >> 1);
      blend[m] = BlendAt(i, j, s, t);
      const Vec3& a = p_[static_cast<std::size_t>(4 * j + i)];
      const Vec3& b = p_[static_cast<std::size_t>(Second(i, j))];
      inner[m] = b + blend[m].g * (a - b);
    }
    const auto point = [&](int i, int j) -> const Vec3& {
      return (i == 1 || i == 2) && (j == 1 || j == 2) ? inner[(i - 1) + 2 * (j - 1)] : p_[static_cast<std::size_t>(4 * j + i)];
    };
    // Collapse s row by row (with its derivatives), then t.
    Vec3 r[4], rs[4], rss[4];
    for (int j = 0; j < 4; ++j) {
      const Vec3 &q0 = point(0, j), &q1 = point(1, j), &q2 = point(2, j), &q3 = point(3, j);
      r[j] = bs[0] * q0 + bs[1] * q1 + bs[2] * q2 + bs[3] * q3;
      if (first) rs[j] = ds[0] * q0 + ds[1] * q1 + ds[2] * q2 + ds[3] * q3;
      if (second) rss[j] = dds[0] * q0 + dds[1] * q1 + dds[2] * q2 + dds[3] * q3;
    }
    out->p = bt[0] * r[0] + bt[1] * r[1] + bt[2] * r[2] + bt[3] * r[3];
    if (!first) return;
    out->dpdu = bt[0] * rs[0] + bt[1] * rs[1] + bt[2] * rs[2] + bt[3] * rs[3];
    out->dpdv = dt[0] * r[0] + dt[1] * r[1] + dt[2] * r[2] + dt[3] * r[3];
    if (!second) return;
    out->d2pdu2 = bt[0] * rss[0] + bt[1] * rss[1] + bt[2] * rss[2] + bt[3] * rss[3];
    out->d2pduv = dt[0] * rs[0] + dt[1] * rs[1] + dt[2] * rs[2] + dt[3] * rs[3];
    out->d2pdv2 = ddt[0] * r[0] + ddt[1] * r[1] + ddt[2] * r[2] + ddt[3] * r[3];
    // The blends' own change, in the derivatives of the first-derivative field.
    for (int m = 0; m < 4; ++m) {
      const int i = 1 + (m & 1), j = 1 + (m >> 1);
      const Vec3 diff = p_[static_cast<std::size_t>(4 * j + i)] - p_[static_cast<std::size_t>(Second(i, j))];
      const Blend& g = blend[m];
      out->d2pdu2 += (ds[i] * bt[j] * g.gs) * diff;
      out->d2pdv2 += (bs[i] * dt[j] * g.gt) * diff;
      out->d2pduv += (0.5 * (ds[i] * bt[j] * g.gt + bs[i] * dt[j] * g.gs)) * diff;
    }
  }

 private:
  std::array<Vec3, kPoints> p_;
};

// The Gregory patch `at` (position and derivatives, at (s, t) in [0,1]^2) is, if it is
// one: its positions on a 6 x 6 grid give the 20 points by least squares, kept only if
// they match `at`'s position and first derivatives within `tol` at 9 points between the
// nodes. The grid's nodes differ in s and t and lie symmetrically about no corner's
// diagonal: there a blend's two points weigh alike, and a grid with too many such nodes
// (5 x 5, the same in s and t) left one combination of the 20 points unseen.
template <class At>
std::optional<GregoryPatch> FitGregory(const At& at, double tol) {
  static constexpr std::array<double, 6> kS = {0.0, 0.13, 0.37, 0.58, 0.81, 1.0};
  static constexpr std::array<double, 6> kT = {0.0, 0.17, 0.41, 0.63, 0.86, 1.0};
  static constexpr int kNodes = 36;
  static const Eigen::Matrix<double, GregoryPatch::kPoints, kNodes> kSolve = [] {
    Eigen::Matrix<double, kNodes, GregoryPatch::kPoints> a;
    for (int j = 0; j < 6; ++j)
      for (int i = 0; i < 6; ++i) {
        double w[GregoryPatch::kPoints];
        GregoryPatch::PositionWeights(kS[static_cast<std::size_t>(i)], kT[static_cast<std::size_t>(j)], w);
        for (int k = 0; k < GregoryPatch::kPoints; ++k) a(6 * j + i, k) = w[k];
      }
    return Eigen::Matrix<double, GregoryPatch::kPoints, kNodes>(a.completeOrthogonalDecomposition().pseudoInverse());
  }();
  Eigen::Matrix<double, kNodes, 3> node;
  SurfaceDerivs d;
  for (int j = 0; j < 6; ++j)
    for (int i = 0; i < 6; ++i) {
      at(kS[static_cast<std::size_t>(i)], kT[static_cast<std::size_t>(j)], DerivOrder::Position, &d);
      node.row(6 * j + i) = d.p.transpose();
    }
  const Eigen::Matrix<double, GregoryPatch::kPoints, 3> fitted = kSolve * node;
  std::array<Vec3, GregoryPatch::kPoints> points;
  for (int k = 0; k < GregoryPatch::kPoints; ++k) points[static_cast<std::size_t>(k)] = fitted.row(k).transpose();
  const GregoryPatch patch(points);
  if (!MatchesBetweenNodes(at, patch, DerivOrder::First, tol)) return std::nullopt;
  return patch;
}

}  // namespace

// Where a (sub-)face's limit surface is a bicubic polynomial, as bicubic patches: the
// whole face for a regular Catmull-Clark quadrilateral (at a boundary too: Bfr extends the
// missing points linearly, which keeps it bicubic) or a bilinear one; else the cells of
// Bfr's patch tree away from the extraordinary corners, which are regular B-spline patches;
// and the cells at those corners, Gregory patches at Bfr's approximation level 2 (the cell
// of 1/4 x 1/4 at such a corner of a quadrilateral, the quadrant at the centre of a
// non-quadrilateral's sub-face), as Gregory patches. BicubicPatch and GregoryPatch
// evaluate them in a fraction of Bfr's time (its patch tree, basis weights and point
// combination; at a Gregory cell three evaluations of it where second derivatives are
// asked, SubdivFace::Evaluate's differences). Found from Bfr itself (FitBicubic,
// FitGregory), independently of how it orders and builds its points: the face whole, else
// each quadrant, else each quarter of a quadrant; what fits neither is left to Bfr.
struct BicubicPieces {
  // The 4 x 4 grid of quarters: at most this many pieces of either kind.
  static constexpr int kCells = 16;
  std::vector<BicubicPatch> patches;
  // Per cell of the 4 x 4 grid of quarters, [4 j + i] for u in quarter i and v in quarter j:
  // the patch covering it (-1: none, Bfr) and that patch's level (0: the whole face, over
  // [0,1]^2; 1: a quadrant; 2: the cell).
  std::array<std::int8_t, 16> patchOf{}, levelOf{};
  // Where no bicubic covers a cell, the Gregory patch that does (-1: none, Bfr), with its
  // level as above: Bfr's irregular cells, at an extraordinary corner (a quadrant of a
  // non-quadrilateral face's sub-face, whose centre corner is one, or a cell of a
  // quadrilateral's).
  std::vector<GregoryPatch> gregory;
  std::array<std::int8_t, 16> gregoryOf{};

  // Where the (sub-)face's corners are known to be extraordinary (Corners), the fits that
  // cannot succeed there are not tried, and the Gregory fit goes first.
  struct Corners {
    // Bit 2 qj + qi: quadrant (qi, qj)'s corner of the (sub-)face is an extraordinary point
    // whose Gregory patch is the quadrant (a triangle's centre) or the cell at that corner
    // (a smooth interior vertex of valence other than 4 at a quadrilateral's corner).
    unsigned gregoryQuadrants = 0, gregoryCells = 0;
  };

  BicubicPieces(const osd::Bfr::Surface<double>& surface, const std::vector<double>& pts, const SubFaceMap& map,
                double tol, Corners corners) {
    patchOf.fill(-1);
    gregoryOf.fill(-1);
    if (surface.IsRegular() && Fit(surface, pts, map, tol, 0, 0, 0)) return;
    for (int qj = 0; qj < 2; ++qj)
      for (int qi = 0; qi < 2; ++qi) {
        // A quadrant is one bicubic, or one Gregory patch (a non-quadrilateral face's
        // sub-face at its centre, an extraordinary corner: Bfr's cells there are the
        // quadrants), or cells of either. At a known extraordinary corner it is no bicubic
        // (Bfr's patch there is irregular), and one Gregory patch only at a triangle's centre.
        const unsigned bit = 1u << (2 * qj + qi);
        if (corners.gregoryQuadrants & bit) {
          if (FitIrregular(surface, pts, map, tol, 1, qi, qj)) continue;
        } else if (!(corners.gregoryCells & bit)) {
          if (Fit(surface, pts, map, tol, 1, qi, qj) || FitIrregular(surface, pts, map, tol, 1, qi, qj)) continue;
        }
        // The cells' nodes, shared along their common edges: the 7 x 7 grid of sixths of
        // the quadrant (a cell's node (i/3, j/3) computed as Bfr's coordinate (c + i/3) / 4,
        // the same double from either cell of an edge since c + 3/3 is exact).
        QuadrantNodes nodes;
        for (int j = 2 * qj; j < 2 * qj + 2; ++j)
          for (int i = 2 * qi; i < 2 * qi + 2; ++i) {
            const bool atCorner = (corners.gregoryCells & bit) && i == 3 * qi && j == 3 * qj;
            if (atCorner && FitIrregular(surface, pts, map, tol, 2, i, j)) continue;
            if (!Fit(surface, pts, map, tol, 2, i, j, &nodes) && !atCorner) FitIrregular(surface, pts, map, tol, 2, i, j);
          }
      }
  }
  int PatchAt(double u, double v) const { return patchOf[static_cast<std::size_t>(4 * QuarterOf(v) + QuarterOf(u))]; }
  int GregoryAt(double u, double v) const { return gregoryOf[static_cast<std::size_t>(4 * QuarterOf(v) + QuarterOf(u))]; }
  // The polynomial or Gregory patch at (u, v), if one covers that cell.
  bool Evaluate(double u, double v, DerivOrder order, SurfaceDerivs* out) const {
    const int i = QuarterOf(u), j = QuarterOf(v);
    const auto cell = static_cast<std::size_t>(4 * j + i);
    const int level = levelOf[cell];
    if (const int k = patchOf[cell]; k >= 0) {
      if (level == 0) {
        patches[static_cast<std::size_t>(k)].Evaluate(u, v, order, out);
        return true;
      }
      return Scaled(patches[static_cast<std::size_t>(k)], level, i, j, u, v, order, out);
    }
    if (const int k = gregoryOf[cell]; k >= 0) return Scaled(gregory[static_cast<std::size_t>(k)], level, i, j, u, v, order, out);
    return false;
  }

 private:
  // A patch over a cell of `level` holding quarter (i, j), at (u, v).
  template <class Patch>
  static bool Scaled(const Patch& patch, int level, int i, int j, double u, double v, DerivOrder order, SurfaceDerivs* out) {
    // The patch's own (s, t) = n (u - u0, v - v0): derivatives along u are n times those along s.
    const int shift = 2 - level;
    const double n = static_cast<double>(1 << level);
    patch.Evaluate(n * u - (i >> shift), n * v - (j >> shift), order, out);
    if (!Wants(order, DerivOrder::First)) return true;
    out->dpdu *= n;
    out->dpdv *= n;
    if (!Wants(order, DerivOrder::Second)) return true;
    out->d2pdu2 *= n * n;
    out->d2pduv *= n * n;
    out->d2pdv2 *= n * n;
    return true;
  }
  // Bfr on cell (ci, cj) of `level`, in the cell's own (s, t).
  static auto CellOf(const osd::Bfr::Surface<double>& surface, const std::vector<double>& pts, const SubFaceMap& map,
                     int level, int ci, int cj) {
    const double n = static_cast<double>(1 << level);
    return [&surface, &pts, &map, n, ci, cj](double s, double t, DerivOrder order, SurfaceDerivs* d) {
      EvaluateMapped(surface, pts.data(), map, (ci + s) / n, (cj + t) / n, order, d);
      if (!Wants(order, DerivOrder::First)) return;
      d->dpdu /= n;
      d->dpdv /= n;
      if (!Wants(order, DerivOrder::Second)) return;
      d->d2pdu2 /= n * n;
      d->d2pduv /= n * n;
      d->d2pdv2 /= n * n;
    };
  }
  // Marks the quarters of cell (ci, cj) of `level` as covered by patch k of `of`.
  void Cover(std::array<std::int8_t, 16>& of, int k, int level, int ci, int cj) {
    const int width = 4 >> level;
    for (int j = cj * width; j < (cj + 1) * width; ++j)
      for (int i = ci * width; i < (ci + 1) * width; ++i) {
        of[static_cast<std::size_t>(4 * j + i)] = static_cast<std::int8_t>(k);
        levelOf[static_cast<std::size_t>(4 * j + i)] = static_cast<std::int8_t>(level);
      }
  }
  // The positions at a quadrant's cells' nodes, each evaluated once.
  struct QuadrantNodes {
    std::array<Vec3, 49> p;  // [7 j + i] at sixth (i, j) of the quadrant
    std::bitset<49> has;
  };
  // Fits the cell (ci, cj) of `level` as a bicubic (Fit) or a Gregory patch
  // (FitIrregular); covers its quarters if it is one. A cell of level 2 takes its nodes
  // from, and puts them into, its quadrant's `nodes` where given.
  bool Fit(const osd::Bfr::Surface<double>& surface, const std::vector<double>& pts, const SubFaceMap& map,
           double tol, int level, int ci, int cj, QuadrantNodes* nodes = nullptr) {
    const auto at = CellOf(surface, pts, map, level, ci, cj);
    const auto node = [&at, nodes, ci, cj](int i, int j) {
      const auto evaluate = [&at, i, j] {
        SurfaceDerivs d;
        at(i / 3.0, j / 3.0, DerivOrder::Position, &d);
        return d.p;
      };
      if (!nodes) return evaluate();
      const auto k = static_cast<std::size_t>(7 * (3 * (cj & 1) + j) + 3 * (ci & 1) + i);
      if (!nodes->has[k]) {
        nodes->p[k] = evaluate();
        nodes->has[k] = true;
      }
      return nodes->p[k];
    };
    return Keep(FitBicubic(at, node, tol), patches, patchOf, level, ci, cj);
  }
  bool FitIrregular(const osd::Bfr::Surface<double>& surface, const std::vector<double>& pts, const SubFaceMap& map,
                    double tol, int level, int ci, int cj) {
    return Keep(FitGregory(CellOf(surface, pts, map, level, ci, cj), tol), gregory, gregoryOf, level, ci, cj);
  }
  template <class Patch>
  bool Keep(const std::optional<Patch>& patch, std::vector<Patch>& into, std::array<std::int8_t, 16>& of, int level,
            int ci, int cj) {
    if (!patch) return false;
    into.push_back(*patch);
    Cover(of, static_cast<int>(into.size()) - 1, level, ci, cj);
    return true;
  }
};

// Whether base vertex v is an extraordinary point of the Catmull-Clark limit surface:
// interior, manifold, smooth (no sharpness at it or along its edges), of valence other than
// 4. Bfr's patches at it are irregular.
bool SmoothExtraordinary(const osd::Far::TopologyLevel& level, int v) {
  if (level.IsVertexBoundary(v) || level.IsVertexNonManifold(v) || level.GetVertexSharpness(v) > 0.0f ||
      level.GetVertexFaces(v).size() == 4)
    return false;
  for (const int e : level.GetVertexEdges(v))
    if (level.GetEdgeSharpness(e) > 0.0f) return false;
  return true;
}

// A prepared base face: its Bfr surfaces (points and, where the cage has them, texture
// coordinates) and their patch points.
struct FaceData {
  osd::Bfr::Surface<double> surface;
  std::vector<double> patchPoints;  // x y z per point: the control points, then any Bfr adds
  osd::Bfr::Surface<double> stSurface;
  std::vector<double> stPatchPoints;  // s t per point
  // Per sub-face (one for a quadrilateral), where it is a bicubic polynomial or a Gregory
  // patch (Catmull-Clark and bilinear faces; none for Loop's, whose regular pieces are
  // quartic): fitted when a scan first holds the sub-face (Cage::Hold), under the cage's
  // mutex, and read lock-free. Null until then, so every evaluation of a sub-face is Bfr's
  // before its scan's hold and the pieces' after it, whatever other threads do with the
  // face's other sub-faces.
  mutable std::vector<std::atomic<const BicubicPieces*>> pieces;
  double fitTol = 0.0;  // kBicubicFitRel of the patch points' extent
  FaceData() = default;
  FaceData(const FaceData&) = delete;
  FaceData& operator=(const FaceData&) = delete;
  ~FaceData() {
    for (auto& p : pieces) delete p.load(std::memory_order_relaxed);
  }
};

class SubdivFace::Cage {
 public:
  Cage(const SubdivMesh& mesh, std::unique_ptr<osd::Far::TopologyRefiner> refiner)
      : mesh_(mesh), refiner_(std::move(refiner)), factory_(*refiner_), slots_(static_cast<std::size_t>(mesh.faceSizes.size())) {
    points_.reserve(mesh.points.size() * 3);
    for (const Vec3& p : mesh.points) points_.insert(points_.end(), {p.x(), p.y(), p.z()});
    st_.reserve(mesh.st.size() * 2);
    for (const Vec2& t : mesh.st) st_.insert(st_.end(), {t.x(), t.y()});
  }
  ~Cage() {
    for (Slot& s : slots_) delete s.data.load(std::memory_order_relaxed);
  }
  Cage(const Cage&) = delete;
  Cage& operator=(const Cage&) = delete;

  const SubdivMesh& Mesh() const { return mesh_; }
  const osd::Far::TopologyRefiner& Refiner() const { return *refiner_; }
  const osd::Bfr::RefinerSurfaceFactory<>& Factory() const { return factory_; }

  // The prepared face, prepared now if it is not. Lock-free once prepared.
  const FaceData& Data(int face) {
    Slot& slot = slots_[static_cast<std::size_t>(face)];
    if (const FaceData* d = slot.data.load(std::memory_order_acquire)) return *d;
    const std::lock_guard lock(mutex_);
    if (const FaceData* d = slot.data.load(std::memory_order_relaxed)) return *d;
    auto* d = new FaceData;
    Prepare(face, d);
    slot.data.store(d, std::memory_order_release);
    nPeak_ = std::max(nPeak_, ++nPrepared_);
    ++nPreparations_;
    return *d;
  }
  // Initialises `out` for the face's points and computes its patch points (the face has a
  // limit surface: checked when the cage was made).
  void Prepare(int face, FaceData* out) const {
    const osd::Bfr::Surface<double>::PointDescriptor xyz(3), st(2);
    factory_.InitVertexSurface(face, &out->surface);
    out->patchPoints.resize(static_cast<std::size_t>(out->surface.GetNumPatchPoints()) * 3);
    out->surface.PreparePatchPoints(points_.data(), xyz, out->patchPoints.data(), xyz);
    const osd::Bfr::Parameterization param = out->surface.GetParameterization();
    if (param.GetType() != osd::Bfr::Parameterization::TRI) {
      Eigen::Vector3d lo = Eigen::Vector3d::Constant(INFINITY), hi = -lo;
      for (std::size_t k = 0; k + 2 < out->patchPoints.size(); k += 3) {
        const Eigen::Vector3d q(out->patchPoints[k], out->patchPoints[k + 1], out->patchPoints[k + 2]);
        lo = lo.cwiseMin(q);
        hi = hi.cwiseMax(q);
      }
      out->fitTol = kBicubicFitRel * (hi - lo).maxCoeff();
      const bool quad = param.GetType() == osd::Bfr::Parameterization::QUAD;
      out->pieces = std::vector<std::atomic<const BicubicPieces*>>(quad ? 1 : static_cast<std::size_t>(param.GetFaceSize()));
    }
    if (mesh_.st.empty()) return;
    switch (mesh_.stClass) {
      case StClass::Vertex: factory_.InitVertexSurface(face, &out->stSurface); break;
      case StClass::Varying: factory_.InitVaryingSurface(face, &out->stSurface); break;
      case StClass::FaceVarying: factory_.InitFaceVaryingSurface(face, &out->stSurface, 0); break;
    }
    out->stPatchPoints.resize(static_cast<std::size_t>(out->stSurface.GetNumPatchPoints()) * 2);
    out->stSurface.PreparePatchPoints(st_.data(), st, out->stPatchPoints.data(), st);
  }
  // A hold that fits (a scan's) also fits sub-face `subFace`'s bicubic pieces if they are
  // not yet: the hold is taken first, so the face stays prepared while they are fitted.
  void Hold(int face, int subFace, bool fit) {
    {
      const std::lock_guard lock(mutex_);
      ++slots_[static_cast<std::size_t>(face)].holds;
    }
    if (!fit) return;
    try {
      const FaceData& data = Data(face);
      const std::size_t k = static_cast<std::size_t>(std::max(subFace, 0));
      if (k >= data.pieces.size()) return;  // a Loop face
      const std::lock_guard lock(mutex_);
      if (data.pieces[k].load(std::memory_order_relaxed)) return;
      const osd::Bfr::Parameterization param = data.surface.GetParameterization();
      auto pieces = std::make_unique<const BicubicPieces>(data.surface, data.patchPoints, MapOf(param, subFace),
                                                          data.fitTol, CornersOf(face, subFace, param));
      data.pieces[k].store(pieces.release(), std::memory_order_release);
    } catch (...) {
      Release(face);  // the holder's constructor fails: no release will come for this hold
      throw;
    }
  }
  // The extraordinary corners of a Catmull-Clark quadrilateral or triangle's sub-face,
  // as BicubicPieces takes them (none known for other faces and schemes).
  BicubicPieces::Corners CornersOf(int face, int subFace, const osd::Bfr::Parameterization& param) const {
    BicubicPieces::Corners c;
    if (mesh_.scheme != SubdivScheme::CatmullClark) return c;
    const osd::Far::TopologyLevel& level = refiner_->GetLevel(0);
    const auto fv = level.GetFaceVertices(face);
    if (param.GetType() == osd::Bfr::Parameterization::QUAD && subFace < 0) {
      // Bfr's corners (0,0), (1,0), (1,1), (0,1) are the face's vertices in order.
      constexpr unsigned kQuadrant[4] = {1u << 0, 1u << 1, 1u << 3, 1u << 2};
      for (int k = 0; k < 4; ++k)
        if (SmoothExtraordinary(level, fv[k])) c.gregoryCells |= kQuadrant[k];
    } else if (param.GetType() == osd::Bfr::Parameterization::TRI && subFace >= 0) {
      // MapOf's kite: (0,0) the triangle's corner `subFace`, (1,1) its centre (valence 3).
      c.gregoryQuadrants = 1u << 3;
      if (SmoothExtraordinary(level, fv[subFace])) c.gregoryCells = 1u << 0;
    }
    return c;
  }
  void Release(int face) {
    const std::lock_guard lock(mutex_);
    Slot& slot = slots_[static_cast<std::size_t>(face)];
    if (slot.holds == 0 || --slot.holds > 0) return;
    if (const FaceData* d = slot.data.exchange(nullptr, std::memory_order_acq_rel)) {
      delete d;
      --nPrepared_;
    }
  }
  long PreparedNow() {
    const std::lock_guard lock(mutex_);
    return nPrepared_;
  }
  long Preparations() {
    const std::lock_guard lock(mutex_);
    return nPreparations_;
  }
  long PeakPrepared() {
    const std::lock_guard lock(mutex_);
    return nPeak_;
  }

 private:
  struct Slot {
    std::atomic<const FaceData*> data{nullptr};
    int holds = 0;  // guarded by mutex_
  };
  const SubdivMesh mesh_;
  std::unique_ptr<osd::Far::TopologyRefiner> refiner_;
  // Bfr's factory and its cache of irregular patch topologies are used under mutex_ only.
  const osd::Bfr::RefinerSurfaceFactory<> factory_;
  std::vector<double> points_, st_;
  std::mutex mutex_;
  std::vector<Slot> slots_;
  long nPrepared_ = 0, nPreparations_ = 0, nPeak_ = 0;
};

SubdivFace::SubdivFace(std::shared_ptr<Cage> cage, int face, int subFace, std::shared_ptr<const std::vector<Vec3>> hull)
    : cage_(std::move(cage)), face_(face), subFace_(subFace), hull_(std::move(hull)) {
  if (subFace_ >= 0) map_ = MapOf(cage_->Factory().GetFaceParameterization(face_), subFace_);
}

const BicubicPieces* SubdivFace::Pieces(const FaceData& face) const {
  const auto k = static_cast<std::size_t>(std::max(subFace_, 0));
  return k < face.pieces.size() ? face.pieces[k].load(std::memory_order_acquire) : nullptr;
}

void SubdivFace::Evaluate(double u, double v, DerivOrder order, SurfaceDerivs* out) const {
  const FaceData& face = cage_->Data(face_);
  if (const BicubicPieces* pc = Pieces(face); pc && pc->Evaluate(u, v, order, out)) return;
  const double* pts = face.patchPoints.data();
  if (Wants(order, DerivOrder::Second) && !face.surface.IsRegular()) {
    // Bfr's irregular patches (Gregory patches at an extraordinary corner) give second
    // derivatives up to 21 % (Catmull-Clark) and 53 % (Loop) off those of their first
    // derivatives, and Newton on the silhouette system, whose Jacobian takes J's gradient
    // from them, can run away (a Loop kite seen edge-on lost its top row). Taken instead as
    // forward differences of the first derivatives kSecondDiffStep apart (backward at the
    // domain's far edges): consistent with them to O(step), two evaluations more.
    EvaluateMapped(face.surface, pts, map_, u, v, DerivOrder::First, out);
    SurfaceDerivs a, b;
    const double hu = u + kSecondDiffStep <= 1.0 ? kSecondDiffStep : -kSecondDiffStep;
    const double hv = v + kSecondDiffStep <= 1.0 ? kSecondDiffStep : -kSecondDiffStep;
    EvaluateMapped(face.surface, pts, map_, u + hu, v, DerivOrder::First, &a);
    EvaluateMapped(face.surface, pts, map_, u, v + hv, DerivOrder::First, &b);
    out->d2pdu2 = (a.dpdu - out->dpdu) / hu;
    out->d2pdv2 = (b.dpdv - out->dpdv) / hv;
    out->d2pduv = 0.5 * ((a.dpdv - out->dpdv) / hu + (b.dpdu - out->dpdu) / hv);
    return;
  }
  EvaluateMapped(face.surface, pts, map_, u, v, order, out);
}

void SubdivFace::EvaluateByBfr(double u, double v, DerivOrder order, SurfaceDerivs* out) const {
  const FaceData& face = cage_->Data(face_);
  EvaluateMapped(face.surface, face.patchPoints.data(), map_, u, v, order, out);
}

bool SubdivFace::BicubicAt(double u, double v) const {
  const BicubicPieces* pc = Pieces(cage_->Data(face_));
  return pc && pc->PatchAt(u, v) >= 0;
}

bool SubdivFace::GregoryAt(double u, double v) const {
  const BicubicPieces* pc = Pieces(cage_->Data(face_));
  return pc && pc->GregoryAt(u, v) >= 0;
}

int SubdivFace::PieceAt(double u, double v) const {
  const BicubicPieces* pc = Pieces(cage_->Data(face_));
  if (!pc) return -1;
  if (const int k = pc->PatchAt(u, v); k >= 0) return k;
  const int g = pc->GregoryAt(u, v);
  return g >= 0 ? BicubicPieces::kCells + g : -1;  // after every bicubic's index
}

int SubdivFace::BicubicCover(std::array<const BicubicPatch*, 16>* out) const {
  const BicubicPieces* pc = Pieces(cage_->Data(face_));
  if (!pc || std::any_of(pc->patchOf.begin(), pc->patchOf.end(), [](std::int8_t k) { return k < 0; })) return -1;
  for (std::size_t k = 0; k < pc->patches.size(); ++k) (*out)[k] = &pc->patches[k];
  return static_cast<int>(pc->patches.size());
}

std::optional<TexCoords> SubdivFace::TextureCoords(double u, double v) const {
  if (cage_->Mesh().st.empty()) return std::nullopt;
  const FaceData& face = cage_->Data(face_);
  const SubFaceMap::Point m = map_.At(u, v);
  const osd::Bfr::Surface<double>::PointDescriptor desc(2);
  double st[2], du[2], dv[2];
  face.stSurface.Evaluate(m.uv, face.stPatchPoints.data(), desc, st, du, dv);
  const Vec2 Du(du[0], du[1]), Dv(dv[0], dv[1]);
  return TexCoords{Vec2(st[0], st[1]), m.AlongU(Du, Dv), m.AlongV(Du, Dv)};
}

bool SubdivFace::Regular() const { return cage_->Data(face_).surface.IsRegular(); }

const SubdivMesh& SubdivFace::Mesh() const { return cage_->Mesh(); }

std::string SubdivFace::Describe() const {
  std::string s = "subdivision face " + std::to_string(face_);
  if (subFace_ >= 0)
    s += " (sub-face " + std::to_string(subFace_) + " of " + std::to_string(cage_->Mesh().faceSizes[static_cast<std::size_t>(face_)]) + ")";
  return s;
}

void SubdivFace::Hold(bool fit) const { cage_->Hold(face_, subFace_, fit); }
void SubdivFace::Release() const { cage_->Release(face_); }
long SubdivFace::PreparedNow() const { return cage_->PreparedNow(); }
long SubdivFace::Preparations() const { return cage_->Preparations(); }
long SubdivFace::PeakPrepared() const { return cage_->PeakPrepared(); }

namespace {

// The cage's edges, each once, with the faces that use it. Refuses what OpenSubdiv's Bfr
// cannot be trusted with (a fuzzed cage crashed it inside IrregularPatchBuilder): an edge of
// three or more faces, two faces running an edge the same way (their orientations disagree),
// and a vertex where separate fans of faces meet (a bowtie).
void CheckManifold(const SubdivMesh& mesh, std::unordered_map<std::uint64_t, int>* edgeUses) {
  struct Use {
    int count = 0, face = -1;
    bool forward = false;  // the first face runs it from the smaller vertex
  };
  std::unordered_map<std::uint64_t, Use> edges;
  auto key = [](int a, int b) {
    return (static_cast<std::uint64_t>(std::min(a, b)) << 32) | static_cast<std::uint32_t>(std::max(a, b));
  };
  // The corners at each vertex: (face, the vertex before, the vertex after).
  struct Corner {
    int face, prev, next;
  };
  std::vector<std::vector<Corner>> corners(mesh.points.size());
  std::size_t start = 0;
  for (std::size_t f = 0; f < mesh.faceSizes.size(); ++f) {
    const int n = mesh.faceSizes[f];
    for (int k = 0; k < n; ++k) {
      const int a = mesh.faceVertices[start + static_cast<std::size_t>(k)];
      const int b = mesh.faceVertices[start + static_cast<std::size_t>((k + 1) % n)];
      const int before = mesh.faceVertices[start + static_cast<std::size_t>((k + n - 1) % n)];
      corners[static_cast<std::size_t>(a)].push_back({static_cast<int>(f), before, b});
      Use& u = edges[key(a, b)];
      const std::string edge = "the edge between vertices " + std::to_string(a) + " and " + std::to_string(b);
      if (u.count >= 2)
        throw std::invalid_argument(edge + " is used by 3 or more faces (a non-manifold edge)");
      if (u.count == 1 && u.forward == (a < b))
        throw std::invalid_argument("faces " + std::to_string(u.face) + " and " + std::to_string(f) + " both run " + edge +
                                    " the same way (their orientations disagree)");
      if (u.count == 0) {
        u.face = static_cast<int>(f);
        u.forward = a < b;
      }
      ++u.count;
    }
    start += static_cast<std::size_t>(n);
  }
  // A vertex's corners form one fan: linked where one face's edge out of it is the next
  // face's edge into it.
  std::vector<int> parent;
  for (std::size_t v = 0; v < corners.size(); ++v) {
    const auto& c = corners[v];
    parent.resize(c.size());
    for (std::size_t i = 0; i < c.size(); ++i) parent[i] = static_cast<int>(i);
    auto root = [&](int i) {
      while (parent[static_cast<std::size_t>(i)] != i) i = parent[static_cast<std::size_t>(i)];
      return i;
    };
    std::size_t fans = c.size();
    for (std::size_t i = 0; i < c.size(); ++i)
      for (std::size_t j = 0; j < c.size(); ++j)
        if (i != j && c[i].next == c[j].prev) {
          const int ri = root(static_cast<int>(i)), rj = root(static_cast<int>(j));
          if (ri != rj) {
            parent[static_cast<std::size_t>(ri)] = rj;
            --fans;
          }
        }
    if (fans > 1)
      throw std::invalid_argument("vertex " + std::to_string(v) + " joins " + std::to_string(fans) +
                                  " separate fans of faces (a non-manifold vertex)");
  }
  edgeUses->clear();
  for (const auto& [k, u] : edges) (*edgeUses)[k] = u.count;
}

// OpenSubdiv reports through printf by default; the cage is checked before it is given
// to OpenSubdiv, so what it would still say is not for the user's terminal.
void QuietOpenSubdiv() {
  static const bool once = [] {
    osd::Far::SetErrorCallback([](osd::Far::ErrorType, const char*) {});
    osd::Far::SetWarningCallback([](const char*) {});
    return true;
  }();
  (void)once;
}

}  // namespace

// Checks `mesh` and builds its OpenSubdiv topology, with RenderMan's boundary rule and the
// texture coordinates' channel. Throws std::invalid_argument (PrepareSubdivFaces).
static std::unique_ptr<osd::Far::TopologyRefiner> BuildRefiner(const SubdivMesh& mesh) {
  QuietOpenSubdiv();
  using osd::Far::Index;
  const int nPoints = static_cast<int>(mesh.points.size());
  // Step 1: what OpenSubdiv cannot be trusted to refuse cleanly, refused here.
  std::size_t total = 0;
  for (std::size_t f = 0; f < mesh.faceSizes.size(); ++f) {
    if (mesh.faceSizes[f] < 3)
      throw std::invalid_argument("face " + std::to_string(f) + " has " + std::to_string(mesh.faceSizes[f]) +
                                  " vertices (at least 3)");
    total += static_cast<std::size_t>(mesh.faceSizes[f]);
  }
  if (total != mesh.faceVertices.size())
    throw std::invalid_argument("the faces' sizes add up to " + std::to_string(total) + " vertices, but " +
                                std::to_string(mesh.faceVertices.size()) + " vertex indices are given");
  auto checkVertex = [&](int v, const std::string& what) {
    if (v < 0 || v >= nPoints)
      throw std::invalid_argument(what + " index " + std::to_string(v) + " is out of range (" +
                                  std::to_string(nPoints) + " points)");
  };
  for (int v : mesh.faceVertices) checkVertex(v, "vertex");
  std::size_t start = 0;
  for (std::size_t f = 0; f < mesh.faceSizes.size(); ++f) {
    const int n = mesh.faceSizes[f];
    for (int i = 0; i < n; ++i)
      for (int j = i + 1; j < n; ++j)
        if (mesh.faceVertices[start + static_cast<std::size_t>(i)] == mesh.faceVertices[start + static_cast<std::size_t>(j)])
          throw std::invalid_argument("face " + std::to_string(f) + " uses vertex " +
                                      std::to_string(mesh.faceVertices[start + static_cast<std::size_t>(i)]) + " twice");
    if (mesh.scheme == SubdivScheme::Loop && n != 3)
      throw std::invalid_argument("face " + std::to_string(f) + " has " + std::to_string(n) +
                                  " vertices: a Loop cage is of triangles");
    start += static_cast<std::size_t>(n);
  }
  std::vector<Index> creasePairs;
  std::vector<float> creaseWeights;
  for (const SubdivMesh::Crease& c : mesh.creases)
    for (std::size_t k = 0; k + 1 < c.chain.size(); ++k) {
      checkVertex(c.chain[k], "crease vertex");
      checkVertex(c.chain[k + 1], "crease vertex");
      creasePairs.push_back(c.chain[k]);
      creasePairs.push_back(c.chain[k + 1]);
      creaseWeights.push_back(static_cast<float>(c.sharpness));
    }
  std::vector<Index> cornerVertices;
  std::vector<float> cornerWeights;
  for (const auto& [v, sharpness] : mesh.corners) {
    checkVertex(v, "corner vertex");
    cornerVertices.push_back(v);
    cornerWeights.push_back(static_cast<float>(sharpness));
  }
  for (int h : mesh.holes)
    if (h < 0 || h >= static_cast<int>(mesh.faceSizes.size()))
      throw std::invalid_argument("hole face " + std::to_string(h) + " is out of range (" +
                                  std::to_string(mesh.faceSizes.size()) + " faces)");
  std::unordered_map<std::uint64_t, int> edgeUses;
  CheckManifold(mesh, &edgeUses);
  for (std::size_t k = 0; k + 1 < creasePairs.size(); k += 2) {
    const int a = creasePairs[k], b = creasePairs[k + 1];
    const std::uint64_t key = (static_cast<std::uint64_t>(std::min(a, b)) << 32) | static_cast<std::uint32_t>(std::max(a, b));
    if (a == b || !edgeUses.contains(key))
      throw std::invalid_argument("crease: vertices " + std::to_string(a) + " and " + std::to_string(b) +
                                  " are not the ends of an edge of the cage");
  }
  // An interior vertex of valence 2 folds the control hull over on itself. OpenSubdiv 3.5's
  // Bfr builds the irregular patches around one from uninitialised indices when the cage also
  // has creases (valgrind and a fuzzed crash inside IrregularPatchBuilder agree; without
  // creases it is clean), so a cage is refused the combination rather than evaluated wrongly.
  if (!creasePairs.empty()) {
    std::vector<int> valence(mesh.points.size(), 0);
    std::vector<bool> boundary(mesh.points.size(), false);
    for (const auto& [k, uses] : edgeUses)
      for (const int v : {static_cast<int>(k >> 32), static_cast<int>(k & 0xffffffffu)}) {
        ++valence[static_cast<std::size_t>(v)];
        if (uses == 1) boundary[static_cast<std::size_t>(v)] = true;
      }
    for (std::size_t v = 0; v < valence.size(); ++v)
      if (valence[v] == 2 && !boundary[v])
        throw std::invalid_argument("vertex " + std::to_string(v) +
                                    " is an interior vertex of valence 2, and OpenSubdiv 3.5 cannot evaluate a cage "
                                    "that has one together with creases: remove the creases or the vertex");
  }

  // The texture coordinates: as many as their class asks, every index in range.
  if (!mesh.st.empty()) {
    if (mesh.stClass != StClass::FaceVarying && mesh.st.size() != mesh.points.size())
      throw std::invalid_argument("\"st\" has " + std::to_string(mesh.st.size()) + " values, one per point expected (" +
                                  std::to_string(mesh.points.size()) + ")");
    if (mesh.stClass == StClass::FaceVarying) {
      if (mesh.stIndices.size() != mesh.faceVertices.size())
        throw std::invalid_argument("\"st\" has " + std::to_string(mesh.stIndices.size()) + " indices, one per face corner expected (" +
                                    std::to_string(mesh.faceVertices.size()) + ")");
      for (const int k : mesh.stIndices)
        if (k < 0 || k >= static_cast<int>(mesh.st.size()))
          throw std::invalid_argument("\"st\" index " + std::to_string(k) + " is out of range (" + std::to_string(mesh.st.size()) +
                                      " values)");
    }
  }

  // Step 2: the topology, with RenderMan's boundary rule.
  osd::Far::TopologyDescriptor desc;
  desc.numVertices = nPoints;
  desc.numFaces = static_cast<int>(mesh.faceSizes.size());
  desc.numVertsPerFace = mesh.faceSizes.data();
  desc.vertIndicesPerFace = mesh.faceVertices.data();
  desc.numCreases = static_cast<int>(creaseWeights.size());
  desc.creaseVertexIndexPairs = creasePairs.data();
  desc.creaseWeights = creaseWeights.data();
  desc.numCorners = static_cast<int>(cornerWeights.size());
  desc.cornerVertexIndices = cornerVertices.data();
  desc.cornerWeights = cornerWeights.data();
  desc.numHoles = static_cast<int>(mesh.holes.size());
  desc.holeIndices = mesh.holes.data();
  // Face-varying "st": one channel, its values indexed per face corner.
  osd::Far::TopologyDescriptor::FVarChannel stChannel;
  if (!mesh.st.empty() && mesh.stClass == StClass::FaceVarying) {
    stChannel.numValues = static_cast<int>(mesh.st.size());
    stChannel.valueIndices = mesh.stIndices.data();
    desc.numFVarChannels = 1;
    desc.fvarChannels = &stChannel;
  }
  osd::Sdc::Options sdc;
  // FaceVaryingRule lists OpenSubdiv's rules in OpenSubdiv's order.
  sdc.SetFVarLinearInterpolation(static_cast<osd::Sdc::Options::FVarLinearInterpolation>(mesh.faceVaryingRule));
  sdc.SetVtxBoundaryInterpolation(mesh.interpolateBoundary == 1   ? osd::Sdc::Options::VTX_BOUNDARY_EDGE_AND_CORNER
                                  : mesh.interpolateBoundary == 2 ? osd::Sdc::Options::VTX_BOUNDARY_EDGE_ONLY
                                                                  : osd::Sdc::Options::VTX_BOUNDARY_NONE);
  using RefinerFactory = osd::Far::TopologyRefinerFactory<osd::Far::TopologyDescriptor>;
  const osd::Sdc::SchemeType scheme = mesh.scheme == SubdivScheme::Loop       ? osd::Sdc::SCHEME_LOOP
                                      : mesh.scheme == SubdivScheme::Bilinear ? osd::Sdc::SCHEME_BILINEAR
                                                                              : osd::Sdc::SCHEME_CATMARK;
  std::unique_ptr<osd::Far::TopologyRefiner> refiner(RefinerFactory::Create(desc, RefinerFactory::Options(scheme, sdc)));
  if (!refiner) throw std::invalid_argument("OpenSubdiv cannot build the cage's topology");
  return refiner;
}

namespace {

// The control points of a Catmull-Clark quadrilateral whose limit surface is the uniform
// bicubic B-spline patch of its 16 neighbouring points (every vertex interior, of valence
// 4, smooth, and every face around them a quadrilateral that is not a hole), or nothing.
// The B-spline basis is non-negative, so the patch lies in the hull of these points: the
// face's box without preparing it.
std::optional<std::vector<int>> RegularNeighbourhood(const osd::Far::TopologyLevel& level, int face) {
  const auto fv = level.GetFaceVertices(face);
  if (fv.size() != 4) return std::nullopt;
  std::vector<int> ring;
  for (const int v : fv) {
    if (level.IsVertexBoundary(v) || level.IsVertexNonManifold(v) || level.GetVertexFaces(v).size() != 4 ||
        level.GetVertexSharpness(v) > 0.0f)
      return std::nullopt;
    for (const int e : level.GetVertexEdges(v))
      if (level.GetEdgeSharpness(e) > 0.0f) return std::nullopt;
    for (const int f : level.GetVertexFaces(v)) {
      if (level.IsFaceHole(f) || level.GetFaceVertices(f).size() != 4) return std::nullopt;
      for (const int w : level.GetFaceVertices(f)) ring.push_back(w);
    }
  }
  std::sort(ring.begin(), ring.end());
  ring.erase(std::unique(ring.begin(), ring.end()), ring.end());
  return ring;
}

}  // namespace

std::vector<SubdivFace> PrepareSubdivFaces(const SubdivMesh& mesh, SubdivCounts* counts) {
  QuietOpenSubdiv();
  using osd::Far::Index;
  std::unique_ptr<osd::Far::TopologyRefiner> refiner = BuildRefiner(mesh);
  const osd::Far::TopologyLevel& level = refiner->GetLevel(0);
  SubdivCounts c;
  c.faces = level.GetNumFaces();
  c.vertices = level.GetNumVertices();
  c.holes = static_cast<int>(mesh.holes.size());
  for (const SubdivMesh::Crease& k : mesh.creases) c.creaseEdges += static_cast<int>(k.chain.size()) - 1;
  c.corners = static_cast<int>(mesh.corners.size());
  c.textureCoords = !mesh.st.empty();
  for (Index v = 0; v < level.GetNumVertices(); ++v)
    if (!level.IsVertexValenceRegular(v)) ++c.extraordinaryVertices;
  const auto cage = std::make_shared<SubdivFace::Cage>(mesh, std::move(refiner));

  // Step 3: every rendered face's surfaces with a box that contains it. The cage's points
  // give the box of a bilinear face (its corners) and of a regular Catmull-Clark one (its
  // 16 B-spline points); any other face is prepared once here for its patch points (Bfr's
  // bases are non-negative: the surface lies in their hull), then freed.
  const auto& factory = cage->Factory();
  const osd::Far::TopologyLevel& base = cage->Refiner().GetLevel(0);
  std::vector<SubdivFace> faces;
  FaceData scratch;
  for (Index f = 0; f < base.GetNumFaces(); ++f) {
    if (!factory.FaceHasLimitSurface(f)) continue;  // a hole, or a dropped boundary face
    std::vector<Vec3> hullPoints;
    const std::optional<std::vector<int>> ring =
        mesh.scheme == SubdivScheme::CatmullClark ? RegularNeighbourhood(base, f) : std::nullopt;
    if (mesh.scheme == SubdivScheme::Bilinear || ring) {
      for (const int v : ring ? *ring : std::vector<int>(base.GetFaceVertices(f).begin(), base.GetFaceVertices(f).end()))
        hullPoints.push_back(mesh.points[static_cast<std::size_t>(v)]);
    } else {
      cage->Prepare(f, &scratch);
      if (!scratch.surface.IsRegular()) ++c.irregularFaces;
      ++c.boundedAtLoad;
      for (std::size_t k = 0; k + 2 < scratch.patchPoints.size(); k += 3)
        hullPoints.emplace_back(scratch.patchPoints[k], scratch.patchPoints[k + 1], scratch.patchPoints[k + 2]);
    }
    const auto hull = std::make_shared<const std::vector<Vec3>>(std::move(hullPoints));
    const osd::Bfr::Parameterization param = factory.GetFaceParameterization(f);
    if (param.HasSubFaces() || param.GetType() == osd::Bfr::Parameterization::TRI) {
      for (int k = 0; k < param.GetFaceSize(); ++k) faces.emplace_back(cage, f, k, hull);
    } else {
      faces.emplace_back(cage, f, -1, hull);
    }
  }
  c.surfaces = static_cast<int>(faces.size());
  if (counts) *counts = c;
  return faces;
}

CageTessellation TessellateCage(const SubdivMesh& mesh, int rate) {
  QuietOpenSubdiv();
  const std::unique_ptr<osd::Far::TopologyRefiner> refiner = BuildRefiner(mesh);
  const osd::Bfr::RefinerSurfaceFactory<> factory(*refiner);
  std::vector<double> points;
  for (const Vec3& p : mesh.points) points.insert(points.end(), {p.x(), p.y(), p.z()});
  const osd::Bfr::Surface<double>::PointDescriptor xyz(3);
  CageTessellation out;
  osd::Bfr::Surface<double> surface;
  std::vector<double> patchPoints, coords;
  std::vector<int> facets;
  for (int f = 0; f < refiner->GetLevel(0).GetNumFaces(); ++f) {
    if (!factory.InitVertexSurface(f, &surface)) continue;
    patchPoints.resize(static_cast<std::size_t>(surface.GetNumPatchPoints()) * 3);
    surface.PreparePatchPoints(points.data(), xyz, patchPoints.data(), xyz);
    const osd::Bfr::Tessellation tess(surface.GetParameterization(), rate, osd::Bfr::Tessellation::Options().SetFacetSize(3));
    coords.resize(static_cast<std::size_t>(tess.GetNumCoords()) * 2);
    facets.resize(static_cast<std::size_t>(tess.GetNumFacets()) * 3);
    tess.GetCoords(coords.data());
    tess.GetFacets(facets.data());
    const int first = static_cast<int>(out.points.size());
    for (int k = 0; k < tess.GetNumCoords(); ++k) {
      double p[3];
      surface.Evaluate(&coords[2 * static_cast<std::size_t>(k)], patchPoints.data(), xyz, p);
      out.points.emplace_back(p[0], p[1], p[2]);
    }
    for (std::size_t k = 0; k + 2 < facets.size(); k += 3) {
      out.triangles.push_back({first + facets[k], first + facets[k + 1], first + facets[k + 2]});
      // The chord error at the edge midpoints and the centroid, in parameters and in space.
      // A facet across sub-faces of an n-gon has coordinates in two of their tiles (averages
      // of which are no point of the face): not measured, its neighbours are.
      const osd::Bfr::Parameterization param = surface.GetParameterization();
      if (param.HasSubFaces()) {
        int sub[3];
        for (int i = 0; i < 3; ++i) {
          double normalised[2];
          sub[i] = param.ConvertCoordToNormalizedSubFace(&coords[2 * static_cast<std::size_t>(facets[k + static_cast<std::size_t>(i)])], normalised);
        }
        if (sub[0] != sub[1] || sub[1] != sub[2]) continue;
      }
      constexpr double kAt[4][3] = {{0.5, 0.5, 0.0}, {0.0, 0.5, 0.5}, {0.5, 0.0, 0.5}, {1 / 3.0, 1 / 3.0, 1 / 3.0}};
      for (const auto& b : kAt) {
        double uv[2] = {0.0, 0.0}, p[3];
        Vec3 flat = Vec3::Zero();
        for (int i = 0; i < 3; ++i) {
          const int c = facets[k + static_cast<std::size_t>(i)];
          uv[0] += b[i] * coords[2 * static_cast<std::size_t>(c)];
          uv[1] += b[i] * coords[2 * static_cast<std::size_t>(c) + 1];
          flat += b[i] * out.points[static_cast<std::size_t>(first + c)];
        }
        surface.Evaluate(uv, patchPoints.data(), xyz, p);
        out.maxChordError = std::max(out.maxChordError, (Vec3(p[0], p[1], p[2]) - flat).norm());
      }
    }
  }
  return out;
}

}  // namespace patchscan
