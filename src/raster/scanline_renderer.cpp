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

// Screen distance in pixels from (x, y) to the nearest edge line of a triangle: each
// oriented edge is an affine function of screen position, so |e| / |grad e| is exact.
double EdgeDistance(const TriangleSetup& t, double x, double y) {
  double d = INFINITY;
  for (const Vec3& e : t.edge)
    d = std::min(d, std::abs(e.x() * x + e.y() * y + e.z()) / std::hypot(e.x(), e.y()));
  return d;
}

// A uniform number in [0, 1) from a seed and a sample's lattice position (splitmix64):
// the same for the same render whatever order the samples are visited in.
double UnitHash(std::uint64_t seed, int j, int i) {
  std::uint64_t z = seed + 0x9E3779B97F4A7C15ull * (static_cast<std::uint64_t>(j) * 0x100000001B3ull +
                                                     static_cast<std::uint64_t>(i) + 1);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  z ^= z >> 31;
  return static_cast<double>(z >> 11) * 0x1.0p-53;
}

// Half the width of a hidden-line mode line, in pixels.
constexpr double kLineHalfWidth = 0.6;
// A stochastic extra shading call that differs from the pixel's shading call by more than
// this in any channel (colours near 1 at full intensity) marks a highlight or texture
// detail that one call per pixel would alias.
constexpr double kShadeDiscrepancy = 0.08;

}  // namespace

