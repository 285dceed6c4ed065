#include "patch/trim.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "core/sign_changes.h"
#include "core/shortest_number.h"

namespace patchscan {
namespace {

// Samples per segment when looking for the turning points of v along it: a segment of
// degree up to 15 has at most 28 of them (the numerator of v' has degree 2n - 2), and
// two within 1/64 of the segment would be missed (then the parity is wrong on the thin
// band of v between them).
constexpr int kTurnSamples = 64;

// A loop's curves meet head to tail, and its last curve ends at its first's start, within
// this fraction of the loop's size (exporters write decimal numbers).
constexpr double kLoopGapRel = 1e-6;

// A segment's box meets a piece's rectangle with this much slack (of the rectangle's
// size): a curve lying on the rectangle's edge is tracked by both pieces it bounds.
constexpr double kBoxSlackRel = 1e-9;

}  // namespace

TrimSegment::TrimSegment(std::vector<Vec3> uvw) : h_(std::move(uvw)) {
  lo_ = Vec2(INFINITY, INFINITY);
  hi_ = -lo_;
  for (const Vec3& h : h_) {
    const Vec2 p = h.head<2>() / h.z();
    lo_ = lo_.cwiseMin(p);
    hi_ = hi_.cwiseMax(p);
  }
}

Vec2 TrimSegment::At(double t, Vec2* d) const { return RationalBezierAt<2>(std::span<const Vec3>(h_), t, d); }

TrimLoops::TrimLoops(const std::vector<std::vector<TrimCurveInput>>& loops, bool keepInside) : keepInside_(keepInside) {
  for (std::size_t l = 0; l < loops.size(); ++l) {
    loopBegin_.push_back(static_cast<int>(segments_.size()));
    if (loops[l].empty()) throw std::invalid_argument("loop " + std::to_string(l + 1) + " has no curves");
    Vec2 lo(INFINITY, INFINITY), hi = -lo;
    for (std::size_t c = 0; c < loops[l].size(); ++c) {
      const TrimCurveInput& in = loops[l][c];
      const std::string where = "loop " + std::to_string(l + 1) + ", curve " + std::to_string(c + 1) + ": ";
      try {
        for (auto& seg : SplitNurbsCurve(in.order, in.knot, in.tmin, in.tmax, in.uvw)) {
          segments_.emplace_back(std::move(seg));
          segmentEdge_.push_back(in.edge);
        }
      } catch (const std::invalid_argument& e) {
        throw std::invalid_argument(where + e.what());
      }
    }
    const int first = loopBegin_.back(), end = static_cast<int>(segments_.size());
    for (int k = first; k < end; ++k) {
      lo = lo.cwiseMin(segments_[static_cast<std::size_t>(k)].BoxLo());
      hi = hi.cwiseMax(segments_[static_cast<std::size_t>(k)].BoxHi());
    }
    // Head to tail, and closed.
    const double gap = kLoopGapRel * std::max((hi - lo).maxCoeff(), 1e-300);
    for (int k = first; k < end; ++k) {
      const int next = k + 1 < end ? k + 1 : first;
      const Vec2 tail = segments_[static_cast<std::size_t>(k)].At(1.0);
      const Vec2 head = segments_[static_cast<std::size_t>(next)].At(0.0);
      if ((tail - head).norm() > gap)
        throw std::invalid_argument("loop " + std::to_string(l + 1) + " is not closed: a curve ends at (" +
                                    ShortestNumber(tail.x()) + ", " + ShortestNumber(tail.y()) + ") and the next starts at (" +
                                    ShortestNumber(head.x()) + ", " + ShortestNumber(head.y()) + ")");
    }
  }
  loopBegin_.push_back(static_cast<int>(segments_.size()));
  // The v-monotone pieces: sign changes of v' between samples, refined by bisection.
  for (std::size_t s = 0; s < segments_.size(); ++s) {
    const TrimSegment& seg = segments_[s];
    auto dv = [&](double t) {
      Vec2 d;
      seg.At(t, &d);
      return d.y();
    };
    std::vector<double> cuts = {0.0};
    SignChanges([&](double t) { return std::pair(dv(t), NAN); }, 0.0, 1.0, kTurnSamples, &cuts);
    cuts.push_back(1.0);
    for (std::size_t k = 0; k + 1 < cuts.size(); ++k)
      if (cuts[k + 1] > cuts[k])
        vpieces_.push_back({static_cast<int>(s), cuts[k], cuts[k + 1], seg.At(cuts[k]).y(), seg.At(cuts[k + 1]).y()});
  }
}

bool TrimLoops::InsideLoops(const Vec2& uv) const {
  bool inside = false;
  for (const VPiece& p : vpieces_) {
    // Half-open in v, so that a ray through a joint of two pieces counts it once where
    // the curve passes on and twice or never where it turns back.
    const double lo = std::min(p.v0, p.v1), hi = std::max(p.v0, p.v1);
    if (!(uv.y() >= lo && uv.y() < hi)) continue;
    const TrimSegment& seg = segments_[static_cast<std::size_t>(p.segment)];
    if (seg.BoxHi().x() <= uv.x()) continue;
    if (seg.BoxLo().x() > uv.x()) {
      inside = !inside;
      continue;
    }
    // The crossing of v = uv.y on the piece, by bisection (v is monotone there).
    double a = p.t0, b = p.t1;
    const bool rising = p.v1 > p.v0;
    for (int it = 0; it < 200 && b - a > 1e-15; ++it) {
      const double m = 0.5 * (a + b);
      if ((seg.At(m).y() < uv.y()) == rising) a = m;
      else b = m;
    }
    if (seg.At(0.5 * (a + b)).x() > uv.x()) inside = !inside;
  }
  return inside;
}

bool TrimLoops::Kept(const Vec2& uv) const { return InsideLoops(uv) == keepInside_; }

Vec2 PieceTrim::CurveAt(int k, double t, Vec2* d) const {
  const TrimSegment& seg = loops->Segments()[static_cast<std::size_t>(segments[static_cast<std::size_t>(k)])];
  const Vec2 scale(1.0 / (u1 - u0), 1.0 / (v1 - v0));
  const Vec2 p = seg.At(t, d);
  if (d) *d = d->cwiseProduct(scale);
  return (p - Vec2(u0, v0)).cwiseProduct(scale);
}

bool CutRectangle(const std::shared_ptr<const TrimLoops>& loops, double u0, double u1, double v0, double v1,
                  std::shared_ptr<const PieceTrim>* trim) {
  auto cut = std::make_shared<PieceTrim>(PieceTrim{loops, {}, u0, u1, v0, v1});
  const double su = kBoxSlackRel * (u1 - u0), sv = kBoxSlackRel * (v1 - v0);
  const auto& segs = loops->Segments();
  bool enters = false, shared = false;
  for (std::size_t k = 0; k < segs.size(); ++k) {
    const Vec2 &lo = segs[k].BoxLo(), &hi = segs[k].BoxHi();
    if (lo.x() <= u1 + su && hi.x() >= u0 - su && lo.y() <= v1 + sv && hi.y() >= v0 - sv) {
      cut->segments.push_back(static_cast<int>(k));
      shared = shared || loops->EdgeOf(static_cast<int>(k));
    }
    enters = enters || (lo.x() < u1 - su && hi.x() > u0 + su && lo.y() < v1 - sv && hi.y() > v0 + sv);
  }
  trim->reset();
  // No curve enters the rectangle (none reaches it, or those that do run along its edges,
  // as a CAD face's wire runs round the box of its parameters): all of it is on one side.
  // Kept whole, unless a curve on its edge is one a neighbouring face shares: the scans
  // then end the piece at that edge's crossings (tracker/edge_crossings.h), not at its own.
  if (!enters) {
    const bool kept = cut->Kept(Vec2(0.5, 0.5));
    if (!kept || !shared) return kept;
  }
  *trim = std::move(cut);
  return true;
}

std::vector<TrimmedPiece> TrimPieces(const std::shared_ptr<const TrimLoops>& loops, std::vector<NurbsPiece> pieces) {
  std::vector<TrimmedPiece> kept;
  for (NurbsPiece& piece : pieces) {
    std::shared_ptr<const PieceTrim> trim;
    if (CutRectangle(loops, piece.U0(), piece.U1(), piece.V0(), piece.V1(), &trim))
      kept.push_back(TrimmedPiece{std::move(piece), std::move(trim)});
  }
  return kept;
}

}  // namespace patchscan
