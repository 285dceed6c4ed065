#include "raster/scanline_renderer.h"
#include "raster/work_arena.h"

#include <algorithm>
#include <limits>
#include <array>
#include <chrono>
#include <cmath>
#include <memory>

#include <oneapi/tbb/info.h>
#include <oneapi/tbb/task_arena.h>
#include <oneapi/tbb/task_group.h>

#include "raster/row_geometry.h"
#include "raster/triangle_store.h"

namespace patchscan::raster {
namespace {

using detail::FragmentGeometry;
using detail::TriangleGeometry;

// A pixel no surface covers: no colour, no coverage, depth +inf (OpenEXR's and prman's
// background), the other AOVs 0 and surface id -1.
constexpr std::array<float, kChannels> Background() {
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
bool AnyCovered(const std::vector<std::vector<Sample>>& rows, int i0, int aa, int layers) {
  for (int r = 0; r < aa; ++r)
    for (int c = 0; c < aa; ++c)
      if (rows[r][static_cast<size_t>(i0 + c) * layers].handle >= 0) return true;
  return false;
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
}

// The pixel rows, for either geometry, in three stages: each row's sample rows resolved
// (in order: the scan and the active triangles move down the image), its pixels shaded
// (any row, on any thread), and the row handed to the sink (in order). Resolving and
// handing over stay on the calling thread (a source or sink may be bound to it, as MPI's
// are); with threads, each row is shaded as a task while the next rows are resolved, a few
// rows in flight, so memory stays O(width x threads).
template <class Geometry>
std::optional<Counters> RenderRows(Geometry& geo, const RenderSettings& s, const Lattice& lat,
                                      int layers, Counters& stats, RowSink& sink, BackEndTimes* times) {
  const int threads = s.threads > 1 ? std::min(s.threads, tbb::info::default_concurrency()) : 1;
  // Each thread's shading seconds in a slot of its own (its index in the arena, sized
  // below), so no two threads write one; the serial parts' on the calling thread.
  BackEndTimes timed;
  timed.shading.assign(1, 0.0);
  using Clock = std::chrono::steady_clock;
  auto since = [](Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); };
  // Rows in flight a thread: with two, the threads ran out of rows to shade while the
  // calling thread resolved and handed over (4096x3072 θ teapot at two threads 3 % slower).
  constexpr int kRowsInFlightPerThread = 4;
  const int inFlight = threads > 1 ? kRowsInFlightPerThread * threads : 1;
  // One row more than may be in flight: the row being resolved reads the one above it.
  std::vector<PixelRow<Geometry>> ring(static_cast<size_t>(inFlight + 1));
  for (auto& pr : ring) {
    pr.samples.assign(static_cast<size_t>(s.aa), std::vector<Sample>(static_cast<size_t>(lat.nx) * layers));
    pr.refs = geo.MakeRows();
    pr.pixels.resize(static_cast<size_t>(s.width) * kChannels);
  }
  Counters shaded;           // the rows' shading counts, added up in row order
  int written = 0;           // rows handed to the sink: every row above is done with
  bool stopped = false;      // the sink or the geometry failed
  int next = 0;              // the next pixel row to resolve
  std::size_t resolved = 0;  // rows resolved: the next one goes to ring[resolved % size]
  const PixelRow<Geometry>* above = nullptr;  // the row resolved last, if it was the one above

  // Resolves the next pixel row this render owns; null when none is left or it stopped.
  auto resolve = [&]() -> PixelRow<Geometry>* {
    while (next < s.height && s.ownsRow && !s.ownsRow(next)) ++next, above = nullptr;
    if (next >= s.height || stopped) return nullptr;
    PixelRow<Geometry>& pr = ring[resolved++ % ring.size()];
    pr.py = next++;
    pr.j0 = lat.FirstOfPixel(pr.py);
    pr.refs.j0 = pr.j0;
    pr.stats = Counters();
    geo.BeginPixelRow(pr.j0, lat.FirstOfPixel(written));
    for (int r = 0; r < s.aa; ++r) {
      if (r == 0 && above && s.aa > 1) {
        // The shared edge row, resolved with the row above (which may still be shading).
        pr.samples[0] = above->samples[static_cast<size_t>(s.aa - 1)];
        geo.CopySampleRow(above->refs, s.aa - 1, pr.refs, 0);
        continue;
      }
      std::fill(pr.samples[r].begin(), pr.samples[r].end(), kNoSample);
      geo.ScanRow(pr.j0 + r, r, lat.At(pr.j0 + r), pr.samples[r].data(), pr.refs);
    }
    above = &pr;
    return &pr;
  };
  auto timedResolve = [&] {
    const auto t0 = Clock::now();
    PixelRow<Geometry>* pr = resolve();
    timed.resolve += since(t0);
    return pr;
  };
  auto shade = [&](PixelRow<Geometry>& pr) {
    const auto t0 = Clock::now();
    for (int px = 0; px < s.width; ++px) ShadePixel(geo, s, lat, layers, pr, px);
    const int slot = threads > 1 ? tbb::this_task_arena::current_thread_index() : 0;
    if (slot >= 0 && static_cast<std::size_t>(slot) < timed.shading.size())
      timed.shading[static_cast<std::size_t>(slot)] += since(t0);
  };
  auto emit = [&](PixelRow<Geometry>& pr) {
    const auto t0 = Clock::now();
    shaded.Merge(pr.stats);
    // Rows still in flight when the render stopped are dropped.
    if (stopped || geo.Failed() || !sink.WriteRow(pr.py, pr.pixels.data())) stopped = true;
    written = pr.py + 1;
    timed.handOver += since(t0);
  };

  if (threads <= 1) {
    while (PixelRow<Geometry>* pr = timedResolve()) {
      shade(*pr);
      emit(*pr);
    }
  } else {
    const std::shared_ptr<tbb::task_arena> shared = WorkArena(threads);
    tbb::task_arena& arena = *shared;
    timed.shading.assign(static_cast<std::size_t>(arena.max_concurrency()), 0.0);
    std::vector<tbb::task_group> shading(ring.size());  // per ring slot, its row's task
    std::size_t oldest = 0;                             // rows handed over: the oldest in flight
    // Waits for the oldest row in flight (running other rows' tasks meanwhile) and hands it over.
    auto finishOldest = [&] {
      const std::size_t k = oldest++ % ring.size();
      arena.execute([&] { shading[k].wait(); });
      emit(ring[k]);
    };
    try {
      while (PixelRow<Geometry>* pr = timedResolve()) {
        const std::size_t k = (resolved - 1) % ring.size();
        arena.execute([&] { shading[k].run([&shade, pr] { shade(*pr); }); });
        while (resolved - oldest >= static_cast<std::size_t>(inFlight)) finishOldest();
      }
      while (oldest < resolved) finishOldest();
    } catch (...) {
      // No task may outlive the rows it shades.
      for (auto& g : shading) {
        g.cancel();
        try {
          arena.execute([&] { g.wait(); });
        } catch (...) {
        }
      }
      throw;
    }
  }
  if (times) *times = std::move(timed);
  if (stopped) return std::nullopt;
  stats.Merge(shaded);
  return stats;
}

}  // namespace

bool RenderSettings::AnyTransparency() const {
  if (opacity < 1.0 || material.opacity < 1.0) return true;
  for (const Material& m : materials)
    if (m.opacity < 1.0) return true;
  return false;
}

std::optional<Counters> RenderMesh(const TriangleMesh& mesh, const RenderSettings& s,
                                      RowSink& sink, BackEndTimes* times) {
  Counters stats;
  const Lattice lat(s);
  // With transparency each sample keeps its `layers` nearest fragments, nearest first.
  const int layers = s.AnyTransparency() ? kMaxLayers : 1;
  TriangleGeometry geo(mesh, s, lat, layers, stats);
  return RenderRows(geo, s, lat, layers, stats, sink, times);
}

std::optional<Counters> RenderFragments(FragmentSource& source, const RenderSettings& s,
                                           RowSink& sink, BackEndTimes* times) {
  Counters stats;
  const Lattice lat(s);
  const int layers = s.AnyTransparency() ? kMaxLayers : 1;
  FragmentGeometry geo(source, s, lat, layers, stats);
  source.BeginRows(SampleColumns{lat.offset, lat.spacing, lat.nx}, lat.At(0), lat.spacing, lat.ny,
                   KeptDepths{s.hither, geo.DepthDecides() ? layers : 0});
  return RenderRows(geo, s, lat, layers, stats, sink, times);
}

}  // namespace patchscan::raster
