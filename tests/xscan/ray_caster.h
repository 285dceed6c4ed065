// An independent reference for the exact X scan: a brute-force per-sample ray caster.
// For each sample it finds every surface point projecting there by recursive subdivision
// of the parameter domain (a cell is kept while its conservative screen box contains the
// sample), then plain Newton from the centre of each small cell. Slow and simple: it
// shares surface evaluation with the renderer and nothing of the trackers, the walk or
// the renderer's Newton solvers.
#pragma once

#include <algorithm>
#include <cmath>
#include <optional>
#include <span>
#include <vector>

#include "patch/screen.h"

namespace patchscan::test {

struct RayHit {
  Vec2 uv;
  double w;
  std::size_t surface;
};

class RayCaster {
 public:
  // Cells per side of the first grid over each surface.
  static constexpr int kGrid = 32;
  // Newton's convergence in pixels, and its iteration cap (plain Newton converges
  // quadratically from a cell's centre; near a fold it slows to linear, hence the cap).
  static constexpr double kTolPx = 1e-10;
  static constexpr int kMaxIterations = 60;
  // Newton that stops converging (the residual no longer halves) with a residual within
  // kStallTolPx has reached the rounding floor of the screen position, and is accepted.
  // Far from the origin that floor is high: at 1e6 world units the projection subtracts
  // numbers near 5e7 px, whose rounding is ~1e-8 px.
  static constexpr double kStallTolPx = 1e-6;
  // Cells are subdivided until their screen box is this small before Newton starts, and
  // at most this deep.
  static constexpr double kLeafPx = 0.5;
  static constexpr int kMaxDepth = 22;

  // Screen tiles (pixels per side) listing the first-grid cells whose box reaches them.
  static constexpr int kTilePx = 8;

  RayCaster(std::span<const Surface> surfaces, const Camera& camera)
      : surfaces_(surfaces),
        tilesX_((camera.width + kTilePx - 1) / kTilePx + 1),
        tilesY_((camera.height + kTilePx - 1) / kTilePx + 1),
        tiles_(static_cast<size_t>(tilesX_) * tilesY_) {
    for (const Surface& s : surfaces) maps_.emplace_back(camera, s.worldFromObject);
    for (std::size_t k = 0; k < surfaces.size(); ++k)
      for (int j = 0; j < kGrid; ++j)
        for (int i = 0; i < kGrid; ++i) {
          const Box b = CellBox(k, double(i) / kGrid, double(j) / kGrid, 1.0 / kGrid);
          if (!b.valid) continue;
          const int tx0 = std::max(0, int(std::floor(b.xl / kTilePx))), tx1 = std::min(tilesX_ - 1, int(std::floor(b.xh / kTilePx)));
          const int ty0 = std::max(0, int(std::floor(b.yl / kTilePx))), ty1 = std::min(tilesY_ - 1, int(std::floor(b.yh / kTilePx)));
          for (int ty = ty0; ty <= ty1; ++ty)
            for (int tx = tx0; tx <= tx1; ++tx) tiles_[size_t(ty) * tilesX_ + tx].push_back({k, i, j});
        }
  }

  // Every surface point seen at (x, y), inside the image; on a trimmed NURBS piece only
  // the points its trim keeps (by the odd winding rule at the hit, patch/trim.h).
  std::vector<RayHit> HitsAt(double x, double y) const {
    std::vector<RayHit> hits;
    const int tx = int(std::floor(x / kTilePx)), ty = int(std::floor(y / kTilePx));
    if (tx < 0 || ty < 0 || tx >= tilesX_ || ty >= tilesY_) return hits;
    for (const CellRef& c : tiles_[size_t(ty) * tilesX_ + tx])
      Search(c.surface, double(c.i) / kGrid, double(c.j) / kGrid, 1.0 / kGrid, x, y, 0, &hits);
    std::erase_if(hits, [&](const RayHit& h) {
      const PieceTrim* trim = TrimOf(surfaces_[h.surface]);
      return trim && !trim->Kept(h.uv);
    });
    return hits;
  }

  std::optional<RayHit> Nearest(double x, double y) const {
    const auto hits = HitsAt(x, y);
    if (hits.empty()) return std::nullopt;
    return *std::min_element(hits.begin(), hits.end(),
                             [](const RayHit& a, const RayHit& b) { return a.w < b.w; });
  }

 private:
  struct Box {
    double xl = INFINITY, xh = -INFINITY, yl = INFINITY, yh = -INFINITY;  // grown by the margin
    bool fold = false;  // J has both signs: the cell may hold two roots
    bool valid = true;  // false: part of the cell is not in front of the eye
  };
  struct CellRef {
    std::size_t surface;
    int i, j;
  };

