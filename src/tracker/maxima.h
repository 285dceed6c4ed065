// The maxima pre-pass of Blinn 1978 §3.2.2.1: before the Y scan, find per surface the
// places where the scan line first meets it (local maxima of the height on screen) and
// the saddles where its level curves change shape (§3.2.2.4).
//
// Blinn's Y points up the screen; patchscan's screen y points down. So the height used
// here is h(u,v) = -y(u,v): a maximum of h is where a surface first appears as the scan
// line moves down the image.
#pragma once

#include <vector>

#include "core/counters.h"
#include "patch/screen.h"
#include "tracker/newton.h"

namespace patchscan {

enum class StationaryKind {
  StrictMaximum,  // interior, gradient zero, Hessian negative definite (§3.2.2)
  EdgeMaximum,    // on a boundary edge: maximal along it, the gradient pointing out (Fig. 4)
  CornerMaximum,  // at a corner, the gradient pointing out along both parameters
  LineOfMaxima,   // interior, Hessian singular: a parabolic cylinder (§3.4)
  Saddle,         // interior, gradient zero, Hessian indefinite (§3.2.2.4)
};
const char* ToString(StationaryKind k);

struct Stationary {
  StationaryKind kind;
  Vec2 uv;
  double y;           // screen y of the point, pixels (down)
  Vec2 gradH;        // (h_u, h_v) there
  Mat2 hessH;        // second derivatives of h there
  int edge = -1;      // EdgeMaximum: PatchEdge of its edge; CornerMaximum: -1
};

// Seeds per side of the grid of starting points (corners and centre included, §3.2.2.1).
constexpr int kMaximaSeedGrid = 5;
// Duplicates (Blinn's thesis): two points of one kind whose y, and the y at the midpoint
// of their (u,v), agree within a tenth of a raster.
constexpr double kDuplicateY = 0.1;

// All maxima and saddles of one surface seen through `map`, sorted by y (topmost first).
// Minima are not reported (trackers die there by failing to converge, §3.2.3).
// A bicubic patch, or a subdivision face fitted as bicubic pieces in every cell, whose y is
// proven monotone in u and in v has one maximum, at a corner, found without a climb
// (counted as maxima_proven_monotone).
std::vector<Stationary> FindStationaryPoints(const Surface& s, const ScreenMap& map,
                                             Counters* counters = nullptr);
// The same by the seeds' climbs alone, every surface searched (to test the proof against).
std::vector<Stationary> SearchStationaryPoints(const Surface& s, const ScreenMap& map, Counters* counters = nullptr);

}  // namespace patchscan
