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

#include <cmath>
#include <unordered_map>

namespace patchscan {

std::size_t WeldBoundaryVertices(TessMesh* mesh, double tolerance) {
  // A hash grid of cell size `tolerance`: a match lies in one of the 27 cells around.
  struct Key {
    long long x, y, z;
    bool operator==(const Key&) const = default;
  };
  struct KeyHash {
    size_t operator()(const Key& k) const {
      return std::hash<long long>()(k.x * 73856093LL ^ k.y * 19349663LL ^ k.z * 83492791LL);
    }
  };
  if (!(tolerance > 0.0)) return 0;
  std::unordered_map<Key, std::vector<std::uint32_t>, KeyHash> grid;
  auto cell = [&](const Vec3& p) {
    return Key{static_cast<long long>(std::floor(p.x() / tolerance)),
               static_cast<long long>(std::floor(p.y() / tolerance)),
               static_cast<long long>(std::floor(p.z() / tolerance))};
  };
  std::size_t moved = 0;
  for (std::uint32_t i = 0; i < mesh->vertices.size(); ++i) {
    TessVertex& v = mesh->vertices[i];
    if (!(v.uv.x() == 0 || v.uv.x() == 1 || v.uv.y() == 0 || v.uv.y() == 1)) continue;
    const Key c = cell(v.position);
    const TessVertex* match = nullptr;
    for (long long dz = -1; dz <= 1 && !match; ++dz)
      for (long long dy = -1; dy <= 1 && !match; ++dy)
        for (long long dx = -1; dx <= 1 && !match; ++dx) {
          auto it = grid.find({c.x + dx, c.y + dy, c.z + dz});
          if (it == grid.end()) continue;
          for (std::uint32_t j : it->second)
            if ((mesh->vertices[j].position - v.position).norm() <= tolerance) {
              match = &mesh->vertices[j];
              break;
            }
        }
    if (match) {
      if (match->position != v.position) ++moved;
      v.position = match->position;
    } else {
      grid[c].push_back(i);
    }
  }
  return moved;
}

}  // namespace patchscan
