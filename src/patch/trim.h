// Trim curves (RenderMan's TrimCurve): closed loops of NURBS curves in
// a NuPatch's (u,v) that cut part of it away. A point is inside the loops when a ray from
// it crosses them an odd number of times (the specification's odd winding rule). The
// inside is kept and the rest cut away — an exporter's loop around the whole patch keeps
// it, a loop inside that one cuts a hole (RenderMan's convention, as Aqsis renders it);
// with Attribute "trimcurve" "sense" "outside" the outside is kept instead.
//
// Each curve is split at its knots into rational Bézier segments (nurbs.h) and each segment
// into pieces on which v is monotone, so that the parity of a point is a count of the
// pieces whose v range holds it and whose crossing of that v lies to its right: one
// bisection per piece, no flattening. A NURBS piece of the patch keeps only the segments
// whose box meets its own rectangle (PieceTrim): the scans track those (tracker/trim_scan.h).
#pragma once

#include <memory>
#include <span>
#include <vector>

#include <Eigen/Geometry>

#include "core/vec.h"
#include "patch/edge_curve.h"
#include "patch/nurbs.h"

namespace patchscan {

// One curve of a loop as RenderMan gives it: order, knot vector (n + order values), the
// parameter range drawn, and n homogeneous control points (u w, v w, w).
struct TrimCurveInput {
  int order = 0;
  std::vector<double> knot;
  double tmin = 0.0, tmax = 1.0;
  std::vector<Vec3> uvw;
  // The B-rep edge the curve runs along, when it is one two faces share (a CAD face's
  // pcurve); null for RenderMan's trims.
  std::shared_ptr<const EdgeCurve> edge;
};

// A rational Bézier segment of a trim curve on t in [0,1], in the NuPatch's (u,v).
class TrimSegment {
 public:
  explicit TrimSegment(std::vector<Vec3> uvw);
  // The point at t, and its derivative when `d` is given. Allocates nothing.
  Vec2 At(double t, Vec2* d = nullptr) const;
  int Degree() const { return static_cast<int>(h_.size()) - 1; }
  std::span<const Vec3> Points() const { return h_; }
  // The box of the control points divided by their weights: it holds the segment.
  const Vec2& BoxLo() const { return lo_; }
  const Vec2& BoxHi() const { return hi_; }

 private:
  std::vector<Vec3> h_;
  Vec2 lo_, hi_;
};

// A trim curve set: loops of segments, and which side of them is cut away.
class TrimLoops {
 public:
  // Throws std::invalid_argument naming the loop and curve: an order, knot vector, range
  // or weight NuPatch would refuse too (nurbs.h), a point that is not finite, a loop whose
  // curves do not meet head to tail or that does not close.
  TrimLoops(const std::vector<std::vector<TrimCurveInput>>& loops, bool keepInside);

  // Whether the NuPatch keeps the point uv (odd winding rule and the sense).
  bool Kept(const Vec2& uv) const;
  // Whether uv lies inside the loops (an odd number of crossings to its right, along +u).
  bool InsideLoops(const Vec2& uv) const;

  const std::vector<TrimSegment>& Segments() const { return segments_; }
  // The edge segment k runs along (TrimCurveInput::edge), or null.
  const EdgeCurve* EdgeOf(int k) const { return segmentEdge_[static_cast<std::size_t>(k)].get(); }
  // The segments of loop k are [LoopBegin(k), LoopBegin(k + 1)).
  int Loops() const { return static_cast<int>(loopBegin_.size()) - 1; }
  int LoopBegin(int k) const { return loopBegin_[static_cast<std::size_t>(k)]; }
  bool KeepsInside() const { return keepInside_; }
  // The same loops keeping the other side when `keepInside` differs.
  TrimLoops WithSense(bool keepInside) const {
    TrimLoops t = *this;
    t.keepInside_ = keepInside;
    return t;
  }

 private:
  // A piece [t0, t1] of a segment on which v is monotone, from v0 to v1.
  struct VPiece {
    int segment;
    double t0, t1, v0, v1;
  };
  std::vector<TrimSegment> segments_;
  std::vector<std::shared_ptr<const EdgeCurve>> segmentEdge_;  // per segment
  std::vector<int> loopBegin_;
  std::vector<VPiece> vpieces_;
  bool keepInside_;
};

// The trim of one surface: the loops, the segments that can meet it, and its rectangle in
// the loops' parameters (the surface's own (s,t) in [0,1]^2 is u = u0 + s (u1 - u0),
// v = v0 + t (v1 - v0)): a NURBS piece's in its NuPatch's (u,v), a CAD face's analytic
// surface's in the face's.
struct PieceTrim {
  std::shared_ptr<const TrimLoops> loops;
  std::vector<int> segments;
  double u0, u1, v0, v1;
  // Where the loops' edge curves (TrimLoops::EdgeOf) lie in the surface's object space.
  Eigen::Affine3d objectFromEdges = Eigen::Affine3d::Identity();

  Vec2 ToPatch(const Vec2& st) const { return {u0 + st.x() * (u1 - u0), v0 + st.y() * (v1 - v0)}; }
  // Whether the piece keeps its point st.
  bool Kept(const Vec2& st) const { return loops->Kept(ToPatch(st)); }
  // Segment segments[k] in the piece's (s,t), and its derivative.
  Vec2 CurveAt(int k, double t, Vec2* d = nullptr) const;
};

// What `loops` leave of the rectangle [u0,u1] x [v0,v1] of their (u,v): false where no
// curve enters it and its centre is cut away (dropped whole); else true, *trim the
// rectangle's PieceTrim, or null where it is kept whole: no curve enters it and none on its
// edges runs along an edge another face shares (TrimCurveInput::edge).
bool CutRectangle(const std::shared_ptr<const TrimLoops>& loops, double u0, double u1, double v0, double v1,
                  std::shared_ptr<const PieceTrim>* trim);

// The pieces of one NuPatch that `loops` leave, each with its trim (null: whole).
struct TrimmedPiece {
  NurbsPiece piece;
  std::shared_ptr<const PieceTrim> trim;
};
std::vector<TrimmedPiece> TrimPieces(const std::shared_ptr<const TrimLoops>& loops, std::vector<NurbsPiece> pieces);

}  // namespace patchscan
