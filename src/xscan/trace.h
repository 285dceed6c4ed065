// What the exact scan did, as marks in screen space: each tracker's position on each
// sample row and each event of the Y scan and the X scan. A user sees it drawn over the
// image with `--overlay trackers`.
#pragma once

namespace patchscan {

enum class TraceKind {
  EdgeTracker,        // a boundary-edge tracker's position on a sample row
  SilhouetteTracker,  // a silhouette tracker's position
  Maximum,            // the scan passed a maximum (strict, edge, corner or a line of maxima)
  Saddle,             // the scan passed a saddle
  Fold,               // a silhouette crossed a boundary edge
  Birth,              // a silhouette tracker was born
  Death,              // a tracker died (a minimum, or it left the domain)
  Repair,             // the X scan found a crossing no tracker held
  Failure,            // the X scan gave up a walk or a sample
};

class TraceSink {
 public:
  virtual void Mark(TraceKind kind, double x, double y) = 0;

 protected:
  ~TraceSink() = default;
};

}  // namespace patchscan
