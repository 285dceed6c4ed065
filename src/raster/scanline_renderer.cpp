#include "raster/scanline_renderer.h"

#include <algorithm>
#include <limits>
#include <array>
#include <cmath>
#include <memory>
#include <mutex>
#include <numeric>

#include <oneapi/tbb/blocked_range.h>
#include <oneapi/tbb/info.h>
#include <oneapi/tbb/parallel_for.h>
#include <oneapi/tbb/task_arena.h>

#include "raster/triangle_store.h"

namespace patchscan::raster {
namespace {

// The triangles of a mesh as the back end's geometry: the y-sorted list with integer
// sample-row bounds feeding the active store.
class TriangleGeometry {
 public:
  TriangleGeometry(const TriangleMesh& mesh, const RenderSettings& s, const Lattice& lat,
                   int layers, Counters& stats)
      : mesh_(mesh), s_(s), lat_(lat), store_(s, lat, layers, s.shading, stats) {
    stats[Counter::Triangles] = static_cast<std::int64_t>(mesh.triangles.size());
    ySorted_.reserve(mesh.triangles.size());
    for (std::uint32_t k = 0; k < mesh.triangles.size(); ++k) {
      const RasterTriangle& t = mesh.triangles[k];
      const Vec3 &a = mesh.vertices[t.v[0]].h, &b = mesh.vertices[t.v[1]].h, &c = mesh.vertices[t.v[2]].h;
      double yMin = 0, yMax = s.height;
      if (a.z() > 0 && b.z() > 0 && c.z() > 0) {
        // Widened as SetupTriangle widens its bounds: a rounded division must not keep a
        // triangle off a sample row its edge values give it.
        yMin = std::min({a.y() / a.z(), b.y() / b.z(), c.y() / c.z()}) - kBoundsSlackPx;
        yMax = std::max({a.y() / a.z(), b.y() / b.z(), c.y() / c.z()}) + kBoundsSlackPx;
      }
      const int first = lat.Ceil(yMin, lat.ny), last = lat.Floor(yMax, lat.ny);
      if (first <= last) ySorted_.push_back({first, last, k});
    }
    std::stable_sort(ySorted_.begin(), ySorted_.end(),
                     [](const YEntry& p, const YEntry& q) { return p.first < q.first; });
  }

  bool Failed() const { return store_.Failed(); }
  void BeginPixelRow(int j0) { store_.BeginPixelRow(j0); }
  void SwapRows(int, int) {}

  // Resolves sample row j: the nearest triangles per sample.
  void ScanRow(int j, int /*r*/, double y, Sample* row) {
    for (; nextY_ < ySorted_.size() && ySorted_[nextY_].first <= j; ++nextY_) {
      const YEntry& e = ySorted_[nextY_];
      const RasterTriangle& t = mesh_.triangles[e.index];
      store_.Add(mesh_.vertices[t.v[0]], mesh_.vertices[t.v[1]], mesh_.vertices[t.v[2]], t.surfaceId, e.last);
    }
    store_.ScanRow(j, y, row, 0);
  }

  std::uint32_t SurfaceOf(int /*r*/, const Sample& smp) const { return store_.SurfaceOf(smp.handle); }
  double EdgeDistance(int /*r*/, const Sample& smp, double x, double y) const {
    return store_.EdgeDistance(smp.handle, x, y);
  }
  Rgb ShadeSample(int /*r*/, const Sample& smp, double x, double y, std::int64_t& nCalls) {
    return store_.ShadeAt(smp.handle, x, y, nCalls);
  }
  // A group of samples of one triangle-meshed surface is shaded once, at its centroid;
  // `f` receives the fragment shaded (GroupFragment's).
  Rgb ShadeGroup(const Member* m, int /*n*/, double cx, double cy, std::int64_t& nCalls, Fragment* f) {
    return store_.ShadeAt(m[0].smp.handle, cx, cy, nCalls, f);
  }
  Fragment GroupFragment(const Member* m, int /*n*/, double cx, double cy) const {
    return store_.Interpolate(m[0].smp.handle, cx, cy);
  }

