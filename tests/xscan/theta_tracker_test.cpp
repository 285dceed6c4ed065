// θ trackers (Blinn 1978 §4.1, §4.3): G_i's analytic gradient against finite differences; a
// tracker solved by damped Newton sits on its scan line at its tabulated angle and never
// on the other root θ_i + π; the turn function is θ's derivative along the level curve,
// and a turn tracker solved by Newton sits where θ turns back; and chains advanced from
// line to line as trackers (with their links repaired sideways where suspicious) have the
// same vertices, at the same places, as chains crawled afresh on the same lines.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <numbers>
#include <random>
#include <sstream>
#include <variant>

#include "scene/scene.h"
#include "patch/screen.h"
#include "tracker/maxima.h"
#include "xscan/agreement.h"
#include "xscan/exact_scan.h"
#include "xscan/theta_walk.h"

namespace patchscan {
namespace {

using test::View;

struct TrackerCase {
  std::string name;
  Surface surface;
  Camera camera;
};

std::vector<TrackerCase> Cases() {
  std::vector<TrackerCase> cases;
  cases.push_back({"sphere", Surface{Sphere(1.0, -1.0, 1.0, 360), Affine3::Identity()}, View(Vec3(3, -2, 1.5), 128)});
  cases.push_back({"torus", Surface{Torus(1.0, 0.35, 0, 360, 360), Affine3::Identity()}, View(Vec3(2.5, -2.0, 2.2), 128)});
  cases.push_back({"monkey saddle", Surface{MonkeySaddle(0.9), Affine3::Identity()}, View(Vec3(2.5, -3.0, 2.0), 128)});
  // A mirrored, sheared, scaled torus: the world normal's sign follows det L < 0.
  Affine3 odd = Affine3::Identity();
  odd.linear() << -1.3, 0.2, 0.0, 0.1, 0.8, 0.3, 0.0, -0.2, 1.1;
  cases.push_back({"mirrored torus", Surface{Torus(1.0, 0.35, 0, 360, 360), odd}, View(Vec3(2.5, -2.0, 2.2), 128)});
  auto loaded = LoadScene(PATCHSCAN_SURFACES_DIR "/teapot.bpt");
  EXPECT_TRUE(std::holds_alternative<Scene>(loaded));
  const Scene teapot = std::get<Scene>(std::move(loaded));
  const Camera base = View(Vec3::Zero(), 400, Vec3(0, 0, 1));
  const Camera framed = FrameBounds(teapot.WorldBounds(), base, DefaultViewDirection(Vec3(0, 0, 1)));
  for (std::size_t k : {0u, 5u, 12u, 20u, 28u})  // body, handle, spout, lid, bottom
    cases.push_back({"teapot patch " + std::to_string(k), teapot.surfaces[k], framed});
  Camera ortho = View(Vec3(2.5, -2.0, 2.2), 128);
  ortho.orthographic = true;
  cases.push_back({"torus, orthographic", Surface{Torus(1.0, 0.35, 0, 360, 360), Affine3::Identity()}, ortho});
  return cases;
}

ThetaFrame FrameOf(const Camera& c, const Surface& s) {
  return {EyePoint(c), ViewRight(c), ViewForward(c), c.orthographic, &s.worldFromObject, {},
          s.worldFromObject.matrix().isIdentity(0.0)};
}

// The value of G_i / |N| at (u,v), for finite differences.
double TableG(const Surface& s, const ThetaFrame& frame, double u, double v, const Vec2& angle) {
  SurfaceDerivs d;
  VisitShape(s, [&](const auto& shape) { shape.Evaluate(u, v, DerivOrder::Second, &d); });
  return TableFunction(d, frame, angle).g;
}

// Calls compare(case, frame, uv, k) at 200 random points of (0.05, 0.95)² on each case: it
// returns whether it compared there (not at a collapsed edge, say); each case must compare
// at more than 50.
template <class Compare>
void AtRandomPoints(unsigned seed, Compare&& compare) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> in(0.05, 0.95);
  for (const TrackerCase& c : Cases()) {
    const ThetaFrame frame = FrameOf(c.camera, c.surface);
    int compared = 0;
    for (int k = 0; k < 200; ++k) {
      const Vec2 uv(in(rng), in(rng));
      compared += compare(c, frame, uv, k);
    }
    EXPECT_GT(compared, 50) << c.name;
  }
}

TEST(ThetaTracker, GradientOfGMatchesFiniteDifferences) {
  // Central differences with step 1e-5 in (u,v): truncation error about h^2 |g'''| / 6 and
  // rounding about 1e-16 / h, both below 1e-8 for these surfaces' derivatives; relative to
  // the gradient's own size (at least 1e-2 at the points compared) that is 1e-6.
  constexpr double kStep = 1e-5, kRelTol = 1e-5;
  AtRandomPoints(7, [&](const TrackerCase& c, const ThetaFrame& frame, const Vec2& uv, int k) {
    const double u = uv.x(), v = uv.y();
    const int i = 1 + k % 15;
    const Vec2 angle(std::cos(2 * std::numbers::pi * i / 16), std::sin(2 * std::numbers::pi * i / 16));
    SurfaceDerivs d;
    VisitShape(c.surface, [&](const auto& shape) { shape.Evaluate(u, v, DerivOrder::Second, &d); });
    if (d.dpdu.cross(d.dpdv).norm() < 1e-6) return false;  // a collapsed edge
    const TableResidual g = TableFunction(d, frame, angle);
    const Vec2 fd((TableG(c.surface, frame, u + kStep, v, angle) - TableG(c.surface, frame, u - kStep, v, angle)) / (2 * kStep),
                   (TableG(c.surface, frame, u, v + kStep, angle) - TableG(c.surface, frame, u, v - kStep, angle)) / (2 * kStep));
    if (fd.norm() < 1e-2) return false;
    EXPECT_LE((g.grad - fd).norm(), kRelTol * fd.norm()) << c.name << " at (" << u << ", " << v << "), i " << i
                                                         << ": analytic " << g.grad.transpose() << ", differences "
                                                         << fd.transpose();
    // θ of the fragment's normal agrees with G's sign convention: along = cos(θ - θ_i)
    // and g = sin(θ_i - θ) times the in-plane part of the unit normal.
    const Vec3 n = (c.surface.worldFromObject.linear().inverse().transpose() * d.dpdu.cross(d.dpdv)).normalized();
    const double theta = frame.Theta(c.surface.worldFromObject * d.p, n);
    const double inPlane = std::hypot(g.along, g.g);
    EXPECT_NEAR(g.g, inPlane * std::sin(2 * std::numbers::pi * i / 16 - theta), 1e-12) << c.name;
    EXPECT_NEAR(g.along, inPlane * std::cos(2 * std::numbers::pi * i / 16 - theta), 1e-12) << c.name;
    return true;
  });
}

TEST(ThetaTracker, AnIdentityMapTakenAsObjectSpaceChangesNoValue) {
  // ThetaFrame::worldIsObject skips the identity's products: 1 x + 0 y + 0 z is x exactly
  // for finite x, y, z, so G, its gradient, the turn function and the normal's slope are
  // the general path's to the bit.
  AtRandomPoints(13, [&](const TrackerCase& c, const ThetaFrame& frame, const Vec2& uv, int k) {
    if (!frame.worldIsObject) return true;  // the mirrored torus: its map is no identity
    ThetaFrame general = frame;
    general.worldIsObject = false;
    SurfaceDerivs d;
    VisitShape(c.surface, [&](const auto& shape) { shape.Evaluate(uv.x(), uv.y(), DerivOrder::Second, &d); });
    const Vec2 angle(std::cos(0.3 * k), std::sin(0.3 * k));
    const TableResidual a = TableFunction(d, frame, angle), b = TableFunction(d, general, angle);
    EXPECT_EQ(a.g, b.g) << c.name;
    EXPECT_EQ(a.grad, b.grad) << c.name;
    EXPECT_EQ(a.along, b.along) << c.name;
    EXPECT_EQ(a.t, b.t) << c.name;
    const Vec2 gradY(0.3, 1.0), duv(0.01, -0.02);
    const double ta = TurnFunction(d, gradY, frame), tb = TurnFunction(d, gradY, general);
    EXPECT_TRUE(ta == tb || (std::isnan(ta) && std::isnan(tb))) << c.name;
    const Vec3 sa = NormalSlope(d, duv, frame), sb = NormalSlope(d, duv, general);
    EXPECT_TRUE(sa == sb || (sa.hasNaN() && sb.hasNaN())) << c.name;
    return true;
  });
}

// θ of the surface's normal at (u,v) (by atan2 of the world normal), screen y's (u,v)
// gradient there, and the surface's derivatives.
struct ThetaAt {
  double theta = 0.0;
  Vec2 gradY;
  SurfaceDerivs d;
};
ThetaAt ThetaOfPoint(const Surface& s, const Camera& c, const ThetaFrame& frame, const Vec2& uv) {
  ThetaAt out;
  VisitShape(s, [&](const auto& shape) { shape.Evaluate(uv.x(), uv.y(), DerivOrder::Second, &out.d); });
  const Vec3 n = (s.worldFromObject.linear().inverse().transpose() * out.d.dpdu.cross(out.d.dpdv)).normalized();
  out.theta = frame.Theta(s.worldFromObject * out.d.p, n);
  ScreenDerivs sd;
  ScreenMap(c, s.worldFromObject).FromObject(out.d, DerivOrder::First, &sd);
  out.gradY = Vec2(sd.dpdu.y(), sd.dpdv.y());
  return out;
}

TEST(ThetaTracker, TurnFunctionIsThetasDerivativeAlongTheLevelCurve) {
  // §4.3's T(u,v) in this project's form: θ's derivative along the level curve's unit
  // tangent (-y_v, y_u)/|∇y|, against central differences of θ itself (atan2 of the
  // normal, independent of TableFunction) along that tangent. Step 1e-5: truncation
  // h^2 |θ'''| / 6 and rounding 1e-16 / h stay below 1e-7 where |θ'| < 1e3; compared at
  // 1e-5 relative to max(|θ'|, 1).
  constexpr double kStep = 1e-5, kRelTol = 1e-5;
  AtRandomPoints(11, [&](const TrackerCase& c, const ThetaFrame& frame, const Vec2& uv, int) {
    const ThetaAt at = ThetaOfPoint(c.surface, c.camera, frame, uv);
    if (at.d.dpdu.cross(at.d.dpdv).norm() < 1e-6 || at.gradY.norm() < 1e-6) return false;  // a collapsed edge
    const double tau = TurnFunction(at.d, at.gradY, frame);
    if (!std::isfinite(tau)) return false;  // the normal across the scan plane
    const Vec2 t = Vec2(-at.gradY.y(), at.gradY.x()).normalized();
    const double fd = std::remainder(ThetaOfPoint(c.surface, c.camera, frame, uv + kStep * t).theta -
                                         ThetaOfPoint(c.surface, c.camera, frame, uv - kStep * t).theta,
                                     2 * std::numbers::pi) /
                      (2 * kStep);
    if (std::abs(fd) > 1e3) return false;  // near a pole of θ (normal almost across the plane)
    EXPECT_NEAR(tau, fd, kRelTol * std::max(std::abs(fd), 1.0)) << c.name << " at " << uv.transpose();
    return true;
  });
}

// A surface's Y scan (SurfaceScan), line by line from the top of its screen box, with its θ
// walker: as ExactScan scans a surface, without the back end.
class LineScan {
 public:
  LineScan(const Surface& s, const Camera& c, int steps)
      : s_(s), c_(c), steps_(steps), frame_(FrameOf(c, s)), scan_(s, c, true, counters) {}
  double Top() const { return scan_.Top(); }
  // Advances the trackers to y; the number of Y-scan events so far.
  long AdvanceTo(double y) {
    scan_.AdvanceTo(y);
    return scan_.Events();
  }
  // The chains crawled on line y (the trackers advanced to it).
  void Crawl(double y, ChainSet* out) {
    out->Clear();
    With(y, [&](auto& walker, auto& make) {
      walker.WalkAll(scan_.Trackers(), &edgeUsed_, &silUsed_, &scratch_, make,
                     [&](std::span<const ThetaVertex> chain, bool closed) { out->Add(chain, closed); });
    });
  }
  // The chains `from` of line y - dy advanced to line y as θ trackers.
  bool Advance(double y, double dy, const ChainSet& from, bool extrapolate, ChainSet* out) {
    bool ok = false;
    With(y, [&](auto& walker, auto& make) {
      ok = walker.Advance(from, dy, scan_.Trackers(), extrapolate, &edgeUsed_, &silUsed_, &scratch_, out, make);
    });
    return ok;
  }
  const ScreenMap& Map() const { return scan_.Map(); }
  // The sample columns the walker is given (by default one at every pixel centre's x,
  // 0 .. width - 1), and whether its chains are made for chords on every row rather than
  // for slabs (ThetaWalker::SetRowChords); vertices carry their slopes either way.
  void SetColumns(const raster::SampleColumns& cols) { cols_ = cols; }
  void SetRows(bool rows) { rows_ = rows; }
  Counters counters;

