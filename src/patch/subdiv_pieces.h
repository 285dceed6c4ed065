// Where a subdivision face's limit surface is a polynomial (patch/subdiv.h): bicubic
// patches and Gregory patches fitted to OpenSubdiv's Bfr and checked against it, which
// evaluate in a fraction of Bfr's time; and Bfr's own evaluation of a (sub-)face.
#pragma once

#include <opensubdiv/bfr/parameterization.h>
#include <opensubdiv/bfr/surface.h>

#include <array>
#include <bitset>
#include <cstdint>
#include <optional>
#include <vector>

#include "patch/bicubic.h"
#include "patch/subdiv.h"

namespace patchscan {

// A bicubic fitted to Bfr agrees with it to rounding (~1e-15 of the face's size, the
// collocation matrix's condition number being ~10); a surface of higher degree (Loop's
// quartic box splines, a Gregory patch) differs by a sizeable fraction of it. Position
// and derivatives up to the second must agree this closely, relative to the patch points'
// extent (a fitted Gregory patch: position and first derivatives, its fit agreeing to
// ~1e-15 as well where the cell is one, and by ~1e-6 of the extent where it is not).
constexpr double kBicubicFitRel = 1e-9;

// Bfr's evaluation at (u, v) of a (sub-)face through its map to the face's coordinates.
void EvaluateMapped(const OpenSubdiv::Bfr::Surface<double>& surface, const double* pts,
                    const SubdivFace::SubFaceMap& map, double u, double v, DerivOrder order, SurfaceDerivs* out);

// The map of sub-face `subFace` (-1: the face itself) of a face so parameterized.
SubdivFace::SubFaceMap MapOf(const OpenSubdiv::Bfr::Parameterization& param, int subFace);

// Which quarter of [0, 1] u lies in (0 to 3; outside, the nearest; NaN: 3).
inline int QuarterOf(double u) { return u < 0.25 ? 0 : u < 0.5 ? 1 : u < 0.75 ? 2 : 3; }

// A Gregory patch, as OpenSubdiv makes its irregular patches (Bfr's cells at an
// extraordinary corner, below its approximation level): a bicubic Bézier patch over
// (s, t) in [0,1]^2 whose four interior points are each a blend of two, F_a and F_b,
// weighted by the distances σ and τ from the nearest corner's two edges: (σ F_a + τ F_b) /
// (σ + τ), with (σ, τ) = (s, t), (1 - s, t), (s, 1 - t) or (1 - s, 1 - t). Its position is
// that rational function exactly. Its first derivatives are OpenSubdiv's, the Bézier
// patch's with the blend weights held where they are (what Bfr returns, and what Newton's
// iterations on it have always taken), and its second derivatives are those of that
// first-derivative field (the cross one the mean of its two), which the forward
// differences of Bfr's first derivatives approximated before: consistent with the first
// derivatives, as the silhouette trackers need.
class GregoryPatch {
 public:
  // Points 0-15: the Bézier grid, [4 j + i] for s index i and t index j (an interior one
  // is F_a); 16-19: F_b of the interior points (1,1), (2,1), (1,2), (2,2).
  static constexpr int kPoints = 20;
  explicit GregoryPatch(const std::array<Vec3, kPoints>& points) : p_(points) {}

  // The blend of interior point (i, j) (i, j in {1, 2}) at (s, t): F_a's weight G and its
  // derivatives (F_b's are 1 - G and the negated derivatives). At the corner itself, where
  // the blend is undefined, G = 0 (its Bernstein product vanishes there).
  struct Blend {
    double g, gs, gt;
  };
  static Blend BlendAt(int i, int j, double s, double t) {
    const double sigma = i == 1 ? s : 1.0 - s, tau = j == 1 ? t : 1.0 - t;
    const double ds = i == 1 ? 1.0 : -1.0, dt = j == 1 ? 1.0 : -1.0;
    const double sum = sigma + tau, inv = sum > 0.0 ? 1.0 / sum : 1.0;
    return {sigma * inv, ds * tau * inv * inv, -dt * sigma * inv * inv};
  }
  static int Second(int i, int j) { return 16 + (i - 1) + 2 * (j - 1); }


  // The weights of the 20 points in the position at (s, t).
  static void PositionWeights(double s, double t, double w[kPoints]);

  void Evaluate(double s, double t, DerivOrder order, SurfaceDerivs* out) const;

