#include "tracker/maxima.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <optional>
#include <type_traits>

#include "patch/bicubic.h"
#include "patch/subdiv.h"

namespace patchscan {

const char* ToString(StationaryKind k) {
  switch (k) {
    case StationaryKind::StrictMaximum: return "strict maximum";
    case StationaryKind::EdgeMaximum: return "edge maximum";
    case StationaryKind::CornerMaximum: return "corner maximum";
    case StationaryKind::LineOfMaxima: return "line of maxima";
    case StationaryKind::Saddle: return "saddle";
  }
  return "?";
}

namespace {

// h = -y and its derivatives at (u,v).
struct Height {
  double h;
  Vec2 g;   // h_u, h_v
  Mat2 H;   // h_uu h_uv; h_uv h_vv
  Vec3 pu, pv;  // screen tangents, to recognize collapsed edges
};

template <class ShapeT>
Height EvalHeight(const ShapeT& shape, const ScreenMap& map, const Vec2& uv) {
  ScreenDerivs d;
  EvaluateScreen(shape, map, uv.x(), uv.y(), DerivOrder::Second, &d);
  Height r;
  r.h = -d.p.y();
  r.g = Vec2(-d.dpdu.y(), -d.dpdv.y());
  r.H << -d.d2pdu2.y(), -d.d2pduv.y(), -d.d2pduv.y(), -d.d2pdv2.y();
  r.pu = d.dpdu;
  r.pv = d.dpdv;
  return r;
}

// h alone (a subdivision face's second derivatives cost two more evaluations).
template <class ShapeT>
double EvalH(const ShapeT& shape, const ScreenMap& map, const Vec2& uv) {
  ScreenDerivs d;
  EvaluateScreen(shape, map, uv.x(), uv.y(), DerivOrder::Position, &d);
  return -d.p.y();
}

// Relative size of det H below which the Hessian counts as singular (a parabolic
// cylinder, §3.4): the eigenvalue ratio is then below ~1e-6, far flatter than any
// ellipse seeding could follow.
constexpr double kCylinderRelDet = 1e-12;
// A climb stops when a step raises h by less than this many pixels.
constexpr double kClimbTolPx = 1e-10;
// Iteration cap of one climb: Newton finishes in a handful once near; gradient steps
// before that double or halve their length, so 200 covers any patch.
constexpr int kMaxClimbIterations = 200;
// An interior climb end counts as stationary when |grad h| / |Hess h|, the parameter
// distance to the stationary point, is below this.
constexpr double kStationaryParamDist = 1e-6;
// Samples around a collapsed edge to check that h falls away from it in every direction.
constexpr int kCollapsedEdgeSamples = 16;

// At a boundary coordinate, whether the gradient pushes out of the domain.
bool PushesOut(double t, double g) { return (t <= 0.0 && g < 0.0) || (t >= 1.0 && g > 0.0); }

// Whether uv lies on a collapsed boundary edge (its tangent vanishes against the other
// derivative) from which h rises into the domain somewhere along the edge: then the
// single surface point of that edge is no maximum.
template <class ShapeT>
bool OnCollapsedEdgeThatIsNoMaximum(const ShapeT& shape, const ScreenMap& map, const Vec2& uv,
                                    const Height& at) {
  for (int fixedParam = 0; fixedParam < 2; ++fixedParam) {
    if (!(uv[fixedParam] <= 0.0 || uv[fixedParam] >= 1.0)) continue;
    // Along the edge the other parameter varies; its tangent is dp/d(other).
    const Vec3& tangent = fixedParam == 0 ? at.pv : at.pu;
    const Vec3& across = fixedParam == 0 ? at.pu : at.pv;
    if (tangent.norm() > kCollapsedRel * std::max(across.norm(), 1e-300)) continue;
    for (int k = 0; k < kCollapsedEdgeSamples; ++k) {
      Vec2 q = uv;
      q[1 - fixedParam] = (k + 0.5) / kCollapsedEdgeSamples;
      const Height e = EvalHeight(shape, map, q);
      if (!PushesOut(q[fixedParam], e.g[fixedParam]) && e.g[fixedParam] != 0.0) return true;
    }
  }
  return false;
}

// The sign of y_u (axis 0) or y_v (axis 1) over a bicubic Bézier patch seen through the
// screen map m, if it is proven not to change; else 0. The homogeneous screen point's Y and
// W are bicubic polynomials with Bernstein coefficients m (b_ij, 1), and y_u = (Y_u W -
// Y W_u) / W^2; the numerator N is a polynomial of degree (5, 6) whose Bernstein
// coefficients are sums of products of Y_u's and W's and of Y's and W_u's (the product
// rule of Bernstein polynomials, here without its positive binomial factors, which change
// no sign). All of one sign, each beyond kMonotoneMargin of the magnitudes it is summed
// from (rounding), and W's coefficients all positive (the patch in front of the eye): y_u
// keeps that sign on the patch (the convex-hull property). The edge scan proves the same
// along an edge (tracker/edge_scan.cpp, MonotoneSign).
constexpr double kMonotoneMargin = 1e-9;

int ProvenSlopeSign(const BicubicPatch& patch, const Mat4& m, int axis) {
  // Y and W at the Bézier points, [i][j] with i along the axis differentiated.
  double y[4][4], w[4][4];
  const auto& b = patch.BezierPoints();
  for (int j = 0; j < 4; ++j)
    for (int i = 0; i < 4; ++i) {
      const Vec4 h = m.block<4, 3>(0, 0) * b[static_cast<std::size_t>(4 * j + i)] + m.col(3);
      if (!(h.w() > 0.0)) return 0;
      const int a = axis == 0 ? i : j, o = axis == 0 ? j : i;
      y[a][o] = h.y(), w[a][o] = h.w();
    }
  static constexpr double kBinomial2[3] = {1, 2, 1}, kBinomial3[4] = {1, 3, 3, 1};
  double n[6][7] = {}, mag[6][7] = {};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 4; ++j) {
      // Y_u's and W_u's coefficients (degree 2 along the axis), without their factor 3.
      const double yd = y[i + 1][j] - y[i][j], wd = w[i + 1][j] - w[i][j];
      for (int k = 0; k < 4; ++k)
        for (int l = 0; l < 4; ++l) {
          const double f = kBinomial2[i] * kBinomial3[k] * kBinomial3[j] * kBinomial3[l];
          const double t1 = yd * w[k][l], t2 = y[k][l] * wd;
          n[i + k][j + l] += f * (t1 - t2);
          mag[i + k][j + l] += f * (std::abs(t1) + std::abs(t2));
        }
    }
  bool pos = true, neg = true;
  for (int k = 0; k < 6; ++k)
    for (int l = 0; l < 7; ++l) {
      const double margin = kMonotoneMargin * mag[k][l];
      pos = pos && n[k][l] > margin;
      neg = neg && n[k][l] < -margin;
    }
  return pos ? 1 : neg ? -1 : 0;
}

// The corner where h = -y is highest, when y is proven monotone in u and in v over the
// whole surface (a bicubic patch, or a subdivision face that is bicubic pieces in every
// cell): then h has no interior stationary point and no maximum along an edge but at
// that corner, and every climb ends there. Else nothing, and the search runs.
template <class ShapeT>
std::optional<Vec2> ProvenTopCorner(const ShapeT& shape, const ScreenMap& map) {
  std::array<const BicubicPatch*, 16> pieces{};
  int n = 0;
  if constexpr (std::is_same_v<ShapeT, BicubicPatch>) {
    pieces[0] = &shape, n = 1;
  } else if constexpr (std::is_same_v<ShapeT, SubdivFace>) {
    n = shape.BicubicCover(&pieces);
  }
  if (n <= 0) return std::nullopt;
  int sign[2] = {0, 0};
  for (int k = 0; k < n; ++k)
    for (int axis = 0; axis < 2; ++axis) {
      const int s = ProvenSlopeSign(*pieces[static_cast<std::size_t>(k)], map.ScreenFromObject(), axis);
      if (s == 0 || (k > 0 && s != sign[axis])) return std::nullopt;
      sign[axis] = s;
    }
  // y rising along u: h falls, its top at u = 0.
  return Vec2(sign[0] > 0 ? 0.0 : 1.0, sign[1] > 0 ? 0.0 : 1.0);
}

template <class ShapeT>
std::vector<Stationary> FindImpl(const ShapeT& shape, const ScreenMap& map, Counters& st, bool prove) {
  std::vector<Stationary> found;
  if (const std::optional<Vec2> corner = prove ? ProvenTopCorner(shape, map) : std::nullopt) {
    // The climbs' end, found without them: the corner, evaluated there.
    const Height at = EvalHeight(shape, map, *corner);
    if (PushesOut(corner->x(), at.g.x()) && PushesOut(corner->y(), at.g.y())) {
      ++st[Counter::MaximaProvenMonotone];
      if (OnCollapsedEdgeThatIsNoMaximum(shape, map, *corner, at)) return found;
      found.push_back({StationaryKind::CornerMaximum, *corner, -at.h, at.g, at.H, -1});
      return found;
    }
  }
  auto classifyInterior = [](const Mat2& H) {
    const double det = H.determinant(), scale = H.squaredNorm();
    if (std::abs(det) <= kCylinderRelDet * scale) return StationaryKind::LineOfMaxima;
    if (det < 0) return StationaryKind::Saddle;
    return H(0, 0) < 0 ? StationaryKind::StrictMaximum : StationaryKind::Saddle;  // minima filtered below
  };
  // A seed adds at most a climb's end and a saddle: one allocation, not growth by doubling.
  found.reserve(2 * kMaximaSeedGrid * kMaximaSeedGrid);

  for (int sj = 0; sj < kMaximaSeedGrid; ++sj)
    for (int si = 0; si < kMaximaSeedGrid; ++si) {
      ++st[Counter::MaximaSeeds];
      const Vec2 seed(si / double(kMaximaSeedGrid - 1), sj / double(kMaximaSeedGrid - 1));

      // Step 1: constrained hill climbing (projected gradient, Newton when concave).
      Vec2 uv = seed;
      const Height atSeed = EvalHeight(shape, map, uv);
      Height at = atSeed;
      double stepLen = 0.25;  // gradient step length in parameter units, adapted
      bool fixed[2] = {false, false};
      for (int it = 0; it < kMaxClimbIterations; ++it) {
        ++st[Counter::MaximaClimbIterations];
        for (int k = 0; k < 2; ++k) fixed[k] = PushesOut(uv[k], at.g[k]);
        if (fixed[0] && fixed[1]) break;
        Vec2 step = Vec2::Zero();
        if (!fixed[0] && !fixed[1]) {
          const bool concave = at.H(0, 0) < 0 && at.H.determinant() > 0;
          step = concave ? Vec2(-at.H.inverse() * at.g) : Vec2(at.g.normalized() * stepLen);
        } else {
          const int k = fixed[0] ? 1 : 0;
          step[k] = at.H(k, k) < 0 ? -at.g[k] / at.H(k, k) : (at.g[k] > 0 ? stepLen : -stepLen);
        }
        if (!step.allFinite() || step.squaredNorm() == 0.0) break;
        // Clip at the boundary, keeping the direction. The coordinate that meets it is set
        // on it: uv + step rounds to within an ulp of it, and a climb left an ulp inside
        // took a step of that size next, gained nothing and stopped there, an "edge maximum"
        // short of the corner the edge rises to.
        double scale = 1.0;
        int hit = -1;
        for (int k = 0; k < 2; ++k) {
          const double bound = uv[k] + step[k] < 0.0 ? 0.0 : uv[k] + step[k] > 1.0 ? 1.0 : NAN;
          if (std::isnan(bound)) continue;
          if (const double s = (bound - uv[k]) / step[k]; s < scale) scale = s, hit = k;
        }
        step *= scale;
        // Halve until h rises.
        Height next;
        Vec2 to;
        bool rose = false, landed = false;
        for (int halving = 0; halving < 40; ++halving) {
          to = (uv + step).cwiseMax(0.0).cwiseMin(1.0);
          landed = halving == 0 && hit >= 0;
          if (landed) to[hit] = step[hit] < 0.0 ? 0.0 : 1.0;
          next = EvalHeight(shape, map, to);
          if (next.h > at.h) {
            rose = true;
            break;
          }
          step *= 0.5;
        }
        if (!rose) break;
        const double gain = next.h - at.h;
        stepLen = std::min(1.0, (step.norm() >= stepLen * 0.99) ? stepLen * 2 : stepLen * 0.5);
        uv = to;
        at = next;
        // A step cut short by the boundary gains little for that reason alone (from a few
        // ulps inside it, nothing): the climb goes on along the edge it landed on.
        if (gain < kClimbTolPx && !landed) break;
      }
      for (int k = 0; k < 2; ++k) fixed[k] = PushesOut(uv[k], at.g[k]) || (uv[k] <= 0.0 || uv[k] >= 1.0);

      // Step 2: classify where the climb ended.
      Stationary s{StationaryKind::StrictMaximum, uv, -at.h, at.g, at.H, -1};
      const bool outU = (uv.x() <= 0.0 || uv.x() >= 1.0) && PushesOut(uv.x(), at.g.x());
      const bool outV = (uv.y() <= 0.0 || uv.y() >= 1.0) && PushesOut(uv.y(), at.g.y());
      if (outU || outV) {
        s.kind = outU && outV ? StationaryKind::CornerMaximum : StationaryKind::EdgeMaximum;
        if (!(outU && outV))
          s.edge = static_cast<int>(outU ? (uv.x() <= 0 ? PatchEdge::U0 : PatchEdge::U1)
                                         : (uv.y() <= 0 ? PatchEdge::V0 : PatchEdge::V1));
        // A collapsed edge is one point (a pole, the teapot's lid apex): the end is a
        // maximum only if h falls away from that point into the domain all along it.
        if (OnCollapsedEdgeThatIsNoMaximum(shape, map, uv, at)) {
          ++st[Counter::MaximaRejectedCollapsed];
          continue;
        }
      } else {
        // An interior end must be stationary: the gradient, over the Hessian's scale, is
        // the distance (in parameter units) still to go.
        if (at.g.norm() > kStationaryParamDist * std::max(at.H.norm(), 1e-300)) continue;
        s.kind = classifyInterior(at.H);
        if (s.kind == StationaryKind::Saddle) continue;  // a climb does not end on a saddle
      }
      found.push_back(s);

      // Step 3: saddles, by Newton on grad h = 0 from the same seed (§3.2.2.4).
      NewtonOptions opt;
      opt.domain = DomainRule::Fail;
      // Newton starts where the climb did (the seed is in the domain, so not clipped), and
      // a converged solve ends on the point it evaluated last: both evaluations are kept,
      // not repeated (a subdivision face's cost most of the pre-pass).
      const double gtol = 1e-10 * std::max(atSeed.H.norm(), 1e-300);
      Vec2 lastUv = seed;
      Height last = atSeed;
      const auto r = SolveNewton2(
          [&](const Vec2& p, Vec2* f, Mat2* j) {
            if (p != lastUv) last = EvalHeight(shape, map, p), lastUv = p;
            *f = last.g;
            *j = last.H;
          },
          seed, Vec2(gtol, gtol), opt);
      st[Counter::MaximaNewtonIterations] += r.iterations;
      if (r.status == NewtonStatus::Converged && (r.uv.array() > 0).all() && (r.uv.array() < 1).all()) {
        const Height e = r.uv == lastUv ? last : EvalHeight(shape, map, r.uv);
        if (e.H.determinant() < -kCylinderRelDet * e.H.squaredNorm())
          found.push_back({StationaryKind::Saddle, r.uv, -e.h, e.g, e.H, -1});
      }
    }

  // Step 4: merge duplicates (same kind, y and midpoint y within a tenth of a raster).
  std::sort(found.begin(), found.end(), [](const Stationary& a, const Stationary& b) { return a.y < b.y; });
  std::vector<Stationary> unique;
  unique.reserve(found.size());
  for (const Stationary& s : found) {
    bool dup = false;
    for (const Stationary& u : unique) {
      if (u.kind != s.kind || std::abs(u.y - s.y) > kDuplicateY) continue;
      // Climbs ending on one corner end on the very same uv (clamped to it): their midpoint
      // is that point, whose y both already hold.
      if (u.uv == s.uv && u.y == s.y) {
        dup = true;
        break;
      }
      const double yMid = -EvalH(shape, map, 0.5 * (u.uv + s.uv));
      if (std::abs(yMid - s.y) <= kDuplicateY && std::abs(yMid - u.y) <= kDuplicateY) {
        dup = true;
        break;
      }
    }
    if (dup) ++st[Counter::MaximaDuplicates];
    else unique.push_back(s);
  }
  return unique;
}

std::vector<Stationary> Find(const Surface& s, const ScreenMap& map, Counters* counters, bool prove) {
  Counters local;
  Counters& st = counters ? *counters : local;
  return VisitShape(s, [&](const auto& shape) { return FindImpl(shape, map, st, prove); });
}

}  // namespace

std::vector<Stationary> FindStationaryPoints(const Surface& s, const ScreenMap& map, Counters* counters) {
  return Find(s, map, counters, true);
}

std::vector<Stationary> SearchStationaryPoints(const Surface& s, const ScreenMap& map, Counters* counters) {
  return Find(s, map, counters, false);
}

}  // namespace patchscan
