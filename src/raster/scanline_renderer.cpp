#include "raster/scanline_renderer.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>

#include "raster/triangle_setup.h"

namespace patchscan::raster {
namespace {

// The sample lattice: with l = 1 one sample at each pixel centre; with l > 1 samples at
// spacing 1/(l-1) from the image's top-left corner, so a pixel's l x l samples include its
// edges and corners, shared with its neighbours (paper 000 §3.3).
struct Lattice {
  int l;
  double spacing, offset;
  int nx, ny;
  explicit Lattice(const RenderSettings& s)
      : l(s.aa),
        spacing(s.aa == 1 ? 1.0 : 1.0 / (s.aa - 1)),
        offset(s.aa == 1 ? 0.5 : 0.0),
        nx(s.aa == 1 ? s.width : s.width * (s.aa - 1) + 1),
        ny(s.aa == 1 ? s.height : s.height * (s.aa - 1) + 1) {}
  double At(int i) const { return offset + i * spacing; }
  int FirstOfPixel(int p) const { return l == 1 ? p : p * (l - 1); }
  // First and last sample index at or after lo, at or before hi, clamped to [0, n).
  int Ceil(double lo, int n) const {
    return std::clamp(static_cast<int>(std::ceil((lo - offset) / spacing)), 0, n);
  }
  int Floor(double hi, int n) const {
    return std::clamp(static_cast<int>(std::floor((hi - offset) / spacing)), -1, n - 1);
  }
};

struct Sample {
  double invW;          // 1 / w of the nearest surface; 0: nothing covers the sample
  std::int32_t active;  // slot of that nearest triangle in the active store; -1: none
};

struct ActiveTriangle {
  TriangleSetup setup;
  std::uint32_t index;  // into mesh.triangles
  int lastRow;
  Rgb vertexColour[3];  // Gouraud only
};

// Barycentric coordinates of (x, y) for a set-up triangle: b_i = e_i / sum e.
Vec3 Barycentric(const TriangleSetup& t, double x, double y) {
  Vec3 e;
  for (int i = 0; i < 3; ++i) e[i] = t.edge[i].x() * x + t.edge[i].y() * y + t.edge[i].z();
  const double sum = e.sum();
  return sum != 0.0 ? Vec3(e / sum) : Vec3(1.0 / 3, 1.0 / 3, 1.0 / 3);
}

}  // namespace

std::optional<RenderStats> RenderMesh(const TriangleMesh& mesh, const RenderSettings& s,
                                      RowSink& sink) {
  RenderStats stats;
  stats.nTriangles = static_cast<std::int64_t>(mesh.triangles.size());
  const Lattice lat(s);
  const double invHither = 1.0 / s.hither;

  // Step 1: the y-sorted list: each triangle's first and last sample row.
  struct YEntry {
    int first, last;
    std::uint32_t index;
  };
  std::vector<YEntry> ySorted;
  ySorted.reserve(mesh.triangles.size());
  for (std::uint32_t k = 0; k < mesh.triangles.size(); ++k) {
    const RasterTriangle& t = mesh.triangles[k];
    const Vec3 &a = mesh.vertices[t.v[0]].h, &b = mesh.vertices[t.v[1]].h, &c = mesh.vertices[t.v[2]].h;
    double yMin = 0, yMax = s.height;
    if (a.z() > 0 && b.z() > 0 && c.z() > 0) {
      yMin = std::min({a.y() / a.z(), b.y() / b.z(), c.y() / c.z()});
      yMax = std::max({a.y() / a.z(), b.y() / b.z(), c.y() / c.z()});
    }
    const int first = lat.Ceil(yMin, lat.ny), last = lat.Floor(yMax, lat.ny);
    if (first <= last) ySorted.push_back({first, last, k});
  }
  std::stable_sort(ySorted.begin(), ySorted.end(),
                   [](const YEntry& p, const YEntry& q) { return p.first < q.first; });

  // Step 2: buffers sized by the image width, reused for every row. Active triangles live
  // in slots that do not move while a sample refers to them: a triangle is retired at the
  // start of the first pixel row none of whose sample rows it reaches.
  std::vector<ActiveTriangle> active;  // the slots
  std::vector<int> live, freeSlots;
  active.reserve(1024);
  live.reserve(1024);
  std::vector<std::vector<Sample>> rows(s.aa, std::vector<Sample>(lat.nx));
  std::vector<float> rgba(static_cast<size_t>(s.width) * 4);
  size_t nextY = 0;

  auto shadeAt = [&](const ActiveTriangle& at, double x, double y) -> Rgb {
    const RasterTriangle& t = mesh.triangles[at.index];
    const RasterVertex *v0 = &mesh.vertices[t.v[0]], *v1 = &mesh.vertices[t.v[1]],
                       *v2 = &mesh.vertices[t.v[2]];
    const Vec3 b = Barycentric(at.setup, x, y);
    if (s.shading == ShadingMode::Gouraud)
      return b[0] * at.vertexColour[0] + b[1] * at.vertexColour[1] + b[2] * at.vertexColour[2];
    ++stats.nShadingCalls;
    const Vec3 p = b[0] * v0->position + b[1] * v1->position + b[2] * v2->position;
    const Vec2 uv = b[0] * v0->uv + b[1] * v1->uv + b[2] * v2->uv;
    const Vec3 n = s.shading == ShadingMode::Flat
                       ? Vec3((v1->position - v0->position).cross(v2->position - v0->position))
                       : Vec3(b[0] * v0->normal + b[1] * v1->normal + b[2] * v2->normal);
    return Shade(p, n, uv, s.eye, s.material, s.lights);
  };

  // Resolve one sample row: nearest triangle per sample.
  auto scanRow = [&](int j, std::vector<Sample>& row) {
    // Activate the triangles whose first sample row this is.
    for (; nextY < ySorted.size() && ySorted[nextY].first <= j; ++nextY) {
      const YEntry& y = ySorted[nextY];
      const RasterTriangle& t = mesh.triangles[y.index];
      const auto setup = SetupTriangle(mesh.vertices[t.v[0]].h, mesh.vertices[t.v[1]].h,
                                       mesh.vertices[t.v[2]].h, s.cullBackFaces, s.width, s.height);
      if (!setup) continue;
      ++stats.nTrianglesSetUp;
      ActiveTriangle at{*setup, y.index, y.last, {}};
      if (s.shading == ShadingMode::Gouraud)
        for (int k = 0; k < 3; ++k) {
          const RasterVertex& v = mesh.vertices[t.v[k]];
          at.vertexColour[k] = Shade(v.position, v.normal, v.uv, s.eye, s.material, s.lights);
          ++stats.nShadingCalls;
        }
      int slot;
      if (!freeSlots.empty()) {
        slot = freeSlots.back();
        freeSlots.pop_back();
        active[slot] = at;
      } else {
        slot = static_cast<int>(active.size());
        active.push_back(at);
      }
      live.push_back(slot);
    }
    stats.maxActive = std::max<std::int64_t>(stats.maxActive, static_cast<std::int64_t>(live.size()));

    std::fill(row.begin(), row.end(), Sample{0.0, -1});
    const double y = lat.At(j);
    for (const int k : live) {
      if (active[k].lastRow < j) continue;  // done, retired at the next pixel row
      const TriangleSetup& t = active[k].setup;
      // The span: each edge, and the hither edge sum(e) <= |det| / hither, is a half-line.
      double lo = -INFINITY, hi = INFINITY;
      Vec3 sum = Vec3::Zero();
      auto clip = [&](double a, double c) {  // a x + c >= 0
        if (a > 0) lo = std::max(lo, -c / a);
        else if (a < 0) hi = std::min(hi, -c / a);
        else if (c < 0) hi = -INFINITY;
      };
      for (const Vec3& e : t.edge) {
        clip(e.x(), e.y() * y + e.z());
        sum += e;
      }
      const double absDet = 1.0 / std::abs(t.invDet);
      clip(-sum.x(), absDet * invHither - (sum.y() * y + sum.z()));
      // One sample of slack each side: the exact test below decides.
      const int i0 = std::max(0, lat.Ceil(lo, lat.nx) - 1), i1 = std::min(lat.nx - 1, lat.Floor(hi, lat.nx) + 1);
      for (int i = i0; i <= i1; ++i) {
        const double x = lat.At(i);
        double e[3];
        ++stats.nSamplesTested;
        if (!Inside(t, x, y, e)) continue;
        const double invW = (e[0] + e[1] + e[2]) * std::abs(t.invDet);
        if (!(invW <= invHither)) continue;  // nearer than the hither plane
        if (invW > row[i].invW) row[i] = {invW, static_cast<std::int32_t>(k)};
      }
    }
  };

  // Step 3: pixel rows.
  const int perPixel = s.aa * s.aa;
  for (int py = 0; py < s.height; ++py) {
    const int j0 = lat.FirstOfPixel(py);
    std::erase_if(live, [&](int k) {
      if (active[k].lastRow >= j0) return false;
      freeSlots.push_back(k);
      return true;
    });
    for (int r = 0; r < s.aa; ++r) {
      if (r == 0 && py > 0 && s.aa > 1) {
        std::swap(rows[0], rows[s.aa - 1]);  // the shared edge row, already resolved
        continue;
      }
      scanRow(j0 + r, rows[r]);
    }
    for (int px = 0; px < s.width; ++px) {
      // Group the pixel's samples by surface: one shading call per visible surface.
      struct Group {
        std::uint32_t surface;
        int count;
        double sx, sy;
        int active;
      };
      std::array<Group, kMaxAa * kMaxAa> groups;
      int nGroups = 0, covered = 0;
      const int i0 = lat.FirstOfPixel(px);
      for (int r = 0; r < s.aa; ++r)
        for (int c = 0; c < s.aa; ++c) {
          const Sample& smp = rows[r][i0 + c];
          if (smp.active < 0) continue;
          ++covered;
          const std::uint32_t surface = mesh.triangles[active[smp.active].index].surfaceId;
          int g = 0;
          while (g < nGroups && groups[g].surface != surface) ++g;
          if (g == nGroups) groups[nGroups++] = {surface, 0, 0.0, 0.0, smp.active};
          ++groups[g].count;
          groups[g].sx += lat.At(i0 + c);
          groups[g].sy += lat.At(j0 + r);
        }
      stats.nSamplesCovered += covered;
      Rgb colour = Rgb::Zero();
      for (int g = 0; g < nGroups; ++g) {
        const Group& gr = groups[g];
        colour += (static_cast<double>(gr.count) / perPixel) *
                  shadeAt(active[gr.active], gr.sx / gr.count, gr.sy / gr.count);
      }
      float* out = &rgba[static_cast<size_t>(px) * 4];
      for (int k = 0; k < 3; ++k) out[k] = static_cast<float>(colour[k]);
      out[3] = static_cast<float>(static_cast<double>(covered) / perPixel);
    }
    if (!sink.WriteRow(py, rgba.data())) return std::nullopt;
  }
  return stats;
}

}  // namespace patchscan::raster
