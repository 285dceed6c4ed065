// A pixel row on its way through the back end, and the shading of its pixels from its
// resolved samples (Woo and Chall 1990 §3.4): shared by the back end's row loops
// (scanline_renderer.cpp, batched_rows.cpp).
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <vector>

#include "raster/scanline_renderer.h"
#include "raster/triangle_store.h"

namespace patchscan::raster::detail {

// A pixel no surface covers: no colour, no coverage, depth +inf (OpenEXR's and prman's
// background), the other AOVs 0 and surface id -1.
inline constexpr std::array<float, kChannels> Background() {
  std::array<float, kChannels> b{};
  b[kChannelZ] = std::numeric_limits<float>::infinity();
  b[kChannelId] = -1.0f;
  return b;
}

// One pixel row on its way through the back end: its sample rows resolved, what their
// samples refer to (the geometry's Rows), its pixels, and the counts of its shading.
template <class Geometry>
struct PixelRow {
  int py = 0, j0 = 0;
  std::vector<std::vector<Sample>> samples;  // aa sample rows of nx * layers
  typename Geometry::Rows refs;
  std::vector<float> pixels;                 // width * kChannels
  Counters stats;
};

// Whether any of the aa x aa samples of the pixel whose first sample column is i0 holds a
// fragment.
inline bool AnyCovered(const std::vector<std::vector<Sample>>& rows, int i0, int aa, int layers) {
  for (int r = 0; r < aa; ++r)
    for (int c = 0; c < aa; ++c)
      if (rows[r][static_cast<size_t>(i0 + c) * layers].handle >= 0) return true;
  return false;
}

// Fragments of one sample closer in depth than this (relative) are one surface met twice,
// for the midpoint depth filter: far below any thickness a shadow's bias could resolve,
// far above the rounding of two solves at one point.
constexpr double kSameDepthRel = 1e-7;

// The depth of the pixel whose first sample column is i0 by `filter` (not Surface) from
// its samples' nearest fragments (the midpoint: their two nearest); +inf where no sample
// counts.
inline float FilteredDepth(const std::vector<std::vector<Sample>>& rows, int i0, int aa, int layers,
                           DepthFilter filter) {
  double lo = INFINITY, hi = 0.0, sum = 0.0;
  int n = 0;
  for (int r = 0; r < aa; ++r)
    for (int c = 0; c < aa; ++c) {
      const Sample* keep = &rows[r][static_cast<size_t>(i0 + c) * layers];
      if (keep[0].handle < 0) continue;
      double w = 1.0 / keep[0].invW;
      if (filter == DepthFilter::Midpoint) {
        // The next surface: a fragment at the nearest's depth is that surface again (a
        // quadric's seam gives one from each side of it).
        int next = 1;
        while (next < layers && keep[next].handle >= 0 && keep[next].invW >= keep[0].invW * (1.0 - kSameDepthRel)) ++next;
        w = next < layers && keep[next].handle >= 0 ? 0.5 * (w + 1.0 / keep[next].invW) : INFINITY;
      }
      lo = std::min(lo, w);
      hi = std::max(hi, w);
      sum += w;
      ++n;
    }
  const double depth = filter == DepthFilter::Max ? hi : filter == DepthFilter::Average && n > 0 ? sum / n : lo;
  return static_cast<float>(depth);
}

// Pixel px of a resolved row: its samples grouped by surface and layer, one shading call
// per group plus the adaptive-stochastic extra calls, and the AOVs. Reads the row and the
// geometry only, so rows are shaded on any thread in any order.
template <class Geometry>
void ShadePixel(const Geometry& geo, const RenderSettings& s, const Lattice& lat, int layers,
                PixelRow<Geometry>& pr, int px) {
  static constexpr std::array<float, kChannels> background = Background();
  const int perPixel = s.aa * s.aa;
  // Paper 000 §3.4.2: each covered sample is shaded on its own with probability
  // P = (l - 1) / (l^2 - 1) = 1 / (l + 1); a colour that differs from the pixel's one
  // shading call by more than kShadeDiscrepancy makes the pixel shade every sample.
  const double extraP = s.aa > 1 ? 1.0 / (s.aa + 1) : 0.0;
  Counters& stats = pr.stats;
  float* out = &pr.pixels[static_cast<size_t>(px) * kChannels];
  const int i0 = lat.FirstOfPixel(px);
  if (!AnyCovered(pr.samples, i0, s.aa, layers)) {
    std::copy(background.begin(), background.end(), out);  // most pixels of most frames
    return;
  }
  // The AOVs of the surface covering most of the pixel, from the fragment its shading call
  // took.
  const auto writeAovs = [out](const Fragment& a, std::uint32_t surface) {
    const Vec3 nrm = a.normal.normalized();
    out[kChannelZ] = static_cast<float>(a.w);
    for (int k = 0; k < 3; ++k) out[kChannelN + k] = static_cast<float>(nrm.allFinite() ? nrm[k] : 0.0);
    out[kChannelUv] = static_cast<float>(a.uv.x());
    out[kChannelUv + 1] = static_cast<float>(a.uv.y());
    out[kChannelId] = static_cast<float>(surface);
  };
  if (s.aa == 1 && layers == 1 && !s.hiddenLine) {
    // One sample, one layer: the pixel is one group of one sample, shaded as below (the
    // same arithmetic, term for term) without the grouping.
    const Sample& smp = pr.samples[0][static_cast<size_t>(i0)];
    const std::uint32_t surface = geo.SurfaceOf(pr.refs, 0, smp);
    const double opacity = s.opacity * s.MaterialOf(surface).opacity;
    ++stats[Counter::SamplesCovered];
    const Member m{0, i0, smp};
    Fragment f;
    const Rgb rgb = geo.ShadeGroup(pr.refs, &m, 1, lat.At(i0), lat.At(pr.j0), stats[Counter::ShadingCalls], &f);
    const double through = 1.0 - opacity, alpha = 1.0 - through;
    Rgb colour = Rgb::Zero();
    colour += opacity * rgb;
    for (int k = 0; k < 3; ++k) out[k] = static_cast<float>(colour[k]);
    out[3] = static_cast<float>(alpha);
    if (s.aovs)
      writeAovs(f, surface);
    else
      std::copy(background.begin() + 4, background.end(), out + 4);
    if (s.depthFilter != DepthFilter::Surface) out[kChannelZ] = FilteredDepth(pr.samples, i0, s.aa, layers, s.depthFilter);
    return;
  }
  // Group the pixel's samples by surface and layer: one shading call per group.
  struct Group {
    std::uint32_t surface;
    int layer;
    int count;
    double sx, sy;
    double weight;  // summed over its samples: opacity times the light the layers in front pass
    Rgb rgb;
  };
  std::array<Group, kMaxAa * kMaxAa * kMaxLayers> groups;
  std::array<Member, kMaxAa * kMaxAa * kMaxLayers> members;
  std::array<int, kMaxAa * kMaxAa * kMaxLayers> memberGroup;
  std::array<int, kMaxAa * kMaxAa> groupOf;  // per sample, its nearest layer's; -1: none
  int nGroups = 0, nMembers = 0, covered = 0, onLines = 0;
  double alpha = 0.0;  // summed over samples: 1 - (1 - opacity)^(fragments)
  for (int r = 0; r < s.aa; ++r)
    for (int c = 0; c < s.aa; ++c) {
      const Sample* keep = &pr.samples[r][static_cast<size_t>(i0 + c) * layers];
      groupOf[r * s.aa + c] = -1;
      if (keep[0].handle < 0) continue;
      ++covered;
      const double x = lat.At(i0 + c), y = lat.At(pr.j0 + r);
      if (s.hiddenLine && geo.EdgeDistance(pr.refs, r, keep[0], x, y) < kLineHalfWidth) ++onLines;
      double through = 1.0;  // light passing the layers in front
      for (int layer = 0; layer < layers && keep[layer].handle >= 0; ++layer) {
        const std::uint32_t surface = geo.SurfaceOf(pr.refs, r, keep[layer]);
        int g = 0;
        while (g < nGroups && (groups[g].surface != surface || groups[g].layer != layer)) ++g;
        if (g == nGroups) groups[nGroups++] = {surface, layer, 0, 0.0, 0.0, 0.0, Rgb::Zero()};
        if (layer == 0) groupOf[r * s.aa + c] = g;
        const double opacity = s.opacity * s.MaterialOf(surface).opacity;
        ++groups[g].count;
        groups[g].sx += x;
        groups[g].sy += y;
        groups[g].weight += opacity * through;
        members[nMembers] = {r, i0 + c, keep[layer]};
        memberGroup[nMembers++] = g;
        through *= 1.0 - opacity;
      }
      alpha += 1.0 - through;
    }
  // The members of group g, gathered in place at the front of `gathered`.
  std::array<Member, kMaxAa * kMaxAa> gathered;
  auto gather = [&](int g) {
    int n = 0;
    for (int k = 0; k < nMembers; ++k)
      if (memberGroup[k] == g) gathered[n++] = members[k];
    return n;
  };
  stats[Counter::SamplesCovered] += covered;
  // The AOVs are of the surface that covers most of the pixel, at its samples' centroid:
  // the fragment its shading call takes (hidden-line mode, which shades none, asks for it).
  int major = -1;
  for (int g = 0; g < nGroups; ++g)
    if (groups[g].layer == 0 && (major < 0 || groups[g].count > groups[major].count)) major = g;
  Fragment majorFragment, shaded;
  bool haveMajor = false;
  Rgb colour = Rgb::Zero();
  if (s.hiddenLine) {
    // White surfaces, black triangle edges, no shading.
    colour = Rgb::Constant(static_cast<double>(covered - onLines) / perPixel);
    alpha = covered;
  } else {
    bool superSample = false;
    for (int g = 0; g < nGroups; ++g) {
      // Linear transparency: a layer of opacity a seen through layers of opacities
      // a_j contributes a prod (1 - a_j) of its colour at each sample.
      Group& gr = groups[g];
      const int n = gather(g);
      gr.rgb = geo.ShadeGroup(pr.refs, gathered.data(), n, gr.sx / gr.count, gr.sy / gr.count,
                              stats[Counter::ShadingCalls], g == major ? &majorFragment : &shaded);
      colour += (gr.weight / perPixel) * gr.rgb;
      haveMajor |= g == major;
    }
    // Only the (l-1) x (l-1) samples a pixel owns (not its right and bottom edges, which
    // belong to the neighbours) draw, so each sample draws once.
    // With transparency the extra calls are not made (one call per surface and layer).
    for (int k = 0; k < perPixel && !superSample && extraP > 0 && layers == 1; ++k) {
      const int r = k / s.aa, c = k % s.aa;
      if (r == s.aa - 1 || c == s.aa - 1 || groupOf[k] < 0 ||
          UnitHash(s.seed, pr.j0 + r, i0 + c) >= extraP)
        continue;
      const Sample& smp = pr.samples[r][static_cast<size_t>(i0 + c) * layers];
      const Rgb rgb = geo.ShadeSample(pr.refs, r, smp, lat.At(i0 + c), lat.At(pr.j0 + r), stats[Counter::ExtraShadingCalls]);
      superSample = (rgb - groups[groupOf[k]].rgb).cwiseAbs().maxCoeff() > kShadeDiscrepancy;
    }
    if (superSample) {
      ++stats[Counter::SuperSampledPixels];
      colour = Rgb::Zero();
      for (int k = 0; k < perPixel; ++k) {
        if (groupOf[k] < 0) continue;
        const int r = k / s.aa;
        const Sample& smp = pr.samples[r][static_cast<size_t>(i0 + k % s.aa) * layers];
        colour += geo.ShadeSample(pr.refs, r, smp, lat.At(i0 + k % s.aa), lat.At(pr.j0 + r),
                                  stats[Counter::ExtraShadingCalls]) / perPixel;
      }
    }
  }
  for (int k = 0; k < 3; ++k) out[k] = static_cast<float>(colour[k]);
  out[3] = static_cast<float>(alpha / perPixel);
  if (major < 0 || !s.aovs) {
    std::copy(background.begin() + 4, background.end(), out + 4);
  } else {
    const Group& gr = groups[major];
    if (!haveMajor)
      majorFragment = geo.GroupFragment(pr.refs, gathered.data(), gather(major), gr.sx / gr.count, gr.sy / gr.count);
    writeAovs(majorFragment, gr.surface);
  }
  if (s.depthFilter != DepthFilter::Surface) out[kChannelZ] = FilteredDepth(pr.samples, i0, s.aa, layers, s.depthFilter);
}

}  // namespace patchscan::raster::detail
