#include "tracker/surface_scan.h"

#include <algorithm>
#include <cmath>

namespace patchscan {
namespace {

// A surface set up below its top is first advanced from its topmost maximum: at most this
// many pixels above the first line (a surface towering far above the image starts there
// with its trackers found by repair instead).
constexpr double kMaxPreAdvancePx = 1024.0;

}  // namespace

SurfaceScan::SurfaceScan(const Surface& surface, const Camera& camera, bool extrapolate, Counters& counters)
    : surface_(surface),
      hold_(surface, /*fit=*/true),
      map_(camera, surface.worldFromObject),
      normalFromObject_(surface.worldFromObject.linear().inverse().transpose()),
      counters_(counters),
      edges_(surface, map_, counters, extrapolate),
      silhouettes_(surface, map_, PrePass(), counters, extrapolate) {
  if (const PieceTrim* trim = TrimOf(surface)) trims_ = std::make_unique<TrimScan>(surface, *trim, map_, counters, extrapolate);
  ++counters_[Counter::SurfacesSetUp];
}

void SurfaceScan::StartAt(double yStart, double spacing) {
  const double step = std::max(spacing, 1.0);
  for (double y = std::max(std::min(yTop_, yStart), yStart - kMaxPreAdvancePx); y < yStart; y += step) {
    edges_.Advance(LineFor(y));
    silhouettes_.Advance(LineFor(y), edges_);
    if (trims_) trims_->Advance(LineFor(y));
  }
}

std::vector<Stationary> SurfaceScan::PrePass() {
  std::vector<Stationary> stationary = FindStationaryPoints(surface_, map_, &counters_);
  counters_[Counter::Stationary] += static_cast<std::int64_t>(stationary.size());
  yTop_ = INFINITY;
  for (const Stationary& p : stationary) {  // FindStationaryPoints sorts by y
    ScreenDerivs d;
    EvaluateScreen(surface_, map_, p.uv.x(), p.uv.y(), DerivOrder::Position, &d);
    stationary_.push_back({p.kind == StationaryKind::Saddle, Vec2(d.p.x(), d.p.y())});
    yTop_ = std::min(yTop_, p.y);
  }
  return stationary;
}

void SurfaceScan::Save(State* s) const {
  edges_.Save(&s->edges);
  silhouettes_.Save(&s->silhouettes);
  if (trims_) trims_->Save(&s->trims);
  s->row = row_;
}

void SurfaceScan::Restore(const State& s) {
  edges_.Restore(s.edges);
  silhouettes_.Restore(s.silhouettes);
  if (trims_) trims_->Restore(s.trims);
  row_ = s.row;
}

double SurfaceScan::LineFor(double y) const {
  const auto& ranges = edges_.DegenerateRanges();
  constexpr int kMaxSteps = 64;  // ranges are disjoint and few: a handful of steps at most
  double line = y;
  for (int k = 0; k < kMaxSteps; ++k) {
    const auto hit = std::find_if(ranges.begin(), ranges.end(),
                                  [&](const std::pair<double, double>& r) { return line >= r.first && line <= r.second; });
    if (hit == ranges.end()) return line;
    line = y + (k + 1) * kDegenerateStepPx;
  }
  return line;
}

void SurfaceScan::AdvanceTo(double y) {
  edges_.Advance(y);
  silhouettes_.Advance(y, edges_);
  row_.Clear();
  for (const EdgeTracker& t : edges_.Trackers()) {
    row_.edgePoints.push_back(edges_.Uv(t));
    row_.edgeOf.push_back(edges_.Pieces()[t.piece].edge);
  }
  for (const SilhouetteTracker& t : silhouettes_.Trackers()) row_.silhouettePoints.push_back(t.uv);
  if (trims_) {
    trims_->Advance(y);
    for (std::size_t k = 0; k < trims_->Points().size(); ++k) {
      const Vec2& uv = trims_->Points()[k];
      ScreenDerivs d;
      EvaluateScreen(surface_, map_, uv.x(), uv.y(), DerivOrder::Position, &d);
      row_.trimPoints.push_back(uv);
      row_.trimX.push_back(d.p.x());
      row_.trimEdgeX.push_back(trims_->EdgeX(trims_->Curves()[k], y, d.p.x()));
    }
  }
  counters_[Counter::TrackerRows] += static_cast<std::int64_t>(row_.edgePoints.size() + row_.silhouettePoints.size());
}

}  // namespace patchscan