 private:
  struct YEntry {
    int first, last;
    std::uint32_t index;
  };
  const TriangleMesh& mesh_;
  const RenderSettings& s_;
  const Lattice& lat_;
  TriangleStore store_;
  std::vector<YEntry> ySorted_;
  size_t nextY_ = 0;
};

// Sample handles at or above this are triangles (handle - kTriangleHandle: the slot);
// below, a fragment's index in its sample row's pool.
constexpr std::int32_t kTriangleHandle = std::int32_t{1} << 30;

// A direct render's geometry: exact per-sample fragments, each sample row's in a pool of
// that row which lasts while the pixel row needs it, and the triangles of θ slabs the
// source hands over as it goes (always shaded per sample's interpolated normal, as the
// fragments are: flat, Gouraud and hidden-line modes need a mesh).
class FragmentGeometry final : public FragmentRow {
 public:
  FragmentGeometry(FragmentSource& source, const RenderSettings& s, const Lattice& lat,
                   int layers, Counters& stats)
      : source_(source), s_(s), lat_(lat), layers_(layers), stats_(stats), pools_(s.aa),
        store_(s, lat, layers, ShadingMode::Phong, stats) {
    for (auto& p : pools_) p.reserve(static_cast<size_t>(lat.nx) * layers);
  }

  bool Failed() const { return failed_ || store_.Failed(); }
  void BeginPixelRow(int j0) {
    j0_ = j0;
    store_.BeginPixelRow(j0);
  }
  void SwapRows(int a, int b) { std::swap(pools_[a], pools_[b]); }

  void ScanRow(int j, int r, double y, Sample* row) {
    pool_ = &pools_[r];
    pool_->clear();
    row_ = row;
    const SampleColumns columns{lat_.offset, lat_.spacing, lat_.nx};
    if (!source_.ScanRow(y, columns, *this)) failed_ = true;
    if (!store_.Empty()) store_.ScanRow(j, y, row, kTriangleHandle);
  }

  void Add(int column, const Fragment& f) override {
    ++stats_[Counter::SamplesTested];
    if (column < 0 || column >= lat_.nx || !(f.w >= s_.hither)) return;
    if (s_.cullBackFaces && f.normal.dot(s_.EyeFor(f.position) - f.position) < 0.0) return;
    if (const Material& m = s_.MaterialOf(f.surfaceId); !m.twoSided && !ShowsFront(m, f.normal, f.position, s_.EyeFor(f.position)))
      return;
    const auto handle = static_cast<std::int32_t>(pool_->size());
    if (InsertNearest(&row_[static_cast<size_t>(column) * layers_], layers_, 1.0 / f.w, handle))
      pool_->push_back(f);
  }

  void AddTriangle(const RasterVertex& a, const RasterVertex& b, const RasterVertex& c,
                   std::uint32_t surfaceId) override {
    ++stats_[Counter::Triangles];
    double yMax = s_.height;
    if (a.h.z() > 0 && b.h.z() > 0 && c.h.z() > 0)
      yMax = std::max({a.h.y() / a.h.z(), b.h.y() / b.h.z(), c.h.y() / c.h.z()}) + kBoundsSlackPx;
    store_.Add(a, b, c, surfaceId, lat_.Floor(yMax, lat_.ny));
  }

  std::uint32_t SurfaceOf(int r, const Sample& smp) const {
    return smp.handle >= kTriangleHandle ? store_.SurfaceOf(smp.handle - kTriangleHandle)
                                         : pools_[r][smp.handle].surfaceId;
  }
  double EdgeDistance(int, const Sample&, double, double) const { return INFINITY; }
  Rgb ShadeSample(int r, const Sample& smp, double x, double y, std::int64_t& nCalls) {
    if (smp.handle >= kTriangleHandle) return store_.ShadeAt(smp.handle - kTriangleHandle, x, y, nCalls);
    ++nCalls;
    return ShadeFragment(pools_[r][smp.handle], s_, &failed_);
  }
  Rgb ShadeGroup(const Member* m, int n, double cx, double cy, std::int64_t& nCalls, Fragment* f) {
    ++nCalls;
    *f = GroupFragment(m, n, cx, cy);
    return ShadeFragment(*f, s_, &failed_);
  }
  // A group of exact samples of one surface is shaded once, with its samples' attributes
  // averaged: the surface at their centroid to second order. A group with slab samples
  // takes the slab triangle of the sample nearest the centroid, at the centroid.
  Fragment GroupFragment(const Member* m, int n, double cx, double cy) const {
    int nearest = -1;
    double best = INFINITY;
    for (int k = 0; k < n; ++k) {
      if (m[k].smp.handle < kTriangleHandle) continue;
      const double d = std::hypot(lat_.At(m[k].i) - cx, lat_.At(j0_ + m[k].r) - cy);
      if (d < best) best = d, nearest = k;
    }
    if (nearest >= 0) return store_.Interpolate(m[nearest].smp.handle - kTriangleHandle, cx, cy);
    Fragment f = pools_[m[0].r][m[0].smp.handle];
    for (int k = 1; k < n; ++k) {
      const Fragment& g = pools_[m[k].r][m[k].smp.handle];
      f.w += g.w;
      f.position += g.position;
      f.normal += g.normal;
      f.uv += g.uv;
      f.duvdx += g.duvdx;
      f.duvdy += g.duvdy;
    }
    const double inv = 1.0 / n;
    f.w *= inv;
    f.position *= inv;
    f.normal *= inv;
    f.uv *= inv;
    f.duvdx *= inv;
    f.duvdy *= inv;
    return f;
  }

