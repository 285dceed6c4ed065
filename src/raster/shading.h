// Two illumination models, shaded two-sided (a normal facing away from the eye is turned
// towards it):
// - the default, COS 426 2022 (COS 426, "Illumination model"):
//     I = I_E + K_A I_AL + sum_i (K_D (N . L_i) I_i + K_S (V . R_i)^n I_i);
// - RenderMan's standard surface shaders (RenderMan Interface 3.2, appendix A: constant,
//   matte, plastic, metal; paintedplastic is plastic with a texture), whose specular term
//   is sum_i Cl_i max(0, N . H_i)^(1/roughness) with H the unit half-vector of L and V.
// Lights: directional, point (attenuated by 1 / (1 + k d^2), or 1 / d^2 as RenderMan's
// pointlight) and RenderMan's spotlight.
#pragma once

#include <optional>
#include <vector>

#include "raster/bump.h"
#include "raster/environment.h"
#include "raster/mesh.h"
#include "raster/shadow_map.h"
#include "raster/texture.h"

namespace patchscan::raster {

using Rgb = Eigen::Vector3d;

struct Light {
  enum class Kind { Directional, Point, Spot } kind = Kind::Directional;
  Vec3 vector;           // Directional: direction the light travels; Point, Spot: position
  Rgb intensity{1, 1, 1};
  double attenuation = 0.0;    // k in 1 / (1 + k d^2), point lights without inverseSquare
  bool inverseSquare = false;  // point and spot lights: 1 / d^2 (RenderMan)
  // Spot lights (RenderMan's spotlight): the unit axis, the cosines of the cone's
  // half-angle and of that less its soft edge, and the cosine exponent of the beam.
  Vec3 axis = Vec3(0, 0, 1);
  double cosOutside = 0.0, cosInside = 0.0, beamDistribution = 2.0;
  // Shadows (RenderMan's shadowspot, shadowdistant, shadowpoint): the maps, not owned; a
  // point is looked up in the first whose view holds it (a point light's six faces).
  std::vector<const ShadowMap*> shadows;
  double shadowBias = 0.0, shadowBlur = 0.0;
  int shadowSamples = 1;

  // A light of `kind` at (or travelling along) `vector`, with `intensity` and `attenuation`;
  // the rest as above.
  static Light Of(Kind kind, const Vec3& vector, const Rgb& intensity, double attenuation = 0.0) {
    Light l;
    l.kind = kind;
    l.vector = vector;
    l.intensity = intensity;
    l.attenuation = attenuation;
    return l;
  }
};

struct Material {
  enum class Model { Default, Constant, Matte, Plastic, Metal };
  Model model = Model::Default;
  Rgb colour{0.8, 0.8, 0.8};
  Rgb emission{0, 0, 0};
  // ka 1 with the default rig's dim ambient light, as RenderMan's shaders take it.
  double ka = 1.0, kd = 0.75, ks = 0.35;
  double shininess = 40.0;     // n, the default model's specular exponent
  double roughness = 0.1;      // RenderMan's models: the specular exponent is 1 / roughness
  Rgb specularColour{1, 1, 1};  // plastic
  double opacity = 1.0;        // (0, 1]: below 1 the surface is seen through
  bool twoSided = true;        // false: only the front is drawn
  bool reversed = false;       // the front is the side the normal points away from
  int checkerSquares = 0;      // > 0: modulate colour by a uv checker of this many squares
  ImageTexture* texture = nullptr;  // not owned; modulates colour when set
  BumpMap bump;                     // perturbs the shading normal when it has a height field
  ImageTexture* normalMap = nullptr;  // not owned; a tangent-space normal map (raster/bump.h)
  // Reflected, times the colour the highlights take (metal: the surface's; else
  // specularColour), on every model but constant and matte.
  EnvironmentMap environment;
};

struct LightRig {
  Rgb ambient{1, 1, 1};  // I_AL
  std::vector<Light> lights;
};

// A pleasant default for a camera looking along `forward` with `up` and `right`: a warm
// key light from the upper left, a cool fill from the right, a dim rim from behind, and a
// dim bluish ambient light (a seventh of white).
LightRig DefaultLightRig(const Vec3& forward, const Vec3& up, const Vec3& right);

// The material's colour at uv, modulated by its checker or texture (filtered over the
// footprint duvdx, duvdy of one pixel); nullopt if the texture cannot be read.
std::optional<Rgb> SurfaceColour(const Material& m, const Vec2& uv, const Vec2& duvdx,
                                 const Vec2& duvdy);

// Colour at world point p with normal n (any length), seen from `eye`, for a surface of
// colour `base`. Allocation-free.
Rgb Shade(const Vec3& p, const Vec3& n, const Rgb& base, const Vec3& eye, const Material& m,
          const LightRig& rig);

// Renormalization of a vector whose length is near 1 by one Newton step for 1/sqrt
// (Woo and Chall 1990 §4.4, fast renormalization): exact to second order in (|v|^2 - 1).
inline Vec3 Renormalize(const Vec3& v) { return v * (1.5 - 0.5 * v.squaredNorm()); }
// Shade renormalizes by one step when | |n|^2 - 1 | is below this: the step leaves a
// length error of at most (3/8) 0.02^2 = 1.5e-4, invisible in 8- or 16-bit output.
constexpr double kRenormWindow = 0.02;

}  // namespace patchscan::raster
