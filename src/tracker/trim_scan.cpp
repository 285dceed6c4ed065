#include "tracker/trim_scan.h"

#include <algorithm>
#include <cmath>

#include "tracker/monotone_curve.h"

namespace patchscan {
namespace {

// A curve inside the domain by this much (in the piece's (u,v)) counts as inside: a trim
// curve along the piece's edge is the edge.
constexpr double kTrimDomainSlack = 1e-9;

// Screen y along trim curve k at t, and dy/dt.
template <class ShapeT>
std::pair<double, double> YAlong(const ShapeT& shape, const ScreenMap& map, const PieceTrim& trim, int k, double t) {
  Vec2 d;
  const Vec2 uv = trim.CurveAt(k, t, &d);
  ScreenDerivs s;
  EvaluateScreen(shape, map, uv.x(), uv.y(), DerivOrder::First, &s);
  return {s.p.y(), s.dpdu.y() * d.x() + s.dpdv.y() * d.y()};
}

bool InDomain(const Vec2& uv) {
  return uv.x() >= -kTrimDomainSlack && uv.x() <= 1.0 + kTrimDomainSlack && uv.y() >= -kTrimDomainSlack &&
         uv.y() <= 1.0 + kTrimDomainSlack;
}

}  // namespace

TrimScan::TrimScan(const Surface& surface, const PieceTrim& trim, const ScreenMap& map, Counters& counters,
                   bool extrapolate, double tolerancePx)
    : surface_(surface), trim_(trim), map_(map), counters_(counters), extrapolate_(extrapolate), tolerancePx_(tolerancePx) {
  VisitShape(surface_, [&](const auto& shape) {
    for (int k = 0; k < static_cast<int>(trim_.segments.size()); ++k) {
      // Where the curve crosses the lines u = 0, u = 1, v = 0, v = 1: the stretches between
      // are inside the domain or out of it.
      std::vector<double> cuts = {0.0};
      for (int axis = 0; axis < 2; ++axis)
        for (const double bound : {0.0, 1.0})
          SignChanges([&](double t) {
            Vec2 d;
            const Vec2 uv = trim_.CurveAt(k, t, &d);
            return std::pair(uv[axis] - bound, d[axis]);
          }, 0.0, 1.0, kTrimCriticalSamples, &cuts);
      cuts.push_back(1.0);
      std::sort(cuts.begin(), cuts.end());
      for (std::size_t c = 0; c + 1 < cuts.size(); ++c) {
        const double a = cuts[c], b = cuts[c + 1];
        if (!(b > a) || !InDomain(trim_.CurveAt(k, 0.5 * (a + b)))) continue;
        // The stretch's monotone pieces in screen y.
        std::vector<double> turns = {a};
        SignChanges([&](double t) { return std::pair(YAlong(shape, map_, trim_, k, t).second, NAN); }, a, b,
                    kTrimCriticalSamples, &turns);
        turns.push_back(b);
        for (std::size_t m = 0; m + 1 < turns.size(); ++m) {
          if (!(turns[m + 1] > turns[m])) continue;
          const double ya = YAlong(shape, map_, trim_, k, turns[m]).first, yb = YAlong(shape, map_, trim_, k, turns[m + 1]).first;
          if (std::isfinite(ya) && std::isfinite(yb))
            pieces_.push_back({k, turns[m], turns[m + 1], std::min(ya, yb), std::max(ya, yb)});
        }
      }
    }
  });
  std::stable_sort(pieces_.begin(), pieces_.end(), [](const TrimPiece& a, const TrimPiece& b) { return a.yTop < b.yTop; });
  trackers_.reserve(pieces_.size());
  points_.reserve(pieces_.size());
  curves_.reserve(pieces_.size());
  // The edges the curves run along, each once, seen through the surface's map.
  const ScreenMap edgeMap(map_, trim_.objectFromEdges);
  std::vector<const EdgeCurve*> seen;
  for (const int segment : trim_.segments) {
    const EdgeCurve* edge = trim_.loops->EdgeOf(segment);
    int e = -1;
    if (edge) {
      e = static_cast<int>(std::find(seen.begin(), seen.end(), edge) - seen.begin());
      if (e == static_cast<int>(seen.size())) {
        seen.push_back(edge);
        edges_.emplace_back(*edge, edgeMap);
      }
    }
    edgeOfCurve_.push_back(e);
  }
}

void TrimScan::Advance(double yScan) {
  // A piece holds the lines yTop <= y < yBottom, so that a line through a joint of two
  // pieces meets the curve once where it passes on, and twice or never where it turns
  // back (as the parity of TrimLoops::InsideLoops counts).
  VisitShape(surface_, [&](const auto& shape) {
    std::erase_if(trackers_, [&](const Tracker& t) {
      if (pieces_[static_cast<std::size_t>(t.piece)].yBottom > yScan) return false;
      ++counters_[Counter::TrimDied];
      ++events_;
      return true;
    });
    for (; nextPiece_ < pieces_.size() && pieces_[nextPiece_].yTop <= yScan; ++nextPiece_) {
      if (pieces_[nextPiece_].yBottom <= yScan) continue;  // passed between two lines
      trackers_.push_back({static_cast<int>(nextPiece_), 0.0, 0.0, 0.0, 0});
      ++counters_[Counter::TrimBorn];
      ++events_;
    }
    points_.clear();
    curves_.clear();
    for (Tracker& tr : trackers_) {
      const TrimPiece& p = pieces_[static_cast<std::size_t>(tr.piece)];
      auto f = [&](double t, double* v, double* d) {
        const auto [y, yt] = YAlong(shape, map_, trim_, p.curve, t);
        *v = y - yScan;
        *d = yt;
      };
      const double start = extrapolate_ ? ExtrapolatedStart(tr.t, tr.tPrev, tr.tPrev2, tr.nSolved,
                                                              tolerancePx_ <= kQuadraticExtrapolationTolPx)
                                        : tr.t;
      if (tr.nSolved > 0) ++counters_[Counter::TrimNewtonCalls];
      bool repaired = false;
      const double t = TrackOnPiece(f, p.t0, p.t1, start, tr.nSolved > 0, tolerancePx_,
                                    &counters_[Counter::TrimNewtonIterations], &repaired);
      counters_[Counter::TrimRepairs] += repaired;
      tr.tPrev2 = tr.tPrev;
      tr.tPrev = tr.nSolved > 0 ? tr.t : t;
      tr.t = t;
      ++tr.nSolved;
      points_.push_back(trim_.CurveAt(p.curve, t));
      curves_.push_back(p.curve);
    }
  });
}

}  // namespace patchscan