 private:
  FragmentSource& source_;
  const RenderSettings& s_;
  const Lattice& lat_;
  int layers_;
  Counters& stats_;
  std::atomic<bool> failed_ = false;  // the source failed, or a texture (set while shading, on any thread)
  std::vector<std::vector<Fragment>> pools_;  // per sample row of the pixel row
  std::vector<Fragment>* pool_ = nullptr;    // the row being scanned
  Sample* row_ = nullptr;
  TriangleStore store_;
  int j0_ = 0;  // the pixel row's first sample row
};

// The pixel rows, for either geometry: sample rows resolved, samples grouped by surface
// per pixel, one shading call per group plus the adaptive-stochastic extra calls, and
// the finished row handed to the sink.
// A task shades at least this many pixels of a row: enough that a task's overhead (a few
// microseconds) is small against its shading calls.
constexpr int kPixelsPerTask = 32;

// Whether any of the aa x aa samples of the pixel whose first sample column is i0 holds a
// fragment.
bool AnyCovered(const std::vector<std::vector<Sample>>& rows, int i0, int aa, int layers) {
  for (int r = 0; r < aa; ++r)
    for (int c = 0; c < aa; ++c)
      if (rows[r][static_cast<size_t>(i0 + c) * layers].handle >= 0) return true;
  return false;
}

template <class Geometry>
std::optional<Counters> RenderRows(Geometry& geo, const RenderSettings& s, const Lattice& lat,
                                      int layers, Counters& stats, RowSink& sink) {
  std::vector<std::vector<Sample>> rows(s.aa, std::vector<Sample>(static_cast<size_t>(lat.nx) * layers));
  std::vector<float> pixels(static_cast<size_t>(s.width) * kChannels);
  const int perPixel = s.aa * s.aa;
  // Paper 000 §3.4.2: each covered sample is shaded on its own with probability
  // P = (l - 1) / (l^2 - 1) = 1 / (l + 1); a colour that differs from the pixel's one
  // shading call by more than kShadeDiscrepancy makes the pixel shade every sample.
  const double extraP = s.aa > 1 ? 1.0 / (s.aa + 1) : 0.0;
  std::unique_ptr<tbb::task_arena> arena;
  if (s.threads > 1) arena = std::make_unique<tbb::task_arena>(std::min(s.threads, tbb::info::default_concurrency()));
  std::mutex merge;
  // A pixel no surface covers: no colour, no coverage, depth +inf (OpenEXR's and prman's
  // background), the other AOVs 0 and surface id -1.
  std::array<float, kChannels> background{};
  background[kChannelZ] = std::numeric_limits<float>::infinity();
  background[kChannelId] = -1.0f;
  bool previous = false;  // the pixel row above was rendered: its last sample row is this one's first
  for (int py = 0; py < s.height; ++py) {
    if (s.ownsRow && !s.ownsRow(py)) {
      previous = false;
      continue;
    }
    const int j0 = lat.FirstOfPixel(py);
    geo.BeginPixelRow(j0);
    for (int r = 0; r < s.aa; ++r) {
      if (r == 0 && previous && s.aa > 1) {
        std::swap(rows[0], rows[s.aa - 1]);  // the shared edge row, already resolved
        geo.SwapRows(0, s.aa - 1);
        continue;
      }
      std::fill(rows[r].begin(), rows[r].end(), Sample{0.0, -1});
      geo.ScanRow(j0 + r, r, lat.At(j0 + r), rows[r].data());
    }
    // The pixels of the row, each on its own: in chunks over the back end's threads, each
    // chunk counting into its own counts (added up in any order: sums).
    auto shadePixels = [&](int pxBegin, int pxEnd, Counters& stats) {
    for (int px = pxBegin; px < pxEnd; ++px) {
      float* out = &pixels[static_cast<size_t>(px) * kChannels];
      if (!AnyCovered(rows, lat.FirstOfPixel(px), s.aa, layers)) {
        std::copy(background.begin(), background.end(), out);  // most pixels of most frames
        continue;
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
      const int i0 = lat.FirstOfPixel(px);
      for (int r = 0; r < s.aa; ++r)
        for (int c = 0; c < s.aa; ++c) {
          const Sample* keep = &rows[r][static_cast<size_t>(i0 + c) * layers];
          groupOf[r * s.aa + c] = -1;
          if (keep[0].handle < 0) continue;
          ++covered;
          const double x = lat.At(i0 + c), y = lat.At(j0 + r);
          if (s.hiddenLine && geo.EdgeDistance(r, keep[0], x, y) < kLineHalfWidth) ++onLines;
          double through = 1.0;  // light passing the layers in front
          for (int layer = 0; layer < layers && keep[layer].handle >= 0; ++layer) {
            const std::uint32_t surface = geo.SurfaceOf(r, keep[layer]);
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
          gr.rgb = geo.ShadeGroup(gathered.data(), n, gr.sx / gr.count, gr.sy / gr.count,
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
              UnitHash(s.seed, j0 + r, i0 + c) >= extraP)
            continue;
          const Sample& smp = rows[r][static_cast<size_t>(i0 + c) * layers];
          const Rgb rgb = geo.ShadeSample(r, smp, lat.At(i0 + c), lat.At(j0 + r), stats[Counter::ExtraShadingCalls]);
          superSample = (rgb - groups[groupOf[k]].rgb).cwiseAbs().maxCoeff() > kShadeDiscrepancy;
        }
        if (superSample) {
          ++stats[Counter::SuperSampledPixels];
          colour = Rgb::Zero();
          for (int k = 0; k < perPixel; ++k) {
            if (groupOf[k] < 0) continue;
            const int r = k / s.aa;
            const Sample& smp = rows[r][static_cast<size_t>(i0 + k % s.aa) * layers];
            colour += geo.ShadeSample(r, smp, lat.At(i0 + k % s.aa), lat.At(j0 + r),
                                      stats[Counter::ExtraShadingCalls]) / perPixel;
          }
        }
      }
      for (int k = 0; k < 3; ++k) out[k] = static_cast<float>(colour[k]);
      out[3] = static_cast<float>(alpha / perPixel);
      if (major < 0) {
        std::copy(background.begin() + 4, background.end(), out + 4);
      } else {
        const Group& gr = groups[major];
        if (!haveMajor)
          majorFragment = geo.GroupFragment(gathered.data(), gather(major), gr.sx / gr.count, gr.sy / gr.count);
        const Fragment& a = majorFragment;
        const Vec3 nrm = a.normal.normalized();
        out[kChannelZ] = static_cast<float>(a.w);
        for (int k = 0; k < 3; ++k) out[kChannelN + k] = static_cast<float>(nrm.allFinite() ? nrm[k] : 0.0);
        out[kChannelUv] = static_cast<float>(a.uv.x());
        out[kChannelUv + 1] = static_cast<float>(a.uv.y());
        out[kChannelId] = static_cast<float>(gr.surface);
      }
    }
    };
    if (arena) {
      arena->execute([&] {
        tbb::parallel_for(tbb::blocked_range<int>(0, s.width, kPixelsPerTask), [&](const tbb::blocked_range<int>& range) {
          Counters local;
          shadePixels(range.begin(), range.end(), local);
          std::lock_guard lock(merge);
          stats.Merge(local);
        });
      });
    } else {
      shadePixels(0, s.width, stats);
    }
    if (geo.Failed() || !sink.WriteRow(py, pixels.data())) return std::nullopt;
    previous = true;
  }
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
                                      RowSink& sink) {
  Counters stats;
  const Lattice lat(s);
  // With transparency each sample keeps its `layers` nearest fragments, nearest first.
  const int layers = s.AnyTransparency() ? kMaxLayers : 1;
  TriangleGeometry geo(mesh, s, lat, layers, stats);
  return RenderRows(geo, s, lat, layers, stats, sink);
}

std::optional<Counters> RenderFragments(FragmentSource& source, const RenderSettings& s,
                                           RowSink& sink) {
  Counters stats;
  const Lattice lat(s);
  const int layers = s.AnyTransparency() ? kMaxLayers : 1;
  FragmentGeometry geo(source, s, lat, layers, stats);
  source.BeginRows(SampleColumns{lat.offset, lat.spacing, lat.nx}, lat.At(0), lat.spacing, lat.ny);
  return RenderRows(geo, s, lat, layers, stats, sink);
}

}  // namespace patchscan::raster