std::optional<RenderStats> RenderMesh(const TriangleMesh& mesh, const RenderSettings& s,
                                      RowSink& sink) {
  RenderStats stats;
  stats.nTriangles = static_cast<std::int64_t>(mesh.triangles.size());
  const Lattice lat(s);
  const double invHither = 1.0 / s.hither;
  bool failed = false;  // a texture could not be read: stop after this row

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
  freeSlots.reserve(1024);
  // With transparency each sample keeps its `layers` nearest fragments, nearest first.
  const int layers = s.opacity < 1.0 ? kMaxLayers : 1;
  std::vector<std::vector<Sample>> rows(s.aa, std::vector<Sample>(static_cast<size_t>(lat.nx) * layers));
  std::vector<float> pixels(static_cast<size_t>(s.width) * kChannels);
  size_t nextY = 0;

  // Perspective-correct attributes of an active triangle at (x, y).
  struct Attributes {
    Vec3 b, position, normal;
    Vec2 uv, duvdx, duvdy;  // uv and its change per pixel in x and y
    double w;
  };
  auto interpolate = [&](const ActiveTriangle& at, double x, double y) {
    const RasterTriangle& t = mesh.triangles[at.index];
    const RasterVertex &v0 = mesh.vertices[t.v[0]], &v1 = mesh.vertices[t.v[1]],
                       &v2 = mesh.vertices[t.v[2]];
    Attributes a;
    Vec3 e;
    for (int i = 0; i < 3; ++i) e[i] = at.setup.edge[i].x() * x + at.setup.edge[i].y() * y + at.setup.edge[i].z();
    const double sum = e.sum();
    a.b = sum != 0.0 ? Vec3(e / sum) : Vec3::Constant(1.0 / 3);
    a.w = sum != 0.0 ? 1.0 / (sum * std::abs(at.setup.invDet)) : 0.0;
    a.position = a.b[0] * v0.position + a.b[1] * v1.position + a.b[2] * v2.position;
    a.uv = a.b[0] * v0.uv + a.b[1] * v1.uv + a.b[2] * v2.uv;
    // uv = sum(uv_i e_i) / sum(e) with each e_i affine in (x, y): the quotient rule.
    if (sum != 0.0) {
      for (int axis = 0; axis < 2; ++axis) {
        Vec2 numerator = Vec2::Zero();
        double grad = 0.0;
        for (int i = 0; i < 3; ++i) {
          const double g = at.setup.edge[i][axis];
          numerator += g * mesh.vertices[t.v[i]].uv;
          grad += g;
        }
        (axis == 0 ? a.duvdx : a.duvdy) = (numerator - a.uv * grad) / sum;
      }
    } else {
      a.duvdx = a.duvdy = Vec2::Zero();
    }
    a.normal = s.shading == ShadingMode::Flat
                   ? Vec3((v1.position - v0.position).cross(v2.position - v0.position))
                   : Vec3(a.b[0] * v0.normal + a.b[1] * v1.normal + a.b[2] * v2.normal);
    return a;
  };
  auto shadeAt = [&](const ActiveTriangle& at, double x, double y, std::int64_t& nCalls) -> Rgb {
    const Attributes a = interpolate(at, x, y);
    if (s.shading == ShadingMode::Gouraud)
      return a.b[0] * at.vertexColour[0] + a.b[1] * at.vertexColour[1] + a.b[2] * at.vertexColour[2];
    ++nCalls;
    const auto base = SurfaceColour(s.material, a.uv, a.duvdx, a.duvdy);
    if (!base) failed = true;
    return Shade(a.position, a.normal, base.value_or(Rgb::Zero()), s.eye, s.material, s.lights);
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
          const auto base = SurfaceColour(s.material, v.uv, Vec2::Zero(), Vec2::Zero());
          if (!base) failed = true;
          at.vertexColour[k] = Shade(v.position, v.normal, base.value_or(Rgb::Zero()), s.eye,
                                     s.material, s.lights);
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
        Sample* keep = &row[static_cast<size_t>(i) * layers];
        if (!(invW > keep[layers - 1].invW)) continue;
        int at = layers - 1;  // insertion into the sorted layers, dropping the farthest
        for (; at > 0 && invW > keep[at - 1].invW; --at) keep[at] = keep[at - 1];
        keep[at] = {invW, static_cast<std::int32_t>(k)};
      }
    }
  };

  // Step 3: pixel rows.
  const int perPixel = s.aa * s.aa;
  // Paper 000 §3.4.2: each covered sample is shaded on its own with probability
  // P = (l - 1) / (l^2 - 1) = 1 / (l + 1); a colour that differs from the pixel's one
  // shading call by more than kShadeDiscrepancy makes the pixel shade every sample.
  const double extraP = s.aa > 1 ? 1.0 / (s.aa + 1) : 0.0;
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
        int layer;
        int count;
        double sx, sy;
        int active;
        Rgb rgb;
      };
      std::array<Group, kMaxAa * kMaxAa * kMaxLayers> groups;
      std::array<int, kMaxAa * kMaxAa> groupOf;  // per sample, its nearest layer's; -1: none
      int nGroups = 0, covered = 0, onLines = 0;
      double alpha = 0.0;  // summed over samples: 1 - (1 - opacity)^(fragments)
      const int i0 = lat.FirstOfPixel(px);
      for (int r = 0; r < s.aa; ++r)
        for (int c = 0; c < s.aa; ++c) {
          const Sample* keep = &rows[r][static_cast<size_t>(i0 + c) * layers];
          groupOf[r * s.aa + c] = -1;
          if (keep[0].active < 0) continue;
          ++covered;
          const double x = lat.At(i0 + c), y = lat.At(j0 + r);
          if (s.hiddenLine && EdgeDistance(active[keep[0].active].setup, x, y) < kLineHalfWidth) ++onLines;
          double through = 1.0;  // light passing the layers in front
          for (int layer = 0; layer < layers && keep[layer].active >= 0; ++layer) {
            const std::uint32_t surface = mesh.triangles[active[keep[layer].active].index].surfaceId;
            int g = 0;
            while (g < nGroups && (groups[g].surface != surface || groups[g].layer != layer)) ++g;
            if (g == nGroups)
              groups[nGroups++] = {surface, layer, 0, 0.0, 0.0, keep[layer].active, Rgb::Zero()};
            if (layer == 0) groupOf[r * s.aa + c] = g;
            ++groups[g].count;
            groups[g].sx += x;
            groups[g].sy += y;
            through *= 1.0 - s.opacity;
          }
          alpha += 1.0 - through;
        }
      stats.nSamplesCovered += covered;
      Rgb colour = Rgb::Zero();
      if (s.hiddenLine) {
        // White surfaces, black triangle edges, no shading.
        colour = Rgb::Constant(static_cast<double>(covered - onLines) / perPixel);
        alpha = covered;
      } else {
        bool superSample = false;
        for (int g = 0; g < nGroups; ++g) {
          // Linear transparency: layer k is seen through k layers of opacity a, and
          // contributes a (1 - a)^k of its colour.
          Group& gr = groups[g];
          gr.rgb = shadeAt(active[gr.active], gr.sx / gr.count, gr.sy / gr.count, stats.nShadingCalls);
          const double weight = s.opacity * std::pow(1.0 - s.opacity, gr.layer);
          colour += (weight * gr.count / perPixel) * gr.rgb;
        }
        // Only the (l-1) x (l-1) samples a pixel owns (not its right and bottom edges, which
        // belong to the neighbours) draw, so each sample draws once.
        // With transparency the extra calls are not made (one call per surface and layer).
        for (int k = 0; k < perPixel && !superSample && extraP > 0 && layers == 1; ++k) {
          const int r = k / s.aa, c = k % s.aa;
          if (r == s.aa - 1 || c == s.aa - 1 || groupOf[k] < 0 ||
              UnitHash(s.seed, j0 + r, i0 + c) >= extraP)
            continue;
          const Sample& smp = rows[r][static_cast<size_t>(i0 + c) * layers];
          const Rgb rgb = shadeAt(active[smp.active], lat.At(i0 + c), lat.At(j0 + r), stats.nExtraShadingCalls);
          superSample = (rgb - groups[groupOf[k]].rgb).cwiseAbs().maxCoeff() > kShadeDiscrepancy;
        }
        if (superSample) {
          ++stats.nSuperSampledPixels;
          colour = Rgb::Zero();
          for (int k = 0; k < perPixel; ++k) {
            if (groupOf[k] < 0) continue;
            const Sample& smp = rows[k / s.aa][static_cast<size_t>(i0 + k % s.aa) * layers];
            colour += shadeAt(active[smp.active], lat.At(i0 + k % s.aa), lat.At(j0 + k / s.aa),
                              stats.nExtraShadingCalls) / perPixel;
          }
        }
      }
      float* out = &pixels[static_cast<size_t>(px) * kChannels];
      for (int k = 0; k < 3; ++k) out[k] = static_cast<float>(colour[k]);
      out[3] = static_cast<float>(alpha / perPixel);
      // AOVs of the surface that covers most of the pixel, at its samples' centroid.
      int major = -1;
      for (int g = 0; g < nGroups; ++g)
        if (groups[g].layer == 0 && (major < 0 || groups[g].count > groups[major].count)) major = g;
      if (major < 0) {
        std::fill(out + 4, out + kChannels, 0.0f);
        out[kChannelId] = -1.0f;
      } else {
        const Group& gr = groups[major];
        const Attributes a = interpolate(active[gr.active], gr.sx / gr.count, gr.sy / gr.count);
        const Vec3 n = a.normal.normalized();
        out[kChannelZ] = static_cast<float>(a.w);
        for (int k = 0; k < 3; ++k) out[kChannelN + k] = static_cast<float>(n.allFinite() ? n[k] : 0.0);
        out[kChannelUv] = static_cast<float>(a.uv.x());
        out[kChannelUv + 1] = static_cast<float>(a.uv.y());
        out[kChannelId] = static_cast<float>(gr.surface);
      }
    }
    if (failed || !sink.WriteRow(py, pixels.data())) return std::nullopt;
  }
  return stats;
}

}  // namespace patchscan::raster
