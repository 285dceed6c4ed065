#include "xscan/exact_scan.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "patch/screen.h"
#include "patch/tessellate.h"

namespace patchscan {

// A surface being scanned: its Y scan, and what its X scan keeps from line to line.
struct ExactScan::Active {
  std::size_t index;
  double yMax = INFINITY;
  // θ and exact rows: above yFirst the surface has no tracker and none is born
  // (SurfaceScan::FirstY), so its rows are not visited; done once the scan has passed all
  // of it (SurfaceScan::Done): then it leaves the active set before its box's bottom. A
  // surface's box (its hull's) is often several times its height on the screen (a
  // subdivision face's ring of cage points): most of its rows have nothing of it.
  double yFirst = -INFINITY;
  bool done = false;
  // Whether the scan has left the surface behind on line y: below its box, or done.
  bool Passed(double y) const { return yMax < y || done; }
  // θ slabs: the surface's intervals so far lay wholly above yFirst (its scan still at its
  // set-up line, nothing of it walked).
  bool idle = false;
  std::unique_ptr<SurfaceScan> scan;
  std::size_t nextStationary = 0;  // for the trace: the next stationary point to pass
  // θ slabs: the chains on the interval's top line and on its bottom line (whether a walk
  // there failed or repaired a tracker miss), the trackers on the top line and on each of
  // its sample rows, and when it is taken row by row (byRows) each row's chains. θ rows:
  // the chains of the row before (line, at lineY) and of this row (next).
  ChainSet line, next;
  double lineY = 0.0;
  bool lineBroken = false, nextBroken = false;
  // Whether those lines were walked (an interval taken row by row walks neither), and
  // the trackers on a top line not walked yet.
  bool lineWalked = false, nextWalked = false;
  // Whether the surface's sections keep their shape (Calm) from the line or row before to
  // each sample row of the interval, and from its last row to the bottom line (m + 1
  // steps): a slab wants all, and taken row by row, a row is advanced from the one before
  // unless an event lies between them, as on θ rows. The chains of the last row of an
  // interval taken row by row (at carryY), when they may be advanced to the next
  // interval's top line or first row (carried).
  std::vector<char> stepCalm;
  bool byRows = false, carried = false;
  // θ slabs: a surface that was a slab through the interval before is advanced straight
  // from the top line to the bottom one (jumped), the scan's state on the top line saved
  // to come back to for its rows where the interval turns out not to be a slab.
  bool slabBefore = false, jumped = false;
  SurfaceScan::State topState;
  ChainSet carry;
  double carryY = 0.0;
  // θ rows: the vertices of the surface's chains that are solved by Newton (not their ends
  // and silhouettes: the Y scan's trackers) and the samples they covered, summed over its
  // rows so far, and whether it has gone over to the exact X scan for good (where its
  // chains hold more such vertices per sample than kThetaVerticesPerSampleMax).
  long thetaVertices = 0, thetaSamples = 0;
  bool exactX = false;
  // θ: whether the surface's object-to-world map is the identity (ThetaFrame::worldIsObject).
  bool worldIsObject = false;
  RowTrackers topTrackers;
  std::vector<RowTrackers> rowTrackers;
  std::vector<ChainSet> rows;
  std::vector<ChainPair> pairs;
  std::vector<ThetaVertex> ordered;
  // θ slabs: the chains of line and next with vertices added along their links' cubics
  // (RefineChains), which the slabs are zipped from, and whether they are those of the
  // chains line and next hold now.
  ChainSet lineFine, nextFine;
  bool lineRefined = false, nextRefined = false;
};

namespace {

// A texture footprint longer than the whole domain per pixel says nothing more.
constexpr double kMaxUvPerPixel = 1.0;

// θ slabs are not taken this near (pixels) a degenerate level set: dark pixels were
// measured up to 1.5 px from a cone point's row at 64 steps.
constexpr double kDegenerateSlabPx = 2.0;

// θ rows: the most Newton-solved chain vertices per sample covered at which a surface's
// chains still cost less than the exact X scan. A vertex advanced costs ~7.5 k
// instructions (θ, tilt and turn trackers, link checks and repairs, amortised fresh
// crawls), an exact sample's Newton solve ~3.0 k, a sample interpolated along a chord
// ~0.3 k (teapot 1024x768 aa 1, 64 steps, callgrind), and an exact walk of a row ~16 k
// more than a chain advanced (fitted over the teapot, teaspoon and cage): even at ~0.36
// on wide surfaces, higher on narrow ones. A surface over it, once its rows have covered
// kThetaShareMinSamples samples, goes over to the exact X scan for the rest of its rows
// (its samples then exact: no worse). Surfaces dense from the start are sent before
// (kThetaStepsPerPixelMax), so this judges the rest, on their top rows: counted whole
// renders (1024x768 aa 1: teapot θ16, 32, 64; teaspoon θ4, 32, 64; teacup θ64; cage θ32,
// 64) chose 0.7 of 0.5, 0.7, 0.9 and 1.2 (0.5 before the prediction): 0.9 was 1 % cheaper
// on the teapot at 16 steps, 0.4 % dearer at 64, and left the teacup at 16 steps one pixel
// whose normal is 28° off (θ's own, on the rim's inside; 2.2° at 0.7); 1.2 sent the
// teacup's and teapot's at 64 steps too late.
constexpr double kThetaVerticesPerSampleMax = 0.7;
constexpr long kThetaShareMinSamples = 64;

// θ rows: a surface whose normal turns through more θ steps per pixel of its extent on the
// screen than this (ThetaStepsPerPixel) takes the exact X scan from its first row, before
// its rows could tell: the judgement above waits for kThetaShareMinSamples, half of a
// small surface, and a surface's first rows (near its top) hold more vertices per sample
// than the rest. Its rows' vertices per sample came out 3 to 4 times it on the teapot,
// teacup and teaspoon, 1.5 to 2 times on the torus cage (1024x768, 64 steps). Counted
// whole renders at 1024x768 aa 1 (θ16, 32 and 64 on those four scenes) chose 0.1 of 0.08,
// 0.1 and 0.12: the largest with no θ render costlier than exact mode's.
constexpr double kThetaStepsPerPixelMax = 0.1;

// Rows this far above a surface's first line (SurfaceScan::FirstY) are skipped: LineFor
// moves a line by at most 64 of its 4e-6 px steps.
constexpr double kFirstYSlackPx = 1e-3;

// The θ steps a surface's normal turns through per pixel of its extent on the screen: N x
// (the largest angle between its world normals at (u, v) in {0.1, 0.5, 0.9}^2) / (2 pi x
// the diagonal of those points' screen box). Its rows' chains hold about that many
// vertices per sample, times a factor of the surface's shape. A point without a normal (a
// collapsed edge) is left out of the spread; NaN when the box is a point and no normal
// differs. The points' box, not the hull's: a subdivision face's hull (its ring of cage
// points) is several times the face. `normalFromObject`: the surface's world normals from
// dp/du x dp/dv (SurfaceScan::NormalFromObject).
double ThetaStepsPerPixel(const Surface& surface, const ScreenMap& map, const Mat3& normalFromObject, int steps) {
  static constexpr double kAt[3] = {0.1, 0.5, 0.9};
  std::array<Vec3, 9> n;
  Vec2 lo(INFINITY, INFINITY), hi(-INFINITY, -INFINITY);
  VisitShape(surface, [&](const auto& shape) {
    for (std::size_t k = 0; k < n.size(); ++k) {
      SurfaceDerivs d;
      shape.Evaluate(kAt[k % 3], kAt[k / 3], DerivOrder::First, &d);
      n[k] = (normalFromObject * d.dpdu.cross(d.dpdv)).normalized();
      ScreenDerivs sd;
      map.FromObject(d, DerivOrder::Position, &sd);
      lo = lo.cwiseMin(sd.p.head<2>());
      hi = hi.cwiseMax(sd.p.head<2>());
    }
  });
  // A zero normal (Eigen's normalized() leaves it zero) would add a right angle.
  const auto hasNormal = [](const Vec3& v) { return v.squaredNorm() > 0.0; };
  double spread = 0.0;
  for (std::size_t i = 0; i < n.size(); ++i)
    for (std::size_t j = i + 1; j < n.size(); ++j)
      if (hasNormal(n[i]) && hasNormal(n[j]))
        spread = std::max(spread, std::acos(std::clamp(n[i].dot(n[j]), -1.0, 1.0)));
  return steps * spread / (2.0 * std::numbers::pi * (hi - lo).norm());
}

Vec2 ClampLength(const Vec2& v, double len) {
  const double n = v.norm();
  return std::isfinite(n) ? (n > len ? Vec2(v * (len / n)) : v) : Vec2(len, 0.0);
}

}  // namespace

raster::Fragment FragmentAt(const LevelPoint& p, const Surface& surface,
                            const Mat3& normalFromObject, std::uint32_t surfaceId) {
  const SurfaceDerivs& o = p.object;
  raster::Fragment f;
  f.w = p.w;
  f.position = surface.worldFromObject * o.p;
  const Vec3 n = o.dpdu.cross(o.dpdv);
  // As WorldNormal: at a collapsed edge the normal is its limit from inside.
  if (n.norm() > kCollapsedRel * o.dpdu.norm() * o.dpdv.norm() && n.norm() > 0.0)
    f.normal = (normalFromObject * n).normalized();
  else
    f.normal = WorldNormal(surface, p.uv.x(), p.uv.y());
  // The texture coordinates and, through the inverse of the screen Jacobian
  // [x_u x_v; y_u y_v], their change per pixel in x and y.
  const TexCoords t = TextureCoordsAt(surface, p.uv.x(), p.uv.y());
  const Vec2 duvdx = p.UvPerPixelAlongRow(), duvdy = Vec2(-p.gradX.y(), p.gradX.x()) / p.j;
  f.uv = t.st;
  f.duvdx = ClampLength(t.dstdu * duvdx.x() + t.dstdv * duvdx.y(), kMaxUvPerPixel);
  f.duvdy = ClampLength(t.dstdu * duvdy.x() + t.dstdv * duvdy.y(), kMaxUvPerPixel);
  f.surfaceId = surfaceId;
  return f;
}

std::vector<ScanEntry> ScanOrder(std::span<const Surface> surfaces, const Camera& camera) {
  std::vector<ScanEntry> order;
  order.reserve(surfaces.size());
  for (std::size_t k = 0; k < surfaces.size(); ++k) {
    const ScreenMap map(camera, surfaces[k].worldFromObject);
    // Wholly nearer than the hither plane (or behind the eye): never set up.
    if (WhollyBeforeHither(surfaces[k], map, camera.hither)) continue;
    const auto box = ScreenBounds(surfaces[k], map);
    // A surface reaching behind the eye has no finite screen box: active throughout.
    if (box) {
      const auto d = box->Diagonal();
      order.push_back({k, box->lo.y(), box->hi.y(), d.x() * d.y()});
    } else {
      order.push_back({k, -INFINITY, INFINITY, INFINITY});
    }
  }
  std::stable_sort(order.begin(), order.end(), [](const ScanEntry& a, const ScanEntry& b) { return a.yMin < b.yMin; });
  return order;
}

ExactScan::ExactScan(std::span<const Surface> surfaces, const Camera& camera, ExactScanOptions options)
    : ExactScan(surfaces, camera, options, ScanOrder(surfaces, camera)) {
  counters_[Counter::Surfaces] = static_cast<std::int64_t>(surfaces.size());
}

ExactScan::ExactScan(std::span<const Surface> surfaces, const Camera& camera, ExactScanOptions options,
                     std::vector<ScanEntry> share)
    : surfaces_(surfaces), camera_(camera), eye_(EyePoint(camera)), right_(ViewRight(camera)), forward_(ViewForward(camera)), options_(options),
      pending_(std::move(share)), thetaTable_(options.thetaSteps) {
  counters_[Counter::Surfaces] = static_cast<std::int64_t>(pending_.size());
  for (int i = 0; i < options_.thetaSteps; ++i) {
    const double a = 2.0 * std::numbers::pi * i / options_.thetaSteps;
    angles_.emplace_back(std::cos(a), std::sin(a));
  }
}

ExactScan::~ExactScan() = default;

void ExactScan::Activate(const ScanEntry& entry, double y, double spacing) {
  const std::size_t index = entry.index;
  auto a = std::make_unique<Active>();
  a->index = index;
  a->yMax = entry.yMax;
  a->scan = std::make_unique<SurfaceScan>(surfaces_[index], camera_, options_.extrapolate, counters_);
  a->scan->StartAt(y, spacing);
  a->worldIsObject = surfaces_[index].worldFromObject.matrix().isIdentity(0.0);
  a->yFirst = a->scan->FirstY();
  if (options_.thetaSteps > 0 && options_.slabRows == 0 && options_.exactWhereCheaper &&
      ThetaStepsPerPixel(surfaces_[index], a->scan->Map(), a->scan->NormalFromObject(), options_.thetaSteps) >
          kThetaStepsPerPixelMax) {
    a->exactX = true;
    ++counters_[Counter::ThetaExactSurfaces];
  }
  active_.push_back(std::move(a));
  counters_.Raise(Counter::MaxActiveSurfaces, static_cast<std::int64_t>(active_.size()));
}

void ExactScan::UpdateActive(double yLo, double yHi, double spacing) {
  std::erase_if(active_, [&](const std::unique_ptr<Active>& a) { return a->Passed(yLo); });
  for (; nextPending_ < pending_.size() && pending_[nextPending_].yMin <= yHi; ++nextPending_)
    if (pending_[nextPending_].yMax >= yLo) Activate(pending_[nextPending_], yLo, spacing);
}

// Every line a surface's scan takes is SurfaceScan::LineFor of the row's y: the trackers
// and the walks of one row are on the same line, away from degenerate level sets.
void ExactScan::AdvanceTo(Active& a, double y) {
  a.scan->AdvanceTo(a.scan->LineFor(y));
  if (trace_) TraceTrackers(a, y);
}

template <class F>
void ExactScan::VisitTheta(Active& a, double y, const raster::SampleColumns& columns, F&& f) {
  const Surface& surface = surfaces_[a.index];
  VisitShape(surface, [&](const auto& shape) {
    using ShapeT = std::decay_t<decltype(shape)>;
    const ThetaFrame frame{eye_, right_, forward_, camera_.orthographic, &surface.worldFromObject, angles_,
                           a.worldIsObject};
    ThetaWalker<ShapeT> walker(shape, a.scan->Map(), a.scan->LineFor(y), columns, &counters_, &walkEvents_, thetaTable_, frame);
    walker.SetChainSink(chainSink_);
    walker.SetNormalSlopes(true);
    walker.SetRowChords(options_.slabRows == 0);
    walker.SetTrim(a.scan->Trim(), &trimScratch_);
    walker.SetTrimPieces(&trimPiece_, &trimFirst_);
    f(walker, [&](const LevelPoint& p) {
      return FragmentAt(p, surface, a.scan->NormalFromObject(), static_cast<std::uint32_t>(a.index));
    });
  });
}

void ExactScan::FinishWalk(Active& a) {
  // Silhouettes the walk found without a tracker are tracked from the next row on.
  for (const Vec2& uv : walkEvents_.untrackedSilhouettes) a.scan->Adopt(uv);
  if (trace_) TraceWalk(a);
}

template <class Take>
void ExactScan::WalkSurface(Active& a, double y, const RowTrackers& t, const raster::SampleColumns& columns,
                            raster::FragmentRow& out, Take&& take) {
  walkEvents_.Clear();
  if (options_.thetaSteps > 0 && !a.exactX) {
    VisitTheta(a, y, columns, [&](auto& walker, auto&& make) {
      walker.WalkAll(t, &edgeUsed_, &silUsed_, &chain_, make, take);
    });
  } else {
    const Surface& surface = surfaces_[a.index];
    VisitShape(surface, [&](const auto& shape) {
      LevelWalker walker(shape, a.scan->Map(), a.scan->LineFor(y), columns, &counters_, &walkEvents_);
      walker.SetTrim(a.scan->Trim(), &trimScratch_);
      walker.WalkAll(t, &edgeUsed_, &silUsed_, [&](int column, const LevelPoint& p) {
        ++counters_[Counter::Fragments];
        if (out.Hidden(column, p.w)) return;  // not worth its normal and texture coordinates
        out.Add(column, FragmentAt(p, surface, a.scan->NormalFromObject(), static_cast<std::uint32_t>(a.index)));
      });
    });
  }
  FinishWalk(a);
}

bool ExactScan::AdvanceSurface(Active& a, const ChainSet& from, double yFrom, double y, const RowTrackers& t,
                               ChainSet* to, const raster::SampleColumns& columns) {
  walkEvents_.Clear();
  bool ok = false;
  VisitTheta(a, y, columns, [&](auto& walker, auto&& make) {
    const double dy = a.scan->LineFor(y) - a.scan->LineFor(yFrom);  // the walker's lines
    ok = walker.Advance(from, dy, t, options_.extrapolate, &edgeUsed_, &silUsed_, &chain_, to, make);
  });
  FinishWalk(a);
  return ok;
}

bool ExactScan::AdvanceOrWalk(Active& a, const ChainSet* before, double yBefore, double y, const RowTrackers& t,
                              ChainSet* set, const raster::SampleColumns& columns, raster::FragmentRow& out) {
  bool advanced = false;
  if (before) {
    advanced = AdvanceSurface(a, *before, yBefore, y, t, set, columns) && !WalkBroken();
    ++counters_[advanced ? Counter::ThetaRowsAdvanced : Counter::ThetaLineRepairs];
  }
  if (!advanced) {
    set->Clear();
    WalkSurface(a, y, t, columns, out, [set](std::span<const ThetaVertex> chain, bool closed) { set->Add(chain, closed); });
  }
  return advanced;
}

bool ExactScan::ScanRow(double y, const raster::SampleColumns& columns, raster::FragmentRow& out) {
  ++counters_[Counter::SampleRows];
  if (options_.thetaSteps > 0 && options_.slabRows > 0) return ScanRowSlabs(y, columns, out);
  UpdateActive(y, y, columns.dx);

  for (const auto& ap : active_) {
    Active& a = *ap;
    // Nothing of the surface on this row (LineFor moves a line down by far less than the
    // slack), or nothing left of it: not visited.
    if (y < a.yFirst - kFirstYSlackPx) continue;
    const long events = a.scan->Events();
    AdvanceTo(a, y);
    if (a.scan->Done()) {
      a.done = true;
      continue;
    }
    if (options_.thetaSteps == 0 || a.exactX) {
      WalkSurface(a, y, a.scan->Trackers(), columns, out, [](std::span<const ThetaVertex>, bool) {});
      continue;
    }
    // θ rows: between two rows with no event of the Y scan the chains of the row before
    // are advanced as θ trackers (§4.1), as slab lines are; a surface's first row, a row
    // after an event and a chain that cannot be advanced are crawled afresh. Each surface
    // decides alone (its chains are its own), so a partition of the scene changes nothing.
    const bool calm = a.lineWalked && !a.lineBroken && Calm(a, events, a.lineY, y);
    const bool advanced = AdvanceOrWalk(a, calm ? &a.line : nullptr, a.lineY, y, a.scan->Trackers(), &a.next, columns, out);
    long samples = 0;
    for (const ChainSet::Chain& c : a.next.chains) samples += EmitThetaChain(a.next.Of(c), columns, camera_.orthographic, out);
    counters_[Counter::Fragments] += samples;
    // The exact X scan from the next row on where the chains cost more (each surface
    // decides alone, from its own rows: a partition of the scene changes nothing).
    a.thetaVertices += std::count_if(a.next.v.begin(), a.next.v.end(), [](const ThetaVertex& v) {
      return v.kind != ThetaVertex::Kind::End && v.kind != ThetaVertex::Kind::Silhouette;
    });
    a.thetaSamples += samples;
    if (options_.exactWhereCheaper && a.thetaSamples >= kThetaShareMinSamples &&
        static_cast<double>(a.thetaVertices) > kThetaVerticesPerSampleMax * static_cast<double>(a.thetaSamples)) {
      a.exactX = true;
      ++counters_[Counter::ThetaExactSurfaces];
      ++counters_[Counter::ThetaExactJudged];
    }
    std::swap(a.line, a.next);
    a.lineBroken = !advanced && WalkBroken();
    a.lineWalked = true;
    a.lineY = y;
  }
  return true;
}

bool ExactScan::Calm(const Active& a, long eventsBefore, double yTop, double yBottom) const {
  // A trimmed surface's chains end on trim crossings the θ trackers do not advance (and
  // slabs would cut its trim curves by chords).
  if (a.scan->Events() != eventsBefore || a.scan->Trim()) return false;
  for (const ScreenStationary& st : a.scan->StationaryOnScreen())
    if (st.p.y() > yTop && st.p.y() <= yBottom) return false;
  // A degenerate level set (a cone point, a pole, an edge seen edge-on) changes the
  // sections as an event does, and near it they bend as sharply as the line is close to
  // it: slabs zipped to such chains made slivers whose normals blend both sides of a cone
  // point (dark pixels on the rows beside it). Lines within kDegenerateSlabPx of one are
  // crawled afresh and their rows sampled one by one.
  for (const auto& [lo, hi] : a.scan->DegenerateRanges())
    if (hi + kDegenerateSlabPx >= yTop && lo - kDegenerateSlabPx <= yBottom) return false;
  return true;
}

bool ExactScan::BeginsInterval(double y, const raster::SampleColumns& columns) const {
  const long j = RowIndex(y, columns);
  return j < intervalStart_ || j >= intervalEnd_;
}

void ExactScan::WalkLine(Active& a, double y, const RowTrackers& t, const raster::SampleColumns& columns,
                         raster::FragmentRow& out, ChainSet* set, bool* broken) {
  ++counters_[Counter::SlabLines];
  set->Clear();
  WalkSurface(a, y, t, columns, out, [&](std::span<const ThetaVertex> chain, bool closed) { set->Add(chain, closed); });
  *broken = WalkBroken();
}

std::pair<double, double> ExactScan::IntervalLines(const raster::SampleColumns& columns) const {
  // The lattice is square: sample row j lies at y = x0 + j dy, and the lines half a row
  // above the interval's first row and below its last.
  const double dy = columns.dx;
  const double yTop = columns.x0 + (static_cast<double>(intervalStart_) - 0.5) * dy;
  return {yTop, yTop + options_.slabRows * dy};
}

void ExactScan::PrepareInterval(double y, const raster::SampleColumns& columns, raster::FragmentRow& out) {
  const long j = RowIndex(y, columns);
  const int m = options_.slabRows;
  intervalStart_ = j;
  intervalEnd_ = j + m;
  const double dy = columns.dx;
  const auto lines = IntervalLines(columns);
  const double yTop = lines.first, yBottom = lines.second;
  const std::size_t firstNew = [&] {
    std::erase_if(active_, [&](const std::unique_ptr<Active>& a) { return a->Passed(yTop); });
    return active_.size();
  }();
  UpdateActive(yTop, yBottom, dy);
  // An interval wholly above a surface's first line has nothing of it (as rows skip such
  // rows): the surface is not advanced or walked there.
  const auto above = [&](const Active& a) { return yBottom < a.yFirst - kFirstYSlackPx; };
  for (std::size_t k = firstNew; k < active_.size(); ++k) {
    Active& a = *active_[k];
    a.idle = above(a);
    if (a.idle) continue;
    AdvanceTo(a, yTop);
    WalkLine(a, yTop, a.scan->Trackers(), columns, out, &a.line, &a.lineBroken);
    a.lineWalked = true;
  }
  // The trackers on the top line and on the bottom one, and on every sample row of the
  // interval with whether the surface has an event of the Y scan between each of them and
  // the one before: a surface that was a slab through the interval before is advanced
  // straight to the bottom line, and its rows only if that step is not calm (else all
  // its steps are: their events add up, and its stationary points and degenerate ranges
  // each lie in or touch one of them).
  for (const auto& ap : active_) {
    Active& a = *ap;
    if (a.idle) {
      if (above(a)) continue;
      // Its first interval: the scan to its top line (nothing of it lies above), which is
      // walked when the surface is taken (WalkTopLine).
      a.idle = false;
      AdvanceTo(a, yTop);
    }
    a.topTrackers = a.scan->Trackers();
    a.stepCalm.resize(static_cast<std::size_t>(m) + 1);
    a.jumped = false;
    if (a.slabBefore && !a.scan->Trim()) {  // not a surface set up here: none was a slab
      a.scan->Save(&a.topState);
      const long before = a.scan->Events();
      AdvanceTo(a, yBottom);
      if (Calm(a, before, yTop, yBottom)) {
        std::fill(a.stepCalm.begin(), a.stepCalm.end(), char{1});
        a.jumped = true;
        continue;
      }
      a.scan->Restore(a.topState);
    }
    AdvanceRows(a, columns);
  }
}

void ExactScan::AdvanceRows(Active& a, const raster::SampleColumns& columns) {
  const int m = options_.slabRows;
  const auto lines = IntervalLines(columns);
  const double yTop = lines.first, yBottom = lines.second;
  a.rowTrackers.resize(static_cast<std::size_t>(m));
  long before = a.scan->Events();
  double yBefore = yTop;
  for (int r = 0; r <= m; ++r) {
    const double yr = r < m ? RowY(columns, r) : yBottom;
    AdvanceTo(a, yr);
    if (r < m) a.rowTrackers[static_cast<std::size_t>(r)] = a.scan->Trackers();
    a.stepCalm[static_cast<std::size_t>(r)] = Calm(a, before, yBefore, yr);
    before = a.scan->Events(), yBefore = yr;
  }
}

bool ExactScan::AllCalm(const Active& a) {
  return std::all_of(a.stepCalm.begin(), a.stepCalm.end(), [](char c) { return c != 0; });
}

bool ExactScan::PairSurface(Active& a, const raster::SampleColumns& columns, raster::FragmentRow& out) {
  // An event of the surface's Y scan in the interval: rows, and neither line's chains
  // walked (the next interval walks its top line only if it may be a slab). Calm through
  // the interval is calm through each of its steps: their events add up, and its
  // stationary points and degenerate ranges each lie in or touch one of them.
  if (!AllCalm(a)) {
    ++counters_[Counter::EventIntervals];
    a.nextWalked = false;
    return false;
  }
  const auto lines = IntervalLines(columns);
  const double yTop = lines.first, yBottom = lines.second;
  if (!a.lineWalked) {
    // The interval before was taken row by row: its last row's chains, advanced.
    if (a.carried && AdvanceSurface(a, a.carry, a.carryY, yTop, a.topTrackers, &a.line, columns) && !WalkBroken()) {
      ++counters_[Counter::SlabLines];
      a.lineBroken = false;
    } else {
      WalkLine(a, yTop, a.topTrackers, columns, out, &a.line, &a.lineBroken);
    }
    a.lineWalked = true;
    a.lineRefined = false;
  }
  a.nextWalked = true;
  // The chains of the top line advanced to the bottom one as θ trackers (§4.1); a chain
  // that cannot be, or a broken top line, has the bottom line crawled afresh.
  const bool advance = !a.lineBroken;
  if (advance && AdvanceSurface(a, a.line, yTop, yBottom, a.scan->Trackers(), &a.next, columns)) {
    ++counters_[Counter::SlabLines];
    a.nextBroken = WalkBroken();
  } else {
    if (advance) ++counters_[Counter::ThetaLineRepairs];
    WalkLine(a, yBottom, a.scan->Trackers(), columns, out, &a.next, &a.nextBroken);
  }
  if (!advance || a.nextBroken) return false;
  if (!a.lineRefined) RefineChains(a.line, columns, camera_.orthographic, &a.lineFine);
  RefineChains(a.next, columns, camera_.orthographic, &a.nextFine);
  a.lineRefined = a.nextRefined = true;
  return PairChains(a.lineFine, a.nextFine, &a.pairs, &a.ordered);
}

void ExactScan::SlabSurface(Active& a, const raster::SampleColumns& columns, raster::FragmentRow& out) {
  const auto lines = IntervalLines(columns);
  const SlabFrame frame{lines.first, lines.second, camera_.orthographic, eye_, forward_};
  const auto id = static_cast<std::uint32_t>(a.index);
  for (const ChainPair& p : a.pairs)
    ZipSlab(a.lineFine.Of(a.lineFine.chains[p.top]),
            std::span<const ThetaVertex>(a.ordered.data() + p.begin, p.end - p.begin), frame, &anchorsTop_,
            &anchorsBottom_, [&](const raster::RasterVertex& u, const raster::RasterVertex& v, const raster::RasterVertex& w) {
              ++counters_[Counter::SlabTriangles];
              out.AddTriangle(u, v, w, id);
            });
}

void ExactScan::RowSurface(Active& a, const raster::SampleColumns& columns, raster::FragmentRow& out) {
  const int m = options_.slabRows;
  const auto lines = IntervalLines(columns);
  const double yTop = lines.first, yBottom = lines.second;
  // Each row's chains are advanced from the line or row before as θ trackers (§4.1), as
  // θ rows are, unless the surface has an event between them; those, and a row whose
  // chains cannot be advanced, are crawled afresh.
  a.rows.resize(static_cast<std::size_t>(m));
  const ChainSet* before = nullptr;
  double yBefore = yTop;
  if (a.lineWalked && !a.lineBroken) before = &a.line;
  else if (a.carried) before = &a.carry, yBefore = a.carryY;
  LineEnds(a, a.topTrackers, &topEnds_);
  LineEnds(a, a.scan->Trackers(), &bottomEnds_);
  for (int r = 0; r < m; ++r) {
    ChainSet& set = a.rows[static_cast<std::size_t>(r)];
    const RowTrackers& t = a.rowTrackers[static_cast<std::size_t>(r)];
    const bool calm = a.stepCalm[static_cast<std::size_t>(r)];
    const bool advanced = AdvanceOrWalk(a, calm ? before : nullptr, yBefore, RowY(columns, r), t, &set, columns, out);
    before = advanced || !WalkBroken() ? &set : nullptr;
    yBefore = RowY(columns, r);
    SnapEnds((RowY(columns, r) - yTop) / (yBottom - yTop), t, &set);
  }
  if (!a.stepCalm[static_cast<std::size_t>(m)]) before = nullptr;
  a.carried = before != nullptr;
  if (a.carried) a.carry = *before, a.carryY = yBefore;  // within its capacity once warm
}

void ExactScan::LineEnds(const Active& a, const RowTrackers& t, std::vector<LineEnd>* ends) const {
  ends->clear();
  for (const Vec2& uv : t.edgePoints) {
    ScreenDerivs d;
    EvaluateScreen(surfaces_[a.index], a.scan->Map(), uv.x(), uv.y(), DerivOrder::Position, &d);
    if (d.w > 0.0) ends->push_back({uv, SlabEndX(d.p.x())});
  }
}

void ExactScan::SnapEnds(double t, const RowTrackers& row, ChainSet* set) const {
  // The boundary's points on the two lines nearest the end along its side of the domain,
  // one at or before it and one at or after it, where the side has as many on both lines
  // as on the row (no crossing born or gone in the interval: a fold, a corner).
  const auto along = [](const Vec2& uv, int side) { return side % 2 == 0 ? uv.x() : uv.y(); };
  const auto onSide = [](int side, const auto& points, auto uvOf) {
    return std::count_if(points.begin(), points.end(), [&](const auto& p) { return DomainSide(uvOf(p)) == side; });
  };
  const auto uvOfEnd = [](const LineEnd& e) { return e.uv; };
  const auto uvOfPoint = [](const Vec2& uv) { return uv; };
  for (const ChainSet::Chain& c : set->chains) {
    if (c.end - c.begin < 2) continue;
    for (const std::uint32_t i : {c.begin, c.end - 1}) {
      ThetaVertex& v = set->v[i];
      if (v.kind != ThetaVertex::Kind::End) continue;
      const int side = DomainSide(v.uv);
      const auto count = onSide(side, row.edgePoints, uvOfPoint);
      if (onSide(side, topEnds_, uvOfEnd) != count || onSide(side, bottomEnds_, uvOfEnd) != count) continue;
      const double s = along(v.uv, side);
      const auto nearest = [&](const std::vector<LineEnd>& ends) -> const LineEnd* {
        const LineEnd* best = nullptr;
        for (const LineEnd& e : ends)
          if (DomainSide(e.uv) == side && (!best || std::abs(along(e.uv, side) - s) < std::abs(along(best->uv, side) - s)))
            best = &e;
        return best;
      };
      const LineEnd *top = nearest(topEnds_), *bottom = nearest(bottomEnds_);
      if (!top || !bottom) continue;
      const double st = along(top->uv, side), sb = along(bottom->uv, side);
      if ((s - st) * (sb - s) < -kSnapAlongSlack) continue;  // not between: another crossing
      const double x = top->x + t * (bottom->x - top->x);
      if (!(std::abs(x - v.x) <= kSnapMaxPx)) continue;
      // Vertices of the chain the end passes on its way come with it (else the chord from
      // it would turn back and cover their columns twice): the surface begins at x.
      const int inward = i == c.begin ? 1 : -1;
      const auto first = static_cast<std::int64_t>(c.begin), last = static_cast<std::int64_t>(c.end) - 1;
      for (auto k = static_cast<std::int64_t>(i) + inward; k >= first && k <= last; k += inward) {
        ThetaVertex& passed = set->v[static_cast<std::size_t>(k)];
        if (passed.kind == ThetaVertex::Kind::End || (x - passed.x) * (v.x - passed.x) > 0.0) break;
        passed.x = x;
      }
      v.x = x;
    }
  }
}

void ExactScan::ScanInterval(double y, const raster::SampleColumns& columns, raster::FragmentRow& out) {
  PrepareInterval(y, columns, out);
  // Each surface decides alone: a slab where its Y scan has no event in the interval and
  // its lines' chains pair up, else its rows' chains, ending on its boundary where a slab
  // beside it would (SnapEnds): so a partition of the scene changes nothing.
  for (const auto& ap : active_) {
    Active& a = *ap;
    if (a.idle) continue;  // never taken yet: not by rows, no line walked, nothing carried
    a.byRows = !PairSurface(a, columns, out);
    if (a.byRows && a.jumped) {
      // Calm to the bottom line, but its chains there do not pair: back to the top line,
      // and its rows advanced one by one. The bottom line's chains walked from the jump's
      // trackers stay (its trackers converge to the same crossings), unless a row finds an
      // event the jump stepped over.
      a.scan->Restore(a.topState);
      AdvanceRows(a, columns);
      if (!AllCalm(a)) {
        ++counters_[Counter::EventIntervals];
        a.nextWalked = false;
      }
    }
    a.slabBefore = !a.byRows;
    if (a.byRows) {
      ++counters_[Counter::RowIntervals];
      RowSurface(a, columns, out);
    } else {
      ++counters_[Counter::SlabIntervals];
      a.carried = false;
      SlabSurface(a, columns, out);
    }
    std::swap(a.line, a.next);
    std::swap(a.lineFine, a.nextFine);
    a.lineRefined = a.nextRefined;
    a.nextRefined = false;
    a.lineBroken = a.nextBroken;
    a.lineWalked = a.nextWalked;
    // Passed wholly (its rows here still to be emitted): dropped at the next interval.
    a.done = a.scan->Done();
  }
}

bool ExactScan::ScanRowSlabs(double y, const raster::SampleColumns& columns, raster::FragmentRow& out) {
  const long j = RowIndex(y, columns);
  if (BeginsInterval(y, columns)) ScanInterval(y, columns, out);
  const auto r = static_cast<std::size_t>(j - intervalStart_);
  for (const auto& ap : active_)
    if (ap->byRows && r < ap->rows.size())
      for (const ChainSet::Chain& c : ap->rows[r].chains)
        counters_[Counter::Fragments] += EmitThetaChain(ap->rows[r].Of(c), columns, camera_.orthographic, out);
  return true;
}

void ExactScan::TraceMark(const Active& a, TraceKind kind, const Vec2& uv) {
  ScreenDerivs d;
  EvaluateScreen(surfaces_[a.index], a.scan->Map(), uv.x(), uv.y(), DerivOrder::Position, &d);
  if (d.w > 0.0) trace_->Mark(kind, d.p.x(), d.p.y());
}

void ExactScan::TraceTrackers(Active& a, double y) {
  const RowTrackers& t = a.scan->Trackers();
  for (const Vec2& uv : t.edgePoints) TraceMark(a, TraceKind::EdgeTracker, uv);
  for (const Vec2& uv : t.silhouettePoints) TraceMark(a, TraceKind::SilhouetteTracker, uv);
  const auto& stationary = a.scan->StationaryOnScreen();
  for (; a.nextStationary < stationary.size() && stationary[a.nextStationary].p.y() <= y; ++a.nextStationary) {
    const ScreenStationary& st = stationary[a.nextStationary];
    trace_->Mark(st.saddle ? TraceKind::Saddle : TraceKind::Maximum, st.p.x(), st.p.y());
  }
  for (const Vec2& uv : a.scan->Edges().Folds()) TraceMark(a, TraceKind::Fold, uv);
  for (const Vec2& uv : a.scan->Silhouettes().Births()) TraceMark(a, TraceKind::Birth, uv);
  for (const Vec2& uv : a.scan->Edges().Deaths()) TraceMark(a, TraceKind::Death, uv);
  for (const Vec2& uv : a.scan->Silhouettes().Deaths()) TraceMark(a, TraceKind::Death, uv);
}

void ExactScan::TraceWalk(Active& a) {
  for (const Vec2& uv : walkEvents_.repairs) TraceMark(a, TraceKind::Repair, uv);
  for (const Vec2& uv : walkEvents_.failures) TraceMark(a, TraceKind::Failure, uv);
}

}  // namespace patchscan