  // The screen box of the cell [u0, u0+h] x [v0, v0+h] of surface k: its corners' box
  // grown by the largest deviation of the surface from the bilinear interpolation of its
  // corners, (h^2 / 8) max |s''|, with the second derivatives' largest value over five
  // points doubled for safety.
  Box CellBox(std::size_t k, double u0, double v0, double h) const {
    Box b;
    double second = 0.0;
    int positive = 0, negative = 0;
    const double pts[5][2] = {{0, 0}, {1, 0}, {0, 1}, {1, 1}, {0.5, 0.5}};
    for (const auto& p : pts) {
      ScreenDerivs d;
      EvaluateScreen(surfaces_[k], maps_[k], u0 + p[0] * h, v0 + p[1] * h, DerivOrder::Second, &d);
      if (!(d.w > 0.0)) {  // the reference scenes lie in front of the eye
        b.valid = false;
        return b;
      }
      const double j = d.dpdu.x() * d.dpdv.y() - d.dpdv.x() * d.dpdu.y();
      positive += j > 0.0;
      negative += j < 0.0;
      if (p[0] != 0.5) {
        b.xl = std::min(b.xl, d.p.x()), b.xh = std::max(b.xh, d.p.x());
        b.yl = std::min(b.yl, d.p.y()), b.yh = std::max(b.yh, d.p.y());
      }
      second = std::max(second, d.d2pdu2.head<2>().norm() + 2.0 * d.d2pduv.head<2>().norm() +
                                    d.d2pdv2.head<2>().norm());
    }
    const double margin = 2.0 * h * h / 8.0 * second + 1e-9;
    b.xl -= margin, b.xh += margin, b.yl -= margin, b.yh += margin;
    b.fold = positive > 0 && negative > 0;
    return b;
  }

  void Search(std::size_t k, double u0, double v0, double h, double x, double y, int depth,
              std::vector<RayHit>* hits) const {
    const Box b = CellBox(k, u0, v0, h);
    if (!b.valid || x < b.xl || x > b.xh || y < b.yl || y > b.yh) return;
    const double size = std::max(b.xh - b.xl, b.yh - b.yl);
    // A cell across a fold may hold two roots: it is subdivided to the depth limit.
    if ((size <= kLeafPx && !b.fold) || depth >= kMaxDepth) {
      if (Solve(k, u0, v0, h, x, y, hits) || depth >= kMaxDepth) return;
    }
    const double g = 0.5 * h;
    for (int bj = 0; bj < 2; ++bj)
      for (int bi = 0; bi < 2; ++bi) Search(k, u0 + bi * g, v0 + bj * g, g, x, y, depth + 1, hits);
  }

  // Plain Newton from the cell's centre; a root within the cell (grown by a quarter of
  // its side) is a hit unless already found.
  bool Solve(std::size_t k, double u0, double v0, double h, double x, double y,
             std::vector<RayHit>* hits) const {
    Vec2 uv(u0 + 0.5 * h, v0 + 0.5 * h);
    double previous = INFINITY;
    for (int it = 0; it < kMaxIterations; ++it) {
      ScreenDerivs d;
      EvaluateScreen(surfaces_[k], maps_[k], uv.x(), uv.y(), DerivOrder::First, &d);
      const Vec2 f(d.p.x() - x, d.p.y() - y);
      // Converged; or stalled at the rounding floor (kStallTolPx).
      const double residual = f.cwiseAbs().maxCoeff();
      const bool stalled = residual > 0.5 * previous;
      previous = residual;
      if (residual <= kTolPx || (stalled && residual <= kStallTolPx)) {
        const double grow = 0.25 * h;
        if (uv.x() < u0 - grow || uv.x() > u0 + h + grow || uv.y() < v0 - grow || uv.y() > v0 + h + grow)
          return false;
        for (const RayHit& hit : *hits)
          if (hit.surface == k && (hit.uv - uv).norm() < 1e-7) return true;
        hits->push_back({uv, d.w, k});
        return true;
      }
      Mat2 jac;
      jac << d.dpdu.x(), d.dpdv.x(), d.dpdu.y(), d.dpdv.y();
      if (jac.determinant() == 0.0) return false;
      uv = (uv - jac.inverse() * f).cwiseMax(0.0).cwiseMin(1.0);
    }
    return false;
  }

  std::span<const Surface> surfaces_;
  std::vector<ScreenMap> maps_;
  int tilesX_, tilesY_;
  std::vector<std::vector<CellRef>> tiles_;
};

}  // namespace patchscan::test
