#include "patch/tessellate.h"

#include <opensubdiv/bfr/tessellation.h>

#include <algorithm>

namespace patchscan {

namespace Bfr = OpenSubdiv::Bfr;

Vec3 WorldNormal(const Surface& s, double u, double v) {
  const Eigen::Matrix3d normalFromObject = s.worldFromObject.linear().inverse().transpose();
  SurfaceDerivs d;
  EvaluateObject(s, u, v, DerivOrder::First, &d);
  Vec3 n = d.dpdu.cross(d.dpdv);
  // Relative to the derivatives' own size: below this the cross product is rounding.
  constexpr double kDegenerateSine = 1e-10;
  if (n.norm() <= kDegenerateSine * d.dpdu.norm() * d.dpdv.norm() || n.norm() == 0.0) {
    auto inward = [](double t) { return t < 0.5 ? kNormalNudge : (t > 0.5 ? -kNormalNudge : 0.0); };
    EvaluateObject(s, u + inward(u), v + inward(v), DerivOrder::First, &d);
    n = d.dpdu.cross(d.dpdv);
  }
  const Vec3 w = normalFromObject * n;
  const double len = w.norm();
  return len > 0.0 ? Vec3(w / len) : Vec3(0, 0, 1);
}

void TessellateUniform(const Surface& s, int rate, std::uint32_t surfaceId, TessMesh* out) {
  rate = std::clamp(rate, 1, kMaxTessRate);
  const Bfr::Parameterization quad(OpenSubdiv::Sdc::SCHEME_CATMARK, 4);
  const Bfr::Tessellation tess(quad, rate, Bfr::Tessellation::Options().SetFacetSize(3));
  std::vector<double> coords(2 * static_cast<size_t>(tess.GetNumCoords()));
  std::vector<int> facets(3 * static_cast<size_t>(tess.GetNumFacets()));
  tess.GetCoords(coords.data());
  tess.GetFacets(facets.data());

  const auto base = static_cast<std::uint32_t>(out->vertices.size());
  for (int k = 0; k < tess.GetNumCoords(); ++k) {
    const double u = coords[2 * k], v = coords[2 * k + 1];
    SurfaceDerivs d;
    EvaluateObject(s, u, v, DerivOrder::Position, &d);
    out->vertices.push_back({s.worldFromObject * d.p, WorldNormal(s, u, v), Vec2(u, v)});
  }
  for (int f = 0; f < tess.GetNumFacets(); ++f) {
    out->triangles.push_back({base + static_cast<std::uint32_t>(facets[3 * f]),
                              base + static_cast<std::uint32_t>(facets[3 * f + 1]),
                              base + static_cast<std::uint32_t>(facets[3 * f + 2])});
    out->surfaceOf.push_back(surfaceId);
  }
}

}  // namespace patchscan
