// θ slab intervals of ExactScan (Blinn 1978 §4; xscan/exact_scan.h): the surfaces between
// two scan lines whose chains pair up go to the back end as slabs of triangles, the others
// row by row.
#include <algorithm>
#include <cmath>

#include "xscan/exact_scan.h"
#include "xscan/exact_scan_active.h"

namespace patchscan {
bool ExactScan::BeginsInterval(double y, const raster::SampleColumns& columns) const {
  const long j = RowIndex(y, columns);
  return j < intervalStart_ || j >= intervalEnd_;
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

}  // namespace patchscan
