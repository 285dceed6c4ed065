#include "patch/subdiv_pieces.h"

#include <Eigen/Dense>

namespace patchscan {

namespace osd = OpenSubdiv;

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

namespace {

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

// The cubic Bernstein polynomials at x and their first and second derivatives.
void Bernstein3(double x, double b[4], double d[4], double dd[4]) {
  const double y = 1.0 - x;
  b[0] = y * y * y, b[1] = 3.0 * x * y * y, b[2] = 3.0 * x * x * y, b[3] = x * x * x;
  d[0] = -3.0 * y * y, d[1] = 3.0 * y * (y - 2.0 * x), d[2] = 3.0 * x * (2.0 * y - x), d[3] = 3.0 * x * x;
  dd[0] = 6.0 * y, dd[1] = 6.0 * (3.0 * x - 2.0), dd[2] = 6.0 * (1.0 - 3.0 * x), dd[3] = 6.0 * x;
}

}  // namespace

void GregoryPatch::PositionWeights(double s, double t, double w[kPoints]) {
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

void GregoryPatch::Evaluate(double s, double t, DerivOrder order, SurfaceDerivs* out) const {
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

namespace {

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

// A patch over a cell of `level` holding quarter (i, j), at (u, v).
template <class Patch>
bool Scaled(const Patch& patch, int level, int i, int j, double u, double v, DerivOrder order, SurfaceDerivs* out) {
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
auto CellOf(const osd::Bfr::Surface<double>& surface, const std::vector<double>& pts, const SubFaceMap& map,
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

}  // namespace

BicubicPieces::BicubicPieces(const osd::Bfr::Surface<double>& surface, const std::vector<double>& pts, const SubFaceMap& map,
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

// The polynomial or Gregory patch at (u, v), if one covers that cell.
bool BicubicPieces::Evaluate(double u, double v, DerivOrder order, SurfaceDerivs* out) const {
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

// Marks the quarters of cell (ci, cj) of `level` as covered by patch k of `of`.
void BicubicPieces::Cover(std::array<std::int8_t, 16>& of, int k, int level, int ci, int cj) {
  const int width = 4 >> level;
  for (int j = cj * width; j < (cj + 1) * width; ++j)
    for (int i = ci * width; i < (ci + 1) * width; ++i) {
      of[static_cast<std::size_t>(4 * j + i)] = static_cast<std::int8_t>(k);
      levelOf[static_cast<std::size_t>(4 * j + i)] = static_cast<std::int8_t>(level);
    }
}

// Fits the cell (ci, cj) of `level` as a bicubic (Fit) or a Gregory patch
// (FitIrregular); covers its quarters if it is one. A cell of level 2 takes its nodes
// from, and puts them into, its quadrant's `nodes` where given.
bool BicubicPieces::Fit(const osd::Bfr::Surface<double>& surface, const std::vector<double>& pts, const SubFaceMap& map,
         double tol, int level, int ci, int cj, QuadrantNodes* nodes) {
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

bool BicubicPieces::FitIrregular(const osd::Bfr::Surface<double>& surface, const std::vector<double>& pts, const SubFaceMap& map,
                  double tol, int level, int ci, int cj) {
  return Keep(FitGregory(CellOf(surface, pts, map, level, ci, cj), tol), gregory, gregoryOf, level, ci, cj);
}

}  // namespace patchscan
