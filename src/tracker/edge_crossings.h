// Where a scan line crosses a B-rep edge (patch/edge_curve.h) on the screen: the one place
// both faces that share the edge end on that line. Each face's trim crossing (its own pcurve
// through its own surface, tracker/trim_scan.h) lies within the model's tolerance of it; the
// X scans move the face's end to this crossing (xscan/level_walk.h), so two faces meet at
// the same x whatever the gap between their surfaces: crack-free by construction.
//
// The crossing is a function of the edge, the camera and the line alone: the edge's
// monotone pieces in screen y (Blinn 1978 §3.2.1, as the trim trackers cut their curves),
// then on the piece holding the line, Newton kept inside the piece's bracket from the
// chord's point. Both faces compute the same numbers, so they agree to rounding in the
// transforms that place the edge (1e-12 px), far inside kColumnEpsPx.
#pragma once

#include <cstddef>
#include <vector>

#include "patch/edge_curve.h"
#include "patch/screen.h"

namespace patchscan {

// How far (pixels) a face's own trim crossing may lie from its edge's crossing and still be
// taken as the same one: well past the widest gap measured between two faces of public
// models zoomed twenty times (docs/cad.md), well short of an image.
constexpr double kEdgeSnapMaxPx = 16.0;

class EdgeCrossings {
 public:
  // `map` takes the edge's coordinates to the screen. Both must outlive this.
  EdgeCrossings(const EdgeCurve& edge, const ScreenMap& map);

  // The screen x of the edge's crossing with line ys nearest x, if one lies within maxPx of
  // it; NaN otherwise (the line misses the edge there, or the edge is behind the eye).
  double Nearest(double ys, double x, double maxPx = kEdgeSnapMaxPx) const;

 private:
  struct Piece {
    std::size_t segment;
    double t0, t1, y0, y1;  // screen y at t0 and t1
    double xLo, xHi;        // the segment's screen x lies between (its projected hull)
  };
  // Screen (x, y) of segment k at t, and d/dt; false behind the eye.
  bool Screen(std::size_t k, double t, Vec2* p, Vec2* d) const;
  // The crossing's screen x on `piece`, NaN where the solve does not settle.
  double Solve(const Piece& piece, double ys) const;

  const EdgeCurve& edge_;
  ScreenMap map_;
  std::vector<Piece> pieces_;
};

}  // namespace patchscan
