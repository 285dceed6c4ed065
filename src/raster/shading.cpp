#include "raster/shading.h"

#include <cmath>

namespace patchscan::raster {

LightRig DefaultLightRig(const Vec3& forward, const Vec3& up, const Vec3& right) {
  LightRig rig;
  rig.ambient = Rgb(0.9, 0.92, 1.0);
  // Directions the light travels (from the light towards the scene).
  rig.lights.push_back({Light::Kind::Directional, (forward + right - 1.2 * up).normalized(),
                        Rgb(0.95, 0.9, 0.82)});
  rig.lights.push_back({Light::Kind::Directional, (forward - 1.5 * right + 0.2 * up).normalized(),
                        Rgb(0.25, 0.3, 0.4)});
  rig.lights.push_back({Light::Kind::Directional, (-forward - 0.5 * up).normalized(),
                        Rgb(0.3, 0.3, 0.3)});
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

Rgb Shade(const Vec3& p, const Vec3& n, const Rgb& base, const Vec3& eye, const Material& m,
          const LightRig& rig) {
  const Vec3 v = (eye - p).normalized();
  // Interpolated unit normals are nearly unit: one Newton step (paper 000 §4.4) is enough
  // inside the window, exact normalization outside it.
  const double n2 = n.squaredNorm();
  Vec3 nn = std::abs(n2 - 1.0) < kRenormWindow ? Renormalize(n) : n.normalized();
  if (!nn.allFinite()) nn = v;  // a degenerate normal: light it as if facing the eye
  if (nn.dot(v) < 0.0) nn = -nn;
  Rgb c = m.emission + m.ka * base.cwiseProduct(rig.ambient);
  for (const Light& light : rig.lights) {
    Vec3 l;  // towards the light
    double fall = 1.0;
    if (light.kind == Light::Kind::Directional) {
      l = -light.vector.normalized();
    } else {
      l = light.vector - p;
      const double d2 = l.squaredNorm();
      l /= std::sqrt(d2);
      fall = 1.0 / (1.0 + light.attenuation * d2);
    }
    const double ndotl = nn.dot(l);
    if (ndotl <= 0.0) continue;
    const Vec3 r = 2.0 * ndotl * nn - l;
    const double spec = std::pow(std::max(0.0, r.dot(v)), m.shininess);
    c += fall * (m.kd * ndotl * base + m.ks * spec * Rgb(1, 1, 1)).cwiseProduct(light.intensity);
  }
  return c;
}

}  // namespace patchscan::raster
