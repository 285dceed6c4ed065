// Bump mapping (Blinn, "Simulation of Wrinkled Surfaces", SIGGRAPH 1978): the normal of a
// surface displaced by a small height h along its unit normal n, without moving it. Blinn's
// perturbed normal is N' = N + (B_s (N x P_t) - B_t (N x P_s)) / |N| with N = P_s x P_t and
// B_s, B_t the height's derivatives in the texture coordinates; since (n x P_t) / |N| = -grad s
// and (n x P_s) / |N| = grad t (the gradients of the texture coordinates on the surface, in
// its tangent plane), that is |N| (n - grad h): the unit normal less the height's surface
// gradient. Both carry Blinn's approximation: the displacement's term h dn/ds (of the order of
// h times the curvature) is left out.
//
// The gradient of h on the surface is found through the screen (the chain rule that
// Mikkelsen, "Bump Mapping Unparametrized Surfaces on the GPU", 2010, uses): h's change per
// pixel (dh/dx, dh/dy) = (B_s ds/dx + B_t dt/dx, ...) from the fragment's texture footprint, and
// the world gradients of screen x and y at the point, projected into the tangent plane. Every
// mode gives a fragment its normal, position and footprint, so the one formula serves them
// all; it is exact wherever they are (exact mode: the footprint comes from the surface's own
// P_u, P_v).
#pragma once

#include <Eigen/Core>
#include <utility>

#include "raster/mesh.h"

namespace patchscan::raster {

class ImageTexture;

// The rows X, Y, W of the projective map from world space to the screen: x = X/W and
// y = Y/W pixels (orthographic: W = 1). Zero where unknown: no bump is then applied.
using ScreenRows = Eigen::Matrix<double, 3, 4>;

// A material's bump map: its height field (RenderMan's bumpy displacement: the first
// channel) scaled by `amplitude` (world units per unit of the texture's value).
struct BumpMap {
  ImageTexture* height = nullptr;  // not owned; none: no bump
  double amplitude = 1.0;
};

// The gradient, on the surface through p with unit normal n, of a function whose change per
// pixel along screen x and y is `perPixel`: (fx grad x + fy grad y) projected into the
// tangent plane, grad x = (M_x - x M_w) / W the world gradient of screen x. Zero where the
// screen rows are unknown or the point is behind the eye.
Vec3 SurfaceGradient(const ScreenRows& screen, const Vec3& p, const Vec3& n, const Vec2& perPixel);

// The world change, per pixel along screen x and along y, of a point moving in the tangent
// plane through p with unit normal n: the inverse of the screen's Jacobian there. Zero where
// the screen rows are unknown, the point is behind the eye or the plane is seen edge-on.
std::pair<Vec3, Vec3> ScreenTangents(const ScreenRows& screen, const Vec3& p, const Vec3& n);

// The surface's tangents along the texture coordinates, P_s and P_t, at p (unit normal n):
// the screen tangents (ScreenTangents) times the inverse of the texture footprint
// d(s, t)/d(x, y). False where either is singular (an edge-on plane, a zero footprint).
bool TextureTangents(const ScreenRows& screen, const Vec3& p, const Vec3& n, const Vec2& duvdx, const Vec2& duvdy,
                     Vec3* ps, Vec3* pt);

// The normal a tangent-space normal map gives (RGB in [0, 1] = (1 + n) / 2 in the frame T,
// B, N; OpenGL's convention, green towards the image's top, which is -t): T is P_s made
// orthogonal to the unit normal n, B is -P_t's part orthogonal to both. n where the
// tangents are unknown.
Vec3 MappedNormal(const ScreenRows& screen, const Vec3& p, const Vec3& n, const Vec2& duvdx, const Vec2& duvdy,
                  const Vec3& rgb);

// Blinn's perturbed normal at a point with normal n (any length; the result's length is
// near 1 for a gentle bump): n / |n| less the surface gradient of the height, from its
// derivatives (B_s, B_t) in the texture coordinates and the texture coordinates' change per
// pixel duvdx, duvdy.
Vec3 BumpedNormal(const ScreenRows& screen, const Vec3& p, const Vec3& n, const Vec2& heightGradient,
                  const Vec2& duvdx, const Vec2& duvdy);

}  // namespace patchscan::raster