 private:
  std::array<Vec3, kPoints> p_;
};

// Where a (sub-)face's limit surface is a bicubic polynomial, as bicubic patches: the
// whole face for a regular Catmull-Clark quadrilateral (at a boundary too: Bfr extends the
// missing points linearly, which keeps it bicubic) or a bilinear one; else the cells of
// Bfr's patch tree away from the extraordinary corners, which are regular B-spline patches;
// and the cells at those corners, Gregory patches at Bfr's approximation level 2 (the cell
// of 1/4 x 1/4 at such a corner of a quadrilateral, the quadrant at the centre of a
// non-quadrilateral's sub-face), as Gregory patches. BicubicPatch and GregoryPatch
// evaluate them in a fraction of Bfr's time (its patch tree, basis weights and point
// combination; at a Gregory cell three evaluations of it where second derivatives are
// asked, SubdivFace::Evaluate's differences). Found from Bfr itself (FitBicubic,
// FitGregory), independently of how it orders and builds its points: the face whole, else
// each quadrant, else each quarter of a quadrant; what fits neither is left to Bfr.
struct BicubicPieces {
  // The 4 x 4 grid of quarters: at most this many pieces of either kind.
  static constexpr int kCells = 16;
  std::vector<BicubicPatch> patches;
  // Per cell of the 4 x 4 grid of quarters, [4 j + i] for u in quarter i and v in quarter j:
  // the patch covering it (-1: none, Bfr) and that patch's level (0: the whole face, over
  // [0,1]^2; 1: a quadrant; 2: the cell).
  std::array<std::int8_t, 16> patchOf{}, levelOf{};
  // Where no bicubic covers a cell, the Gregory patch that does (-1: none, Bfr), with its
  // level as above: Bfr's irregular cells, at an extraordinary corner (a quadrant of a
  // non-quadrilateral face's sub-face, whose centre corner is one, or a cell of a
  // quadrilateral's).
  std::vector<GregoryPatch> gregory;
  std::array<std::int8_t, 16> gregoryOf{};

  // Where the (sub-)face's corners are known to be extraordinary (Corners), the fits that
  // cannot succeed there are not tried, and the Gregory fit goes first.
  struct Corners {
    // Bit 2 qj + qi: quadrant (qi, qj)'s corner of the (sub-)face is an extraordinary point
    // whose Gregory patch is the quadrant (a triangle's centre) or the cell at that corner
    // (a smooth interior vertex of valence other than 4 at a quadrilateral's corner).
    unsigned gregoryQuadrants = 0, gregoryCells = 0;
  };

  BicubicPieces(const OpenSubdiv::Bfr::Surface<double>& surface, const std::vector<double>& pts,
                const SubdivFace::SubFaceMap& map, double tol, Corners corners);
  int PatchAt(double u, double v) const { return patchOf[static_cast<std::size_t>(4 * QuarterOf(v) + QuarterOf(u))]; }
  int GregoryAt(double u, double v) const { return gregoryOf[static_cast<std::size_t>(4 * QuarterOf(v) + QuarterOf(u))]; }
  // The polynomial or Gregory patch at (u, v), if one covers that cell.
  bool Evaluate(double u, double v, DerivOrder order, SurfaceDerivs* out) const;

 private:
  // Marks the quarters of cell (ci, cj) of `level` as covered by patch k of `of`.
  void Cover(std::array<std::int8_t, 16>& of, int k, int level, int ci, int cj);
  // The positions at a quadrant's cells' nodes, each evaluated once.
  struct QuadrantNodes {
    std::array<Vec3, 49> p;  // [7 j + i] at sixth (i, j) of the quadrant
    std::bitset<49> has;
  };
  // Fits the cell (ci, cj) of `level` as a bicubic (Fit) or a Gregory patch
  // (FitIrregular); covers its quarters if it is one. A cell of level 2 takes its nodes
  // from, and puts them into, its quadrant's `nodes` where given.
  bool Fit(const OpenSubdiv::Bfr::Surface<double>& surface, const std::vector<double>& pts,
           const SubdivFace::SubFaceMap& map, double tol, int level, int ci, int cj, QuadrantNodes* nodes = nullptr);
  bool FitIrregular(const OpenSubdiv::Bfr::Surface<double>& surface, const std::vector<double>& pts,
                    const SubdivFace::SubFaceMap& map, double tol, int level, int ci, int cj);
  template <class Patch>
  bool Keep(const std::optional<Patch>& patch, std::vector<Patch>& into, std::array<std::int8_t, 16>& of, int level,
            int ci, int cj) {
    if (!patch) return false;
    into.push_back(*patch);
    Cover(of, static_cast<int>(into.size()) - 1, level, ci, cj);
    return true;
  }
};

}  // namespace patchscan
