#include "raster/shading.h"

#include <cmath>

namespace patchscan::raster {

LightRig DefaultLightRig(const Vec3& forward, const Vec3& up, const Vec3& right) {
  LightRig rig;
  rig.ambient = 0.15 * Rgb(0.9, 0.92, 1.0);
  // Directions the light travels (from the light towards the scene).
  rig.lights.push_back(Light::Of(Light::Kind::Directional, (forward + right - 1.2 * up).normalized(),
                        Rgb(0.95, 0.9, 0.82)));
  rig.lights.push_back(Light::Of(Light::Kind::Directional, (forward - 1.5 * right + 0.2 * up).normalized(),
                        Rgb(0.25, 0.3, 0.4)));
  rig.lights.push_back(Light::Of(Light::Kind::Directional, (-forward - 0.5 * up).normalized(),
                        Rgb(0.3, 0.3, 0.3)));
  return rig;
}

std::optional<Rgb> SurfaceColour(const Material& m, const Vec2& uv, const Vec2& duvdx,
                                 const Vec2& duvdy) {
  Rgb base = m.colour;
  if (m.checkerSquares > 0) {
    const long iu = static_cast<long>(std::floor(uv.x() * m.checkerSquares));
    const long iv = static_cast<long>(std::floor(uv.y() * m.checkerSquares));
    if ((iu + iv) & 1) base *= 0.25;
  }
  if (m.texture) {
    const auto t = m.texture->Lookup(uv, duvdx, duvdy);
    if (!t) return std::nullopt;
    base = base.cwiseProduct(*t);
  }
  return base;
}

namespace {

// The light arriving at p from `light`: its colour Cl and the unit direction l towards
// it. False when none arrives (outside a spot's cone).
bool LightAt(const Light& light, const Vec3& p, Vec3* l, Rgb* cl) {
  *cl = light.intensity;
  if (light.kind == Light::Kind::Directional) {
    *l = -light.vector.normalized();
    return true;
  }
  *l = light.vector - p;
  const double d2 = l->squaredNorm();
  if (!(d2 > 0.0)) return false;
  *l /= std::sqrt(d2);
  *cl *= light.inverseSquare ? 1.0 / d2 : 1.0 / (1.0 + light.attenuation * d2);
  if (light.kind == Light::Kind::Spot) {
    // RenderMan Interface 3.2, appendix A, spotlight: cos^beamdistribution of the angle
    // off the axis, times smoothstep(cos outside, cos inside, cos angle).
    const double c = -l->dot(light.axis);
    if (c <= light.cosOutside) return false;
    double edge = 1.0;
    if (c < light.cosInside) {
      const double t = (c - light.cosOutside) / (light.cosInside - light.cosOutside);
      edge = t * t * (3.0 - 2.0 * t);
    }
    *cl *= std::pow(c, light.beamDistribution) * edge;
  }
  return true;
}

// The share of the light that the light's shadow maps let through to p.
double Unshadowed(const Light& light, const Vec3& p) {
  for (const ShadowMap* map : light.shadows)
    if (map->Holds(p)) return map->Visibility(p, light.shadowBias, light.shadowBlur, light.shadowSamples);
  return 1.0;
}

}  // namespace

Rgb Shade(const Vec3& p, const Vec3& n, const Rgb& base, const Vec3& eye, const Material& m,
          const LightRig& rig) {
  using Model = Material::Model;
  if (m.model == Model::Constant) return base;
  const Vec3 v = (eye - p).normalized();
  // Interpolated unit normals are nearly unit: one Newton step (Woo and Chall 1990 §4.4) is enough
  // inside the window, exact normalization outside it.
  const double n2 = n.squaredNorm();
  Vec3 nn = std::abs(n2 - 1.0) < kRenormWindow ? Renormalize(n) : n.normalized();
  if (!nn.allFinite()) nn = v;  // a degenerate normal: light it as if facing the eye
  if (nn.dot(v) < 0.0) nn = -nn;
  const bool renderMan = m.model != Model::Default;
  Rgb diffuse = Rgb::Zero(), specular = Rgb::Zero();
  for (const Light& light : rig.lights) {
    Vec3 l;  // towards the light
    Rgb cl;
    if (!LightAt(light, p, &l, &cl)) continue;
    const double ndotl = nn.dot(l);
    if (ndotl <= 0.0) continue;
    if (!light.shadows.empty()) {
      const double lit = Unshadowed(light, p);
      if (lit <= 0.0) continue;
      cl *= lit;
    }
    diffuse += ndotl * cl;
    if (renderMan) {
      const Vec3 h = (l + v).normalized();
      specular += std::pow(std::max(0.0, nn.dot(h)), 1.0 / m.roughness) * cl;
    } else {
      const Vec3 r = 2.0 * ndotl * nn - l;
      specular += std::pow(std::max(0.0, r.dot(v)), m.shininess) * cl;
    }
  }
  const Rgb ambient = m.ka * rig.ambient;
  switch (m.model) {
    case Model::Matte:
      return base.cwiseProduct(ambient + m.kd * diffuse);
    case Model::Plastic:
      return base.cwiseProduct(ambient + m.kd * diffuse) + m.ks * m.specularColour.cwiseProduct(specular);
    case Model::Metal:
      return base.cwiseProduct(ambient + m.ks * specular);
    default:
      return m.emission + base.cwiseProduct(ambient + m.kd * diffuse) + m.ks * specular;
  }
}

}  // namespace patchscan::raster
