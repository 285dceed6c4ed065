#include "xscan/exact_scan.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "core/check.h"
#include "patch/screen.h"
#include "patch/tessellate.h"
#include "xscan/exact_scan_active.h"

namespace patchscan {

namespace {

// A texture footprint longer than the whole domain per pixel says nothing more.
constexpr double kMaxUvPerPixel = 1.0;

// θ slabs are not taken this near (pixels) a degenerate level set: dark pixels were
// measured up to 1.5 px from a cone point's row at 64 steps.
constexpr double kDegenerateSlabPx = 2.0;

// θ rows: the most Newton-solved chain vertices per sample covered at which a surface's
// chains still cost less than the exact X scan (a vertex advanced costs ~2.5 exact
// samples' Newton solves). A surface over it, once its rows have covered
// kThetaShareMinSamples samples, takes the exact X scan for the rest of its rows. How the
// value was chosen: docs/tuning.md.
constexpr double kThetaVerticesPerSampleMax = 0.7;
constexpr long kThetaShareMinSamples = 64;

// θ rows: a surface whose normal turns through more θ steps per pixel of its extent on the
// screen than this (ThetaStepsPerPixel) takes the exact X scan from its first row, before
// its rows could tell (the judgement above waits for kThetaShareMinSamples). How the value
// was chosen: docs/tuning.md.
constexpr double kThetaStepsPerPixelMax = 0.1;


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
  // As WorldNormal: at a collapsed edge the normal is its limit from inside.
  if (!NormalVanishes(o.dpdu, o.dpdv))
    f.normal = (normalFromObject * o.dpdu.cross(o.dpdv)).normalized();
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

std::unique_ptr<ExactScan::Active> ExactScan::SetUp(const ScanEntry& entry, double y, double spacing,
                                                   Counters& counters) const {
  auto a = std::make_unique<Active>();
  a->index = entry.index;
  a->yMax = entry.yMax;
  a->scan = std::make_unique<SurfaceScan>(surfaces_[entry.index], camera_, options_.extrapolate, counters);
  a->scan->StartAt(y, spacing);
  a->worldIsObject = surfaces_[entry.index].worldFromObject.matrix().isIdentity(0.0);
  a->yFirst = a->scan->FirstY();
  return a;
}

void ExactScan::Activate(const ScanEntry& entry, double y, double spacing) {
  const std::size_t index = entry.index;
  std::unique_ptr<Active> a;
  // Set up ahead (PrepareBatch), on this very row.
  if (nextReady_ < ready_.size() && ready_[nextReady_].index == static_cast<std::size_t>(&entry - pending_.data()))
    a = std::move(ready_[nextReady_++].a);
  else
    a = SetUp(entry, y, spacing, counters_);
  if (options_.thetaSteps > 0 && options_.slabRows == 0 && options_.exactWhereCheaper &&
      ThetaStepsPerPixel(surfaces_[index], a->scan->Map(), a->scan->NormalFromObject(), options_.thetaSteps) >
          kThetaStepsPerPixelMax) {
    a->exactX = true;
    ++counters_[Counter::ThetaExactSurfaces];
  }
  active_.push_back(std::move(a));
  counters_.Raise(Counter::MaxActiveSurfaces, static_cast<std::int64_t>(active_.size()));
}

void ExactScan::GatherCounts() {
  const auto gather = [&](const std::vector<std::unique_ptr<Active>>& list) {
    for (const auto& a : list)
      if (a && a->own) {
        counters_.Merge(*a->own);
        *a->own = Counters();
      }
  };
  gather(active_);
  gather(retired_);
}

void ExactScan::UpdateActive(double yLo, double yHi, double spacing) {
  if (holdRetired_) {
    for (auto& a : active_)
      if (a->Passed(yLo)) retired_.push_back(std::move(a));
    std::erase(active_, nullptr);
  } else {
    std::erase_if(active_, [&](const std::unique_ptr<Active>& a) { return a->Passed(yLo); });
  }
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

void ExactScan::FinishWalk(Active& a, bool adopt) {
  // Silhouettes the walk found without a tracker are tracked from the next row on.
  if (adopt)
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
    FinishWalk(a);
  } else {
    WalkExact(a, y, t, columns, out, {&walkEvents_, &edgeUsed_, &silUsed_, &trimScratch_, &counters_});
    FinishWalk(a, AdoptsOn(RowIndex(y, columns)));
  }
}

void ExactScan::WalkExact(const Active& a, double y, const RowTrackers& t, const raster::SampleColumns& columns,
                          raster::FragmentRow& out, const WalkScratch& s) const {
  const Surface& surface = surfaces_[a.index];
  VisitShape(surface, [&](const auto& shape) {
    LevelWalker walker(shape, a.scan->Map(), a.scan->LineFor(y), columns, s.counters, s.events);
    walker.SetTrim(a.scan->Trim(), s.trim);
    walker.WalkAll(t, s.edgeUsed, s.silUsed, [&](int column, const LevelPoint& p) {
      ++(*s.counters)[Counter::Fragments];
      if (out.Hidden(column, p.w)) return;  // not worth its normal and texture coordinates
      out.Add(column, FragmentAt(p, surface, a.scan->NormalFromObject(), static_cast<std::uint32_t>(a.index)));
    });
  });
}

void ExactScan::PrepareBatch(double y0, double dy, int first, int count, const raster::SampleColumns& columns,
                            const ParallelFor& parallel) {
  retired_.clear();  // the rows of the batch before are scanned (their counts gathered)
  holdRetired_ = true;
  // As the row loop below asks (UpdateActive): the surfaces each row reaches, set up at once.
  ready_.clear();
  nextReady_ = 0;
  if (parallel) {
    for (std::size_t next = nextPending_, k = 0; k < static_cast<std::size_t>(count); ++k) {
      const double y = raster::RowY(y0, dy, first + static_cast<int>(k));
      for (; next < pending_.size() && pending_[next].yMin <= y; ++next)
        if (pending_[next].yMax >= y) ready_.push_back({next, y, nullptr});
    }
    parallel(static_cast<int>(ready_.size()), [&](int i) {
      Ready& r = ready_[static_cast<std::size_t>(i)];
      auto own = std::make_unique<Counters>();
      r.a = SetUp(pending_[r.index], r.y, columns.dx, *own);
      r.a->own = std::move(own);
    });
  }
  if (prepared_.size() < static_cast<std::size_t>(count)) prepared_.resize(static_cast<std::size_t>(count));
  preparedCount_ = count;
  for (int k = 0; k < count; ++k) {
    // As the back end's rows (raster::Lattice::At), bit for bit.
    const double y = raster::RowY(y0, dy, first + k);
    ++counters_[Counter::SampleRows];
    UpdateActive(y, y, columns.dx);
    PreparedRow& row = prepared_[static_cast<std::size_t>(k)];
    row.y = y;
    row.count = 0;
    // As ScanRow's exact rows, but for the walks.
    for (const auto& ap : active_) {
      Active& a = *ap;
      if (y < a.yFirst - kFirstYSlackPx) continue;
      AdvanceTo(a, y);
      if (a.scan->Done()) {
        a.done = true;
        continue;
      }
      if (row.entries.size() <= static_cast<std::size_t>(row.count)) row.entries.emplace_back();
      Prepared& e = row.entries[static_cast<std::size_t>(row.count++)];
      e.a = &a;
      e.t = a.scan->Trackers();  // into the lists' capacity
    }
  }
  holdRetired_ = false;
  PATCHSCAN_DCHECK(nextReady_ == ready_.size(), "every surface set up ahead is reached");
  GatherCounts();
}

bool ExactScan::ScanPrepared(int k, const raster::SampleColumns& columns, raster::FragmentRow& out,
                             RowScratch& scratch) {
  const PreparedRow& row = prepared_[static_cast<std::size_t>(k)];
  const bool adopts = k == preparedCount_ - 1 && AdoptsOn(RowIndex(row.y, columns));
  const WalkScratch s{&scratch.events, &scratch.edgeUsed, &scratch.silUsed, &scratch.trim, &scratch.counters};
  for (int e = 0; e < row.count; ++e) {
    const Prepared& p = row.entries[static_cast<std::size_t>(e)];
    scratch.events.Clear();
    WalkExact(*p.a, row.y, p.t, columns, out, s);
    // The last row's surfaces are each scanned by this thread alone.
    if (adopts) p.a->adopt = scratch.events.untrackedSilhouettes;
  }
  return true;
}

void ExactScan::FinishBatch() {
  for (const auto& a : active_) {
    for (const Vec2& uv : a->adopt) a->scan->Adopt(uv);
    a->adopt.clear();
  }
  GatherCounts();
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


void ExactScan::WalkLine(Active& a, double y, const RowTrackers& t, const raster::SampleColumns& columns,
                         raster::FragmentRow& out, ChainSet* set, bool* broken) {
  ++counters_[Counter::SlabLines];
  set->Clear();
  WalkSurface(a, y, t, columns, out, [&](std::span<const ThetaVertex> chain, bool closed) { set->Add(chain, closed); });
  *broken = WalkBroken();
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
