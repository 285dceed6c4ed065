// Cubic basis matrices as RenderMan defines them (RenderMan Interface 3.2, RiBasis):
// a curve segment is P(t) = [t^3 t^2 t 1] · M · [G0 G1 G2 G3]^T, and `step` is how many
// control points one segment advances by in a patch mesh.
#pragma once

#include <optional>
#include <string_view>

#include "patch/geometry.h"

namespace patchscan {

struct Basis {
  Mat4 m;
  int step = 3;
  std::string_view name;
};

const Basis& BezierBasis();
const Basis& BSplineBasis();
const Basis& CatmullRomBasis();
const Basis& HermiteBasis();
const Basis& PowerBasis();

// The named bases by their RenderMan names ("bezier", "b-spline", "catmull-rom",
// "hermite", "power"); nullopt for any other name.
std::optional<Basis> BasisByName(std::string_view name);

// The four basis functions of `basis` at t, with first and second derivatives:
// P(t) = sum_k w[k] * G_k. No allocation.
struct BasisWeights {
  Vec4 w, dw, d2w;
};
BasisWeights EvaluateBasis(const Basis& basis, double t);

}  // namespace patchscan
