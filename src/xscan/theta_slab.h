// θ slabs (Blinn 1978 §4): the chains of one surface on two consecutive scan
// lines bound the piece of surface between them, a polygon one scan step high whose top
// and bottom are the chains themselves. Cut into triangles whose vertices are the chains'
// vertices, with their exact positions, normals and uv, it goes to the shared triangle
// back end, which finds the samples it covers and interpolates them perspective-correctly.
//
// Along a level curve x is monotone between silhouette points (J = 0 is where x turns
// back), so a chain is a row of x-monotone pieces between its anchors: its boundary ends
// and its silhouette vertices. Two chains of the same piece of curve on consecutive lines
// have the same anchors in the same order; each pair of pieces bounds a trapezoid whose
// slanted sides are the chords from anchor to anchor (the boundary edge, the silhouette),
// and the zip below fills it with triangles without gap or overlap. Where the chains of
// the two lines do not pair up so (a curve born or gone between them, a silhouette
// crossing a boundary, a fold) the slab's shape is not known from its lines, and the scan
// takes every sample row between them by its own chains instead.
#pragma once

#include <cmath>
#include <cstdint>
#include <span>
#include <vector>

#include "raster/mesh.h"
#include "xscan/theta_walk.h"

namespace patchscan {

// ChainSet (the chains of one surface on one line) is in theta_walk.h.

// A chain of the top line and its partner on the bottom line, the partner's vertices in
// the order that runs along the curve in the same direction from the same anchor.
struct ChainPair {
  std::uint32_t top;
  std::uint32_t begin, end;  // the partner's vertices, in the `ordered` vector PairChains fills
};

// Pairs every chain of `top` with one of `bottom`: same count, each pair closed or open
// alike with the same anchors in the same order (open chains ending on the same boundary
// sides), nearest in uv at their ends. False when the lines' chains differ so. Every
// vertex must be in front of the eye.
bool PairChains(const ChainSet& top, const ChainSet& bottom, std::vector<ChainPair>* pairs,
                std::vector<ThetaVertex>* ordered);

// Where a slab lies: its two lines, and the view (for the facing of its triangles).
struct SlabFrame {
  double yTop, yBottom;
  bool orthographic;
  Vec3 eye, forward;  // world
};
// A chain vertex on line y as a vertex for the back end (homogeneous screen position).
// Chain ends (boundary points shared by two surfaces) snap to 1 / kSlabEndGrid px in x.
constexpr double kSlabEndGrid = 65536.0;
inline double SlabEndX(double x) { return std::round(x * kSlabEndGrid) / kSlabEndGrid; }
raster::RasterVertex SlabVertex(const ThetaVertex& v, double y, bool orthographic);

// A slab's triangles blend the normal linearly between their vertices, where a θ row's
// chord follows the cubic its ends' slopes give (raster::Chord): across a link a quarter
// turn long (4 θ steps) the blend was wrong by up to 50° where the section's normal turns
// unevenly in x. So before zipping, each link whose chord is a cubic gets vertices on that
// cubic, evenly along its parameter, enough that the blend between them strays from it by
// about kSlabNormalTolRad: n pieces where the blend across the whole link strays δ at its
// middle, n = ⌈√(δ / tol)⌉ (a smooth curve's chord error falls as the square of its
// length), at most kMaxLinkPieces and one more than the sample columns between its ends.
// The chains' own vertices are kept, so the slabs stay as watertight as before. How the
// tolerance was chosen: docs/tuning.md.
constexpr double kSlabNormalTolRad = 0.01;
constexpr int kMaxLinkPieces = 8;
// The chains of `in` with those vertices added (kind Table, index -1: no anchor), into
// *out (its vectors reused: no allocation once they have grown).
void RefineChains(const ChainSet& in, const raster::SampleColumns& cols, bool orthographic, ChainSet* out);

// Anchors of a chain: its first and last vertices and its silhouette vertices, by index.
void ChainAnchors(std::span<const ThetaVertex> chain, std::vector<std::uint32_t>* anchors);

// The triangles of the slab between a top chain on line yTop and its partner on line
// yBottom (as PairChains gives it), oriented so that a triangle whose normals face the eye
// is front-facing on screen. Tri(a, b, c) receives each; the anchor vectors are scratch.
template <class Tri>
void ZipSlab(std::span<const ThetaVertex> top, std::span<const ThetaVertex> bottom, const SlabFrame& frame,
             std::vector<std::uint32_t>* anchorsTop, std::vector<std::uint32_t>* anchorsBottom, Tri&& tri) {
  ChainAnchors(top, anchorsTop);
  ChainAnchors(bottom, anchorsBottom);
  if (anchorsTop->size() != anchorsBottom->size()) return;  // PairChains has made sure they agree
  auto emit = [&](const ThetaVertex& a, double ya, const ThetaVertex& b, double yb, const ThetaVertex& c, double yc) {
    raster::RasterVertex va = SlabVertex(a, ya, frame.orthographic), vb = SlabVertex(b, yb, frame.orthographic),
                         vc = SlabVertex(c, yc, frame.orthographic);
    // det [h_a h_b h_c] > 0 is front-facing on screen (raster::SetupTriangle).
    const double det = va.h.dot(vb.h.cross(vc.h));
    const Vec3 centroid = (a.f.position + b.f.position + c.f.position) / 3.0;
    const Vec3 toEye = frame.orthographic ? Vec3(-frame.forward) : Vec3(frame.eye - centroid);
    const bool facesEye = (a.f.normal + b.f.normal + c.f.normal).dot(toEye) >= 0.0;
    if ((det > 0.0) != facesEye) std::swap(vb, vc);
    tri(va, vb, vc);
  };
  for (std::size_t s = 0; s + 1 < anchorsTop->size(); ++s) {
    const std::uint32_t t0 = (*anchorsTop)[s], t1 = (*anchorsTop)[s + 1];
    const std::uint32_t b0 = (*anchorsBottom)[s], b1 = (*anchorsBottom)[s + 1];
    // Each piece is x-monotone: zip by the fraction of the piece's x extent reached.
    auto fraction = [](std::span<const ThetaVertex> c, std::uint32_t i0, std::uint32_t i1, std::uint32_t i) {
      const double span = c[i1].x - c[i0].x;
      if (std::abs(span) > 1e-9) return (c[i].x - c[i0].x) / span;
      return i1 > i0 ? static_cast<double>(i - i0) / (i1 - i0) : 0.0;
    };
    std::uint32_t i = t0, k = b0;
    while (i < t1 || k < b1) {
      const bool advanceTop =
          k == b1 || (i < t1 && fraction(top, t0, t1, i + 1) <= fraction(bottom, b0, b1, k + 1));
      if (advanceTop) {
        emit(top[i], frame.yTop, top[i + 1], frame.yTop, bottom[k], frame.yBottom);
        ++i;
      } else {
        emit(top[i], frame.yTop, bottom[k + 1], frame.yBottom, bottom[k], frame.yBottom);
        ++k;
      }
    }
  }
}

}  // namespace patchscan