 private:
  template <class F>
  void With(double y, F&& f) {
    VisitShape(s_, [&](const auto& shape) {
      ThetaWalker<std::decay_t<decltype(shape)>> walker(shape, scan_.Map(), y, cols_, &counters, nullptr, ThetaTable(steps_), frame_);
      walker.SetNormalSlopes(true);
      walker.SetRowChords(rows_);
      auto make = [&](const LevelPoint& p) { return FragmentAt(p, s_, scan_.NormalFromObject(), 0); };
      f(walker, make);
    });
  }
  const Surface& s_;
  Camera c_;
  int steps_;
  ThetaFrame frame_;
  SurfaceScan scan_;
  raster::SampleColumns cols_{0.0, 1.0, c_.width};
  bool rows_ = false;
  std::vector<char> edgeUsed_, silUsed_;
  std::vector<ThetaVertex> scratch_;
};

// The vertices of a chain set that are trackers (ends, silhouettes, tabulated angles,
// turn points), less the tabulated angles next to a silhouette vertex: the crawl does not place those in
// the step that finds the silhouette (they are within that step of it), while an advanced
// chain keeps those it had.
std::vector<ThetaVertex> Trackers(const ChainSet& set) {
  std::vector<ThetaVertex> out;
  for (const ChainSet::Chain& c : set.chains) {
    const auto v = set.Of(c);
    for (std::size_t k = 0; k < v.size(); ++k) {
      const ThetaVertex::Kind kind = v[k].kind;
      if (kind == ThetaVertex::Kind::Tilt) continue;
      if (kind == ThetaVertex::Kind::Table) {
        // Next to a silhouette along the chain, tilt vertices (which chains crawled at
        // different places may or may not have) passed over.
        auto silhouetteFrom = [&](std::size_t j, int step) {
          for (; j < v.size(); j += static_cast<std::size_t>(step)) {  // j wraps below 0
            if (v[j].kind != ThetaVertex::Kind::Tilt) return v[j].kind == ThetaVertex::Kind::Silhouette;
          }
          return false;
        };
        if (silhouetteFrom(k - 1, -1) || silhouetteFrom(k + 1, 1)) continue;
      }
      out.push_back(v[k]);
    }
  }
  return out;
}

// How many vertices of `a` have no vertex of `b` of the same kind and index at the same place.
int Unmatched(const std::vector<ThetaVertex>& a, const std::vector<ThetaVertex>& b, double tolPx) {
  int n = 0;
  for (const ThetaVertex& v : a) {
    bool found = false;
    for (const ThetaVertex& w : b)
      found = found || (v.kind == w.kind && v.index == w.index && std::abs(v.x - w.x) <= tolPx);
    n += !found;
  }
  return n;
}

// Newton from a start one line away converges quadratically: two or three iterations for
// most trackers. With a wrong Jacobian (a missing term of G_i's gradient, a turn
// function's gradient off by 50%) it converges linearly and takes 5 to 12: a mean above
// this says the Jacobian is wrong.
constexpr double kMeanIterationsOneLine = 3.5;

TEST(ThetaTracker, SolvedTrackersSitAtTheirAnglesOnTheirLines) {
  // From the crawl's vertex on one line, Newton to the next line (1 px below) must land
  // on that line at exactly the tabulated angle, on θ_i's side (not θ_i + π), in few
  // iterations (kMeanIterationsOneLine).
  constexpr double kAngleTolRad = 1e-8;  // kThetaTol, with room for the normal's rounding
  std::int64_t allSolved = 0, allIterations = 0;
  for (const TrackerCase& c : Cases()) {
    LineScan scan(c.surface, c.camera, 16);
    const ThetaFrame frame = FrameOf(c.camera, c.surface);
    ChainSet line;
    long solved = 0, lost = 0;
    for (double y = std::ceil(scan.Top()) + 0.5; y < c.camera.height; y += 1.0) {
      scan.AdvanceTo(y);
      if (!line.v.empty()) {
        VisitShape(c.surface, [&](const auto& shape) {
          for (const ThetaVertex& v : line.v) {
            if (v.kind != ThetaVertex::Kind::Table) continue;
            LevelPoint p;
            std::int64_t iterations = 0;
            const double angle = 2 * std::numbers::pi * v.index / 16;
            if (!SolveThetaTracker(shape, scan.Map(), y, frame, Vec2(std::cos(angle), std::sin(angle)), v.uv, &p,
                                   &iterations)) {
              ++lost;  // left the patch, or no convergence: the scan repairs sideways
              continue;
            }
            ++solved;
            ++allSolved;
            allIterations += iterations;
            EXPECT_NEAR(p.y, y, kEdgeTolPx) << c.name;
            const raster::Fragment f = FragmentAt(p, c.surface, c.surface.worldFromObject.linear().inverse().transpose(), 0);
            const double want = 2 * std::numbers::pi * v.index / 16;
            const double got = frame.Theta(f.position, f.normal);
            EXPECT_NEAR(std::remainder(got - want, 2 * std::numbers::pi), 0.0, kAngleTolRad)
                << c.name << " line " << y << " index " << v.index;
          }
        });
      }
      scan.Crawl(y, &line);
    }
    std::cout << c.name << ": " << solved << " trackers solved one line on, " << lost << " lost\n";
    // Lost trackers left the patch (their angle is gone from the section there) or did
    // not converge; the scan repairs both sideways.
    EXPECT_GT(solved, 20) << c.name;
  }
  const double mean = static_cast<double>(allIterations) / static_cast<double>(allSolved);
  std::cout << "Newton iterations per θ tracker solved one line on: " << mean << '\n';
  EXPECT_LE(mean, kMeanIterationsOneLine);
}

TEST(ThetaTracker, SolvedTurnTrackersSitAtTurnPoints) {
  // From the crawl's turn vertex on one line, Newton on (y - ys, T) to the next line must
  // land on that line where θ turns back along the curve: the points of the line a
  // distance δ either way along the curve (projected onto the line by Newton in y) both
  // have θ on the same side of the turn's. δ = 1e-3 of (u,v): θ moves by θ'' δ²/2 there,
  // far above the turn's own error (kTurnTol δ = 1e-10) wherever θ'' > 1e-3.
  constexpr double kDelta = 1e-3, kFlatRad = 1e-9;
  long solved = 0, lost = 0, flat = 0;
  std::int64_t iterations = 0;
  for (const TrackerCase& c : Cases()) {
    LineScan scan(c.surface, c.camera, 16);
    const ThetaFrame frame = FrameOf(c.camera, c.surface);
    const ScreenMap map(c.camera, c.surface.worldFromObject);
    auto yAt = [&](const Vec2& uv, Vec2* grad) {
      ScreenDerivs sd;
      EvaluateScreen(c.surface, map, uv.x(), uv.y(), DerivOrder::First, &sd);
      *grad = Vec2(sd.dpdu.y(), sd.dpdv.y());
      return sd.p.y();
    };
    // The point of line ys nearest uv along screen y's gradient.
    auto onLine = [&](Vec2 uv, double ys) {
      for (int k = 0; k < 20; ++k) {
        Vec2 g;
        const double y = yAt(uv, &g);
        if (std::abs(y - ys) <= 1e-10) break;
        uv -= (y - ys) * g / g.squaredNorm();
      }
      return uv;
    };
    ChainSet line;
    for (double y = std::ceil(scan.Top()) + 0.5; y < c.camera.height; y += 1.0) {
      scan.AdvanceTo(y);
      VisitShape(c.surface, [&](const auto& shape) {
        for (const ThetaVertex& v : line.v) {
          if (v.kind != ThetaVertex::Kind::Turn) continue;
          LevelPoint p;
          if (!SolveTurnTracker(shape, map, y, frame, v.uv, &p, &iterations)) {
            ++lost;  // the turn pair met, or the turn left the patch: repaired sideways
            continue;
          }
          ++solved;
          EXPECT_NEAR(p.y, y, kEdgeTolPx) << c.name;
          const Vec2 t = Vec2(-p.gradY.y(), p.gradY.x()).normalized();
          const double at = ThetaOfPoint(c.surface, c.camera, frame, p.uv).theta;
          const double ahead = std::remainder(ThetaOfPoint(c.surface, c.camera, frame, onLine(p.uv + kDelta * t, y)).theta - at, 2 * std::numbers::pi);
          const double behind = std::remainder(ThetaOfPoint(c.surface, c.camera, frame, onLine(p.uv - kDelta * t, y)).theta - at, 2 * std::numbers::pi);
          if (std::abs(ahead) <= kFlatRad || std::abs(behind) <= kFlatRad) {
            ++flat;  // θ'' vanishes too: a turn pair being born or meeting
            continue;
          }
          EXPECT_EQ(ahead > 0.0, behind > 0.0) << c.name << " line " << y << " at " << p.uv.transpose() << ": θ "
                                               << at << ", +δ " << ahead << ", -δ " << behind;
        }
      });
      scan.Crawl(y, &line);
    }
  }
  // (Lost trackers' iterations count too: a turn pair that has met takes the cap.)
  const double mean = static_cast<double>(iterations) / static_cast<double>(solved + lost);
  std::cout << solved << " turn trackers solved one line on (" << flat << " flat), " << lost << " lost; Newton iterations per tracker " << mean << "\n";
  EXPECT_GT(solved, 100);
  EXPECT_LT(flat, solved / 20);
  EXPECT_LE(mean, kMeanIterationsOneLine);
}

TEST(ThetaTracker, AdvancedChainsHaveTheCrawledChainsVertices) {
  // Between lines with no Y-scan event the chains advanced as trackers (their links
  // repaired by a crawl or filled by Newton) must have, in order, the same ends,
  // silhouettes and tabulated-angle vertices as chains crawled afresh on the same line, at the same places (the solves' tolerance, and the
  // advance's starting guesses' differences, are far below kSameVertexPx).
  constexpr double kSameVertexPx = 1e-5;
  long linesCompared = 0, linesAdvanced = 0, linesWithTurns = 0, turnLinesDiffering = 0, trackersWithoutExtrapolation = 0, iterationsWithout = 0;
  Counters total;
  for (const TrackerCase& c : Cases()) {
    // Not compared: the orthographic torus, whose crawled chains near the inner silhouette
    // have θ stepping back across 0 without a silhouette vertex (a fault of the crawl
    // there, not of the advance, still to be found).
    if (c.camera.orthographic) continue;
    for (bool extrapolate : {true, false}) {
      LineScan scan(c.surface, c.camera, 16);
      ChainSet advanced, crawled, next;
      bool have = false;
      long events = -1;
      for (double y = std::ceil(scan.Top()) + 0.5; y < c.camera.height; y += 1.0) {
        const long e = scan.AdvanceTo(y);
        scan.Crawl(y, &crawled);
        if (have && e == events) {
          ++linesCompared;
          if (scan.Advance(y, 1.0, advanced, extrapolate, &next)) {
            ++linesAdvanced;
            const std::vector<ThetaVertex> a = Trackers(next), b = Trackers(crawled);
            // Where a section has turn points, the crawl itself misses a turn pair that
            // fits inside one of its steps (θ turning back by less than half a table
            // step), which the trackers of the line before still follow, and a turn
            // pair born inside a link between lines is seen by neither until it reaches a
            // vertex: such lines may differ, and are counted.
            auto turns = [](const ChainSet& s) {
              return std::any_of(s.v.begin(), s.v.end(), [](const ThetaVertex& v) { return v.kind == ThetaVertex::Kind::Turn; });
            };
            if (turns(crawled) || turns(next)) {
              ++linesWithTurns;
              turnLinesDiffering += Unmatched(a, b, kSameVertexPx) + Unmatched(b, a, kSameVertexPx) > 0;
              std::swap(advanced, next);
              events = e;
              continue;
            }
            ASSERT_EQ(next.chains.size(), crawled.chains.size()) << c.name << " line " << y;
            auto dump = [](const ChainSet& s) {
              std::ostringstream o;
              for (const auto& ch : s.chains) {
                o << "\n  chain" << (ch.closed ? " (ring)" : "") << ":";
                for (const ThetaVertex& v : s.Of(ch)) o << " " << static_cast<int>(v.kind) << "/" << v.index << "@" << v.x;
              }
              return o.str();
            };
            // The crawl may start a ring at another of its silhouettes: compared as sets.
            EXPECT_EQ(Unmatched(a, b, kSameVertexPx) + Unmatched(b, a, kSameVertexPx), 0)
                << c.name << " line " << y << "\nadvanced:" << dump(next) << "\ncrawled:" << dump(crawled)
                << "\nline before:" << dump(advanced);
            // The order along each chain: the advanced chain's trackers are those of the
            // chain on the line before, in its order (a dropped tracker aside).
            std::swap(advanced, next);
            events = e;
            continue;
          }
        }
        advanced = crawled;
        have = true;
        events = e;
      }
      if (!extrapolate) {
        trackersWithoutExtrapolation += scan.counters[Counter::ThetaTrackers];
        iterationsWithout += scan.counters[Counter::ThetaTrackerIterations];
      } else {
        total[Counter::ThetaTrackers] += scan.counters[Counter::ThetaTrackers];
        total[Counter::ThetaTrackerIterations] += scan.counters[Counter::ThetaTrackerIterations];
        total[Counter::ThetaLinkRepairs] += scan.counters[Counter::ThetaLinkRepairs];
        total[Counter::ThetaLinksFilled] += scan.counters[Counter::ThetaLinksFilled];
        total[Counter::ThetaTrackersLost] += scan.counters[Counter::ThetaTrackersLost];
      }
    }
  }
  const double with = static_cast<double>(total[Counter::ThetaTrackerIterations]) / static_cast<double>(total[Counter::ThetaTrackers]);
  const double without = static_cast<double>(iterationsWithout) / static_cast<double>(trackersWithoutExtrapolation);
  std::cout << linesAdvanced << " of " << linesCompared << " quiet lines advanced (" << linesWithTurns
            << " with turn points, " << turnLinesDiffering << " of them differing); " << total[Counter::ThetaTrackers]
            << " trackers, Newton iterations per tracker " << with << " extrapolated, " << without
            << " from the last position; " << total[Counter::ThetaLinkRepairs] << " links repaired ("
            << total[Counter::ThetaLinksFilled] << " filled by Newton), " << total[Counter::ThetaTrackersLost]
            << " trackers lost\n";
  // Most quiet lines advance; extrapolation (§3.5) saves iterations.
  EXPECT_GT(linesAdvanced, linesCompared * 9 / 10);
  EXPECT_LT(linesWithTurns, linesAdvanced / 4);
  EXPECT_LT(turnLinesDiffering, linesWithTurns / 10);
  EXPECT_LT(with, without);
  // Links missing only tabulated vertices are filled by Newton (ThetaWalker::FillLink), and
  // the lines compared above hold them: the same vertices as the crawl's.
  EXPECT_GT(total[Counter::ThetaLinksFilled], 20);  // 54 of 745 repairs when measured
}

TEST(ThetaTracker, TiltTrackersRideStraightAlongYsGradientOntoTheLine) {
  // SolveTiltTracker: from a point a tenth of a pixel off line ys (a link's middle, a
  // start extrapolated from the lines before, are nearer) it lands on the line (within
  // kEdgeTolPx, in at most kMaxTiltIterations: y is smooth and the step is short) on the
  // straight (u,v) line through its start along y's gradient there, and its rate
  // d(u,v)/d(ys) is the derivative of its solution as ys moves: central differences over
  // kRateStepPx agree within kRateRelTol (their truncation, ~h^2/6 of the solution's
  // third derivative, reaches 2e-3 of the rate where y's gradient is 20 px per unit of
  // (u,v); the rate only predicts the next line's start). Not compared within
  // kNearSilhouetteJn of a silhouette, where y along that line folds over close by, nor
  // where y's gradient is under kMinGradPx per unit of (u,v) (near a maximum or saddle of
  // y: 1.9 px per unit on the teapot's body made 1.3e-2).
  constexpr double kOffLinePx = 0.1, kRateStepPx = 1e-2, kRateRelTol = 1e-2, kCollinearRel = 1e-9;
  constexpr double kNearSilhouetteJn = 0.2, kMinGradPx = 10.0;
  constexpr int kMaxTiltIterations = 4;
  AtRandomPoints(7, [&](const TrackerCase& c, const ThetaFrame&, const Vec2& uv, int) {
    const ScreenMap map(c.camera, c.surface.worldFromObject);
    bool compared = false;
    VisitShape(c.surface, [&](const auto& shape) {
      const LevelPoint start = EvalLevelPoint(shape, map, uv);
      if (!start.ok || std::abs(start.jn) < kNearSilhouetteJn || start.gradY.norm() < kMinGradPx) return;
      const double ys = start.y + kOffLinePx;
      LevelPoint p, lo, hi;
      Vec2 rate;
      std::int64_t iterations = 0, more = 0;
      if (!SolveTiltTracker(shape, map, ys, uv, &p, &iterations, &rate) ||
          !SolveTiltTracker(shape, map, ys - kRateStepPx, uv, &lo, &more) ||
          !SolveTiltTracker(shape, map, ys + kRateStepPx, uv, &hi, &more))
        return;  // left the patch
      compared = true;
      EXPECT_NEAR(p.y, ys, kEdgeTolPx) << c.name << " at " << uv.transpose();
      EXPECT_LE(iterations, kMaxTiltIterations) << c.name << " at " << uv.transpose();
      EXPECT_TRUE(p.second) << c.name;
      const Vec2 moved = p.uv - uv, g = start.gradY;
      EXPECT_LE(std::abs(moved.x() * g.y() - moved.y() * g.x()), kCollinearRel * moved.norm() * g.norm())
          << c.name << " at " << uv.transpose();
      const Vec2 fd = (hi.uv - lo.uv) / (2.0 * kRateStepPx);
      EXPECT_LE((rate - fd).norm(), kRateRelTol * fd.norm()) << c.name << " at " << uv.transpose();
    });
    return compared;
  });
}

TEST(ThetaTracker, RatesAlongTheLinesPredictTheNextLine) {
  // ThetaWalker::PredictedStart: a θ or turn tracker solved on the line before carries its
  // rate d(u,v)/d(ys) (RateAlongLines of its Jacobian), and the next line's start is the
  // quadratic through its last two positions with that slope (error O(dy³)) instead of
  // the line through them (O(dy²)). The same chains advanced both ways on every quiet line
  // (the rates struck out for the second) must end at the same vertices (but for a few
  // lines where a turn pair is born), the prediction
  // taking fewer Newton iterations: at most kMaxShare of the linear extrapolation's, at
  // line spacings of 1 px and of 1/4 px (aa 4's sample rows).
  constexpr double kSameVertexPx = 1e-5;
  constexpr double kMaxShare = 0.85;
  for (double dy : {1.0, 0.25}) {
    std::int64_t predicted = 0, linear = 0, trackers = 0, turnLines = 0, turnLinesDiffering = 0;
    for (const TrackerCase& c : Cases()) {
      LineScan scan(c.surface, c.camera, 16);
      ChainSet line, next, other, withoutRates;
      bool have = false;
      long events = -1;
      for (double y = std::ceil(scan.Top()) + 0.5; y < c.camera.height; y += dy) {
        const long e = scan.AdvanceTo(y);
        if (have && e == events) {
          withoutRates = line;
          std::fill(withoutRates.rate.begin(), withoutRates.rate.end(), Vec2(NAN, NAN));
          const auto count = [&] {
            return scan.counters[Counter::ThetaTrackerIterations] + scan.counters[Counter::ThetaTurnIterations];
          };
          const std::int64_t before = count();
          const bool a = scan.Advance(y, dy, line, true, &next);
          const std::int64_t mid = count();
          const bool b = scan.Advance(y, dy, withoutRates, true, &other);
          if (a && b) {
            predicted += mid - before;
            linear += count() - mid;
            trackers += static_cast<std::int64_t>(next.v.size());
            const std::vector<ThetaVertex> va = Trackers(next), vb = Trackers(other);
            const int unmatched = Unmatched(va, vb, kSameVertexPx) + Unmatched(vb, va, kSameVertexPx);
            // Where a turn pair is being born two turn points lie close, and the two
            // starts may each converge to a different one (each chain then skips the other
            // pair, whose excursion of θ is within a table step): such lines are counted.
            const auto turns = [](const std::vector<ThetaVertex>& v) {
              return std::any_of(v.begin(), v.end(), [](const ThetaVertex& x) { return x.kind == ThetaVertex::Kind::Turn; });
            };
            if (turns(va) || turns(vb)) {
              ++turnLines;
              turnLinesDiffering += unmatched > 0;
            } else {
              EXPECT_EQ(unmatched, 0) << c.name << " line " << y;
            }
          }
          if (a) {
            std::swap(line, next);
            events = e;
            continue;
          }
        }
        scan.Crawl(y, &line);
        have = true;
        events = e;
      }
    }
    std::cout << "line spacing " << dy << " px: " << trackers << " vertices advanced, Newton iterations "
              << predicted << " predicted from the rates, " << linear << " extrapolated linearly; " << turnLinesDiffering
              << " of " << turnLines << " lines with turn points differing\n";
    EXPECT_GT(trackers, 1000);
    EXPECT_LT(turnLinesDiffering, turnLines / 10);
    EXPECT_LE(static_cast<double>(predicted), kMaxShare * static_cast<double>(linear)) << "spacing " << dy;
  }
}

TEST(ThetaTracker, RowChainsTiltOnlyWhereASampleColumnLiesBetween) {
  // On every row (chords, not slabs) a link is interpolated only at the sample columns
  // strictly between its ends, so its normal's turn out of the scan plane needs a tilt
  // vertex only where a column lies between (ThetaWalker::TurnsPastStep). Crawled on the
  // same lines with one column at every pixel and with one column far off the image, the
  // chains have the same vertices apart from tilt vertices, and with the far column none;
  // for slabs (every link judged, the slab's triangles cover it whatever the columns) the
  // tilts stay. The surfaces' normals leave the scan plane by more than a step on many
  // lines at N 8: with unit columns there are tilts to lose.
  constexpr int kSteps = 8;
  const raster::SampleColumns far{-1e6, 1.0, 1};
  long rowTilts = 0, slabTilts = 0, slabTiltsFar = 0;
  for (const TrackerCase& c : Cases()) {
    LineScan scan(c.surface, c.camera, kSteps);
    ChainSet unit, none;
    for (double y = std::ceil(scan.Top()) + 0.5; y < c.camera.height; y += 1.0) {
      scan.AdvanceTo(y);
      const auto kinds = [](const ChainSet& set, bool tilts) {
        std::vector<ThetaVertex> out;
        for (const ThetaVertex& v : set.v)
          if ((v.kind == ThetaVertex::Kind::Tilt) == tilts) out.push_back(v);
        return out;
      };
      for (bool rows : {true, false}) {
        scan.SetRows(rows);
        scan.SetColumns({0.0, 1.0, c.camera.width});
        scan.Crawl(y, &unit);
        scan.SetColumns(far);
        scan.Crawl(y, &none);
        const std::vector<ThetaVertex> a = kinds(unit, false), b = kinds(none, false);
        ASSERT_EQ(a.size(), b.size()) << c.name << " line " << y << (rows ? " rows" : " slabs");
        for (std::size_t k = 0; k < a.size(); ++k) {
          EXPECT_EQ(a[k].kind, b[k].kind) << c.name << " line " << y;
          EXPECT_EQ(a[k].index, b[k].index) << c.name << " line " << y;
          EXPECT_NEAR(a[k].x, b[k].x, kLinkMatchPx) << c.name << " line " << y;
        }
        const long tiltsUnit = static_cast<long>(kinds(unit, true).size());
        const long tiltsFar = static_cast<long>(kinds(none, true).size());
        if (rows) {
          EXPECT_EQ(tiltsFar, 0) << c.name << " line " << y << ": a tilt vertex no sample column needs";
          rowTilts += tiltsUnit;
        } else {
          slabTilts += tiltsUnit;
          slabTiltsFar += tiltsFar;
        }
      }
    }
  }
  std::cout << "tilt vertices at N " << kSteps << ": rows " << rowTilts << " (none with no column between), slabs "
            << slabTilts << " with unit columns, " << slabTiltsFar << " with one far column\n";
  EXPECT_GT(rowTilts, 0);
  EXPECT_GT(slabTilts, 0);
  EXPECT_EQ(slabTiltsFar, slabTilts);
}

}  // namespace
}  // namespace patchscan
