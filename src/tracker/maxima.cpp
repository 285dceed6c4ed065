#include "tracker/maxima.h"

#include <algorithm>

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

template <class ShapeT>
std::vector<Stationary> FindImpl(const ShapeT& shape, const ScreenMap& map, Counters& st) {
  std::vector<Stationary> found;
  auto classifyInterior = [](const Mat2& H) {
    const double det = H.determinant(), scale = H.squaredNorm();
    if (std::abs(det) <= kCylinderRelDet * scale) return StationaryKind::LineOfMaxima;
    if (det < 0) return StationaryKind::Saddle;
    return H(0, 0) < 0 ? StationaryKind::StrictMaximum : StationaryKind::Saddle;  // minima filtered below
  };

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
        // Clip at the boundary, keeping the direction.
        double scale = 1.0;
        for (int k = 0; k < 2; ++k) {
          if (uv[k] + step[k] < 0.0) scale = std::min(scale, -uv[k] / step[k]);
          if (uv[k] + step[k] > 1.0) scale = std::min(scale, (1.0 - uv[k]) / step[k]);
        }
        step *= scale;
        // Halve until h rises.
        Height next;
        Vec2 to;
        bool rose = false;
        for (int halving = 0; halving < 40; ++halving) {
          to = (uv + step).cwiseMax(0.0).cwiseMin(1.0);
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
        if (gain < kClimbTolPx) break;
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

}  // namespace

std::vector<Stationary> FindStationaryPoints(const Surface& s, const ScreenMap& map,
                                             Counters* counters) {
  Counters local;
  Counters& st = counters ? *counters : local;
  return VisitShape(s, [&](const auto& shape) { return FindImpl(shape, map, st); });
}

}  // namespace patchscan
