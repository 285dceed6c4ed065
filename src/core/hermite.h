// Cubic Hermite interpolation, the one formula behind the θ chords' attributes along a row
// (raster::Chord), the θ link check's tilt (ThetaWalker::CheckLink), and the predictions
// of the edge trackers' and the X walks' Newton starts (PredictedStart, PredictColumn):
// the cubic from p0 at s = 0 to p1 at s = 1 with tangents m0 and m1 there (per unit s).
#pragma once

namespace patchscan {

// The Hermite basis at s: the cubic is w0 p0 + w1 m0 + w2 p1 + w3 m1 (for s past 1 too:
// the extrapolations one step on).
struct HermiteBlend {
  double w0, w1, w2, w3;
};
constexpr HermiteBlend HermiteWeights(double s) {
  const double s2 = s * s, s3 = s2 * s;
  return {2 * s3 - 3 * s2 + 1, s3 - 2 * s2 + s, -2 * s3 + 3 * s2, s3 - s2};
}

// The cubic's coefficients, lowest power first, where both tangents are known (k0, k1);
// with one of them, the quadratic through both ends with that tangent; with neither, the
// line.
template <class V>
void HermiteCoefficients(const V& p0, const V& p1, const V& m0, const V& m1, bool k0, bool k1, V (&c)[4]) {
  const V d = p1 - p0;
  c[0] = p0;
  c[3] = 0.0 * p0;
  if (k0 && k1) {
    c[1] = m0;
    c[2] = 3.0 * d - 2.0 * m0 - m1;
    c[3] = -2.0 * d + m0 + m1;
  } else if (k0) {
    c[1] = m0;
    c[2] = d - m0;
  } else if (k1) {
    c[1] = 2.0 * d - m1;
    c[2] = m1 - d;
  } else {
    c[1] = d;
    c[2] = 0.0 * p0;
  }
}

// A cubic in power form (lowest first) at s.
template <class V>
V Horner(const V (&c)[4], double s) {
  return ((c[3] * s + c[2]) * s + c[1]) * s + c[0];
}

}  // namespace patchscan
