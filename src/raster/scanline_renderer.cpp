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

// A sample's hold on one fragment: for triangles the slot of the triangle in the active
// store, for exact fragments the fragment's index in its sample row's pool.
struct Sample {
  double invW;          // 1 / w of the fragment; 0: none
  std::int32_t handle;  // -1: none
};

// Keeps the `layers` nearest fragments of a sample, nearest first. Returns whether the
// new one was kept.
bool InsertNearest(Sample* keep, int layers, double invW, std::int32_t handle) {
  if (!(invW > keep[layers - 1].invW)) return false;
  int at = layers - 1;  // insertion into the sorted layers, dropping the farthest
  for (; at > 0 && invW > keep[at - 1].invW; --at) keep[at] = keep[at - 1];
  keep[at] = {invW, handle};
  return true;
}

// One layer of one sample of the pixel being resolved.
struct Member {
  int r;  // sample row within the pixel's rows
  int i;  // sample column
  Sample smp;
};

// The colour of a surface point: the material's (textured) colour lit by the rig.
Rgb ShadeFragment(const Fragment& a, const RenderSettings& s, bool* failed) {
  const Material& m = s.MaterialOf(a.surfaceId);
  const auto base = SurfaceColour(m, a.uv, a.duvdx, a.duvdy);
  if (!base) *failed = true;
  return Shade(a.position, a.normal, base.value_or(Rgb::Zero()), s.EyeFor(a.position), m, s.lights);
}

// Whether a point with normal n (any length) at p shows the front of material m to the eye.
bool ShowsFront(const Material& m, const Vec3& n, const Vec3& p, const Vec3& eye) {
  return (n.dot(eye - p) >= 0.0) != m.reversed;
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

// Triangles being scanned: the active store whose slots do not move while a sample
// refers to them (a triangle is retired at the start of the first pixel row none of whose
// sample rows it reaches). A slot keeps its own copy of the vertices, so triangles may come
// from a mesh's y-sorted list or arrive while the rows are scanned (θ slabs).
class TriangleStore {
 public:
  TriangleStore(const RenderSettings& s, const Lattice& lat, int layers, ShadingMode shading, Counters& stats)
      : s_(s), lat_(lat), layers_(layers), shading_(shading), invHither_(1.0 / s.hither), stats_(stats) {
    active_.reserve(1024);
    live_.reserve(1024);
    freeSlots_.reserve(1024);
  }

  bool Failed() const { return failed_; }
  bool Empty() const { return live_.empty(); }

  // Sets up a triangle whose last sample row is `lastRow`; culled or degenerate ones are
  // dropped.
  void Add(const RasterVertex& a, const RasterVertex& b, const RasterVertex& c, std::uint32_t surfaceId, int lastRow) {
    const auto setup = SetupTriangle(a.h, b.h, c.h, s_.cullBackFaces, s_.width, s_.height);
    if (!setup) return;
    if (const Material& m = s_.MaterialOf(surfaceId); !m.twoSided) {
      if (!ShowsFront(m, a.normal + b.normal + c.normal, (a.position + b.position + c.position) / 3.0,
                      s_.EyeFor(a.position)))
        return;
    }
    ++stats_[Counter::TrianglesSetUp];
    Active at{*setup, {a, b, c}, surfaceId, lastRow, {}, Vec3::Zero()};
    if (s_.orthographic) {
      // With W = 1 the barycentrics are e_i . (x, y, 1) / |det|.
      const double absInvDet = std::abs(setup->invDet);
      for (int k = 0; k < 3; ++k) at.depthPlane += at.v[k].depth * absInvDet * setup->edge[k];
    }
    if (shading_ == ShadingMode::Gouraud)
      for (int k = 0; k < 3; ++k) {
        Fragment f;
        f.position = at.v[k].position;
        f.normal = at.v[k].normal;
        f.uv = at.v[k].uv;
        f.duvdx = f.duvdy = Vec2::Zero();
        f.surfaceId = surfaceId;
        at.vertexColour[k] = ShadeFragment(f, s_, &failed_);
        ++stats_[Counter::ShadingCalls];
      }
    int slot;
    if (!freeSlots_.empty()) {
      slot = freeSlots_.back();
      freeSlots_.pop_back();
      active_[slot] = at;
    } else {
      slot = static_cast<int>(active_.size());
      active_.push_back(at);
    }
    live_.push_back(slot);
  }

  void BeginPixelRow(int j0) {
    std::erase_if(live_, [&](int k) {
      if (active_[k].lastRow >= j0) return false;
      freeSlots_.push_back(k);
      return true;
    });
  }

  // Resolves sample row j against the live triangles: the nearest per sample, each
  // sample's handle `handleBase` + the triangle's slot.
  void ScanRow(int j, double y, Sample* row, std::int32_t handleBase) {
    stats_.Raise(Counter::MaxActiveTriangles, static_cast<std::int64_t>(live_.size()));
    for (const int k : live_) {
      if (active_[k].lastRow < j) continue;  // done, retired at the next pixel row
      const TriangleSetup& t = active_[k].setup;
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
      const Vec3& dp = active_[k].depthPlane;
      if (s_.orthographic)
        clip(dp.x(), dp.y() * y + dp.z() - s_.hither);  // depth >= hither
      else
        clip(-sum.x(), absDet * invHither_ - (sum.y() * y + sum.z()));
      // One sample of slack each side: the exact test below decides.
      const int i0 = std::max(0, lat_.Ceil(lo, lat_.nx) - 1), i1 = std::min(lat_.nx - 1, lat_.Floor(hi, lat_.nx) + 1);
      for (int i = i0; i <= i1; ++i) {
        double e[3];
        ++stats_[Counter::SamplesTested];
        if (!Inside(t, lat_.At(i), y, e)) continue;
        const double invW = s_.orthographic ? 1.0 / (dp.x() * lat_.At(i) + dp.y() * y + dp.z())
                                            : (e[0] + e[1] + e[2]) * std::abs(t.invDet);
        // Nearer than the hither plane (orthographic: or behind the camera plane).
        if (!(invW <= invHither_) || (s_.orthographic && !(invW > 0.0))) continue;
        InsertNearest(&row[static_cast<size_t>(i) * layers_], layers_, invW, handleBase + k);
      }
    }
  }

  std::uint32_t SurfaceOf(int slot) const { return active_[slot].surfaceId; }
  // Screen distance in pixels from (x, y) to the nearest edge line of the triangle: each
  // oriented edge is an affine function of screen position, so |e| / |grad e| is exact.
  double EdgeDistance(int slot, double x, double y) const {
    double d = INFINITY;
    for (const Vec3& e : active_[slot].setup.edge)
      d = std::min(d, std::abs(e.x() * x + e.y() * y + e.z()) / std::hypot(e.x(), e.y()));
    return d;
  }

  // Perspective-correct attributes of a triangle at (x, y).
  Fragment Interpolate(int slot, double x, double y) const { return InterpolateAt(active_[slot], x, y).f; }

  Rgb ShadeAt(int slot, double x, double y, std::int64_t& nCalls) {
    const Active& at = active_[slot];
    const Interpolated a = InterpolateAt(at, x, y);
    if (shading_ == ShadingMode::Gouraud)
      return a.b[0] * at.vertexColour[0] + a.b[1] * at.vertexColour[1] + a.b[2] * at.vertexColour[2];
    ++nCalls;
    return ShadeFragment(a.f, s_, &failed_);
  }

 private:
  struct Active {
    TriangleSetup setup;
    RasterVertex v[3];
    std::uint32_t surfaceId;
    int lastRow;
    Rgb vertexColour[3];  // Gouraud only
    // Orthographic: the depth as an affine function of (x, y, 1), from the vertices' depths.
    Vec3 depthPlane = Vec3::Zero();
  };
  // Perspective-correct attributes of an active triangle at (x, y), and its barycentrics.
  struct Interpolated {
    Fragment f;
    Vec3 b;
  };

  Interpolated InterpolateAt(const Active& at, double x, double y) const {
    const RasterVertex &v0 = at.v[0], &v1 = at.v[1], &v2 = at.v[2];
    Interpolated a;
    Fragment& f = a.f;
    Vec3 e;
    for (int i = 0; i < 3; ++i) e[i] = at.setup.edge[i].x() * x + at.setup.edge[i].y() * y + at.setup.edge[i].z();
    const double sum = e.sum();
    a.b = sum != 0.0 ? Vec3(e / sum) : Vec3::Constant(1.0 / 3);
    f.w = s_.orthographic ? at.depthPlane.dot(Vec3(x, y, 1.0))
          : sum != 0.0    ? 1.0 / (sum * std::abs(at.setup.invDet))
                          : 0.0;
    f.position = a.b[0] * v0.position + a.b[1] * v1.position + a.b[2] * v2.position;
    f.uv = a.b[0] * v0.uv + a.b[1] * v1.uv + a.b[2] * v2.uv;
    // uv = sum(uv_i e_i) / sum(e) with each e_i affine in (x, y): the quotient rule.
    if (sum != 0.0) {
      for (int axis = 0; axis < 2; ++axis) {
        Vec2 numerator = Vec2::Zero();
        double grad = 0.0;
        for (int i = 0; i < 3; ++i) {
          const double g = at.setup.edge[i][axis];
          numerator += g * at.v[i].uv;
          grad += g;
        }
        (axis == 0 ? f.duvdx : f.duvdy) = (numerator - f.uv * grad) / sum;
      }
    } else {
      f.duvdx = f.duvdy = Vec2::Zero();
    }
    f.normal = shading_ == ShadingMode::Flat
                   ? Vec3((v1.position - v0.position).cross(v2.position - v0.position))
                   : Vec3(a.b[0] * v0.normal + a.b[1] * v1.normal + a.b[2] * v2.normal);
    f.surfaceId = at.surfaceId;
    return a;
  }

  const RenderSettings& s_;
  const Lattice& lat_;
  int layers_;
  ShadingMode shading_;
  double invHither_;
  Counters& stats_;
  bool failed_ = false;  // a texture could not be read
  std::vector<Active> active_;  // the slots
  std::vector<int> live_, freeSlots_;
};

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
        yMin = std::min({a.y() / a.z(), b.y() / b.z(), c.y() / c.z()});
        yMax = std::max({a.y() / a.z(), b.y() / b.z(), c.y() / c.z()});
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
  // A group of samples of one triangle-meshed surface is shaded once, at its centroid.
  Rgb ShadeGroup(const Member* m, int /*n*/, double cx, double cy, std::int64_t& nCalls) {
    return store_.ShadeAt(m[0].smp.handle, cx, cy, nCalls);
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
      yMax = std::max({a.h.y() / a.h.z(), b.h.y() / b.h.z(), c.h.y() / c.h.z()});
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
  Rgb ShadeGroup(const Member* m, int n, double cx, double cy, std::int64_t& nCalls) {
    ++nCalls;
    return ShadeFragment(GroupFragment(m, n, cx, cy), s_, &failed_);
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
  bool failed_ = false;
  std::vector<std::vector<Fragment>> pools_;  // per sample row of the pixel row
  std::vector<Fragment>* pool_ = nullptr;    // the row being scanned
  Sample* row_ = nullptr;
  TriangleStore store_;
  int j0_ = 0;  // the pixel row's first sample row
};

// The pixel rows, for either geometry: sample rows resolved, samples grouped by surface
// per pixel, one shading call per group plus the adaptive-stochastic extra calls, and
// the finished row handed to the sink.
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
  for (int py = 0; py < s.height; ++py) {
    const int j0 = lat.FirstOfPixel(py);
    geo.BeginPixelRow(j0);
    for (int r = 0; r < s.aa; ++r) {
      if (r == 0 && py > 0 && s.aa > 1) {
        std::swap(rows[0], rows[s.aa - 1]);  // the shared edge row, already resolved
        geo.SwapRows(0, s.aa - 1);
        continue;
      }
      std::fill(rows[r].begin(), rows[r].end(), Sample{0.0, -1});
      geo.ScanRow(j0 + r, r, lat.At(j0 + r), rows[r].data());
    }
    for (int px = 0; px < s.width; ++px) {
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
          gr.rgb = geo.ShadeGroup(gathered.data(), n, gr.sx / gr.count, gr.sy / gr.count, stats[Counter::ShadingCalls]);
          colour += (gr.weight / perPixel) * gr.rgb;
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
        const int n = gather(major);
        const Fragment a = geo.GroupFragment(gathered.data(), n, gr.sx / gr.count, gr.sy / gr.count);
        const Vec3 nrm = a.normal.normalized();
        out[kChannelZ] = static_cast<float>(a.w);
        for (int k = 0; k < 3; ++k) out[kChannelN + k] = static_cast<float>(nrm.allFinite() ? nrm[k] : 0.0);
        out[kChannelUv] = static_cast<float>(a.uv.x());
        out[kChannelUv + 1] = static_cast<float>(a.uv.y());
        out[kChannelId] = static_cast<float>(gr.surface);
      }
    }
    if (geo.Failed() || !sink.WriteRow(py, pixels.data())) return std::nullopt;
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
  return RenderRows(geo, s, lat, layers, stats, sink);
}

}  // namespace patchscan::raster
