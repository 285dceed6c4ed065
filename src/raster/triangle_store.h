// The back end's sample lattice and its store of active triangles (Woo and Chall 1990 §3.3; paper
// 003 for the set-up): what a sample holds, the nearest-layer insertion, and the slots
// of the triangles being scanned with their per-sample-row scan and per-pixel shading.
// Private to the scan-line renderer (scanline_renderer.cpp), in a header so that its
// per-sample code inlines into the row loop.
#pragma once

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <stdexcept>
#include <vector>

#include "raster/scanline_renderer.h"
#include "raster/triangle_setup.h"

namespace patchscan::raster {

// The sample lattice: with l = 1 one sample at each pixel centre; with l > 1 samples at
// spacing 1/(l-1) from the image's top-left corner, so a pixel's l x l samples include its
// edges and corners, shared with its neighbours (Woo and Chall 1990 §3.3).
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
// A sample no fragment has reached.
inline constexpr Sample kNoSample{0.0, -1};

// Whether a fragment at 1/w = invW is no nearer than the farthest of a sample's `layers`
// kept (nearest first): InsertNearest would drop it.
inline bool Behind(const Sample* keep, int layers, double invW) { return !(invW > keep[layers - 1].invW); }

// Keeps the `layers` nearest fragments of a sample, nearest first. Returns whether the
// new one was kept.
inline bool InsertNearest(Sample* keep, int layers, double invW, std::int32_t handle) {
  if (Behind(keep, layers, invW)) return false;
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

// The colour of a surface point: the material's (textured) colour lit by the rig, with the
// normal its bump map and then its normal map perturb, and its environment reflected.
// `shaded`, when given, receives the fragment as shaded (its normal bumped: what the normal
// AOV shows, as RenderMan's N after displacement).
inline Rgb ShadeFragment(const Fragment& a, const RenderSettings& s, std::atomic<bool>* failed,
                         Fragment* shaded = nullptr) {
  const Material& m = s.MaterialOf(a.surfaceId);
  const auto base = SurfaceColour(m, a.uv, a.duvdx, a.duvdy);
  if (!base) *failed = true;
  Vec3 normal = a.normal;
  if (m.bump.height) {
    if (const auto h = m.bump.height->LookupHeight(a.uv, a.duvdx, a.duvdy))
      normal = BumpedNormal(s.screen, a.position, a.normal, m.bump.amplitude * h->gradient, a.duvdx, a.duvdy);
    else
      *failed = true;
  }
  if (m.normalMap) {
    if (const auto rgb = m.normalMap->Lookup(a.uv, a.duvdx, a.duvdy))
      normal = MappedNormal(s.screen, a.position, normal, a.duvdx, a.duvdy, *rgb);
    else
      *failed = true;
  }
  if (shaded) *shaded = a, shaded->normal = normal;
  const Rgb colour = base.value_or(Rgb::Zero()).cwiseProduct(a.colour);
  const Vec3 eye = s.EyeFor(a.position);
  Rgb rgb = Shade(a.position, normal, colour, eye, m, s.lights);
  using Model = Material::Model;
  if (m.environment.map && m.model != Model::Constant && m.model != Model::Matte) {
    const Reflection r = ReflectedView(s.screen, a.position, normal, eye, s.orthographic);
    if (const auto seen = m.environment.map->LookupEnvironment(r.r, r.drdx, r.drdy))
      rgb += m.environment.kr * (m.model == Model::Metal ? colour : m.specularColour).cwiseProduct(*seen);
    else
      *failed = true;
  }
  return rgb;
}

// Whether a point with normal n (any length) at p shows the front of material m to the eye.
inline bool ShowsFront(const Material& m, const Vec3& n, const Vec3& p, const Vec3& eye) {
  return (n.dot(eye - p) >= 0.0) != m.reversed;
}

// A uniform number in [0, 1) from a seed and a sample's lattice position (splitmix64):
// the same for the same render whatever order the samples are visited in.
inline double UnitHash(std::uint64_t seed, int j, int i) {
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

// An edge whose x coefficient is below this fraction of its y coefficient is level with
// the sample rows (its slope is rounding).
constexpr double kLevelEdgeRel = 1e-9;

// Triangles being scanned: the active store whose slots do not move while a sample
// refers to them. A triangle leaves the scan at the start of the first pixel row none of
// whose sample rows it reaches, and its slot is reused once no pixel row still being shaded
// can refer to it: the back end shades earlier rows while it resolves later ones, reading
// slots while others are added. A slot keeps its own copy of the vertices, so triangles may
// come from a mesh's y-sorted list or arrive while the rows are scanned (θ slabs).
class TriangleStore {
 public:
  TriangleStore(const RenderSettings& s, const Lattice& lat, int layers, ShadingMode shading, Counters& stats)
      : s_(s), lat_(lat), layers_(layers), shading_(shading), invHither_(1.0 / s.hither), stats_(stats) {
    live_.reserve(1024);
    retired_.reserve(1024);
    freeSlots_.reserve(1024);
  }

  bool Failed() const { return failed_; }
  bool Empty() const { return live_.empty(); }

  // Sets up a triangle whose sample rows are [firstRow, lastRow]; culled or degenerate ones
  // are dropped. A triangle may be added before its first row (a batch's rows are scanned at
  // once: RenderBatches); the rows above it skip it.
  void Add(const RasterVertex& a, const RasterVertex& b, const RasterVertex& c, std::uint32_t surfaceId, int lastRow,
           int firstRow = std::numeric_limits<int>::min()) {
    const auto setup = SetupTriangle(a.h, b.h, c.h, s_.cullBackFaces, s_.width, s_.height);
    if (!setup) return;
    if (const Material& m = s_.MaterialOf(surfaceId); !m.twoSided) {
      if (!ShowsFront(m, a.normal + b.normal + c.normal, (a.position + b.position + c.position) / 3.0,
                      s_.EyeFor(a.position)))
        return;
    }
    ++stats_[Counter::TrianglesSetUp];
    Active at{*setup, {a, b, c}, surfaceId, firstRow, lastRow, {}, Vec3::Zero()};
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
        f.colour = at.v[k].colour;
        f.duvdx = f.duvdy = Vec2::Zero();
        f.surfaceId = surfaceId;
        at.vertexColour[k] = ShadeFragment(f, s_, &failed_);
        ++stats_[Counter::ShadingCalls];
      }
    int slot;
    if (!freeSlots_.empty()) {
      slot = freeSlots_.back();
      freeSlots_.pop_back();
    } else {
      slot = active_.Grow();
    }
    active_[slot] = at;
    live_.push_back(slot);
  }

  // Before the pixel row whose first sample row is j0: triangles ending above it leave the
  // scan; the slots of those ending above `oldestInUse` (the first sample row of the oldest
  // pixel row still being shaded, j0 when rows are shaded as they are resolved) are free.
  void BeginPixelRow(int j0, int oldestInUse) {
    std::erase_if(retired_, [&](int k) {
      if (active_[k].lastRow >= oldestInUse) return false;
      freeSlots_.push_back(k);
      return true;
    });
    std::erase_if(live_, [&](int k) {
      if (active_[k].lastRow >= j0) return false;
      (active_[k].lastRow < oldestInUse ? freeSlots_ : retired_).push_back(k);
      return true;
    });
  }

  // Resolves sample row j, of the pixel row whose first sample row is j0, against the live
  // triangles: the nearest per sample, each sample's handle `handleBase` + the triangle's
  // slot; counts into `stats`. Rows of a batch may be scanned on any threads at once: this
  // reads the store and writes only `row` and `stats`.
  void ScanRow(int j, int j0, double y, Sample* row, std::int32_t handleBase, Counters& stats) const {
    // Active on row j: the triangles a scan adding them at their first row would hold, that
    // is reached row j and not retired before j0's pixel row (the same count for any batches).
    std::int64_t activeNow = 0;
    for (const int k : live_) {
      if (active_[k].firstRow > j) continue;  // added ahead of its first row
      if (active_[k].lastRow >= j0) ++activeNow;
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
        // An edge level with the row (x coefficient rounding next to y's) bounds nothing
        // along it: -c / a would be rounding over rounding, and could cut off samples
        // the exact test gives the triangle.
        if (std::abs(e.x()) > kLevelEdgeRel * std::abs(e.y())) clip(e.x(), e.y() * y + e.z());
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
        ++stats[Counter::SamplesTested];
        if (!Inside(t, lat_.At(i), y, e)) continue;
        const double invW = s_.orthographic ? 1.0 / (dp.x() * lat_.At(i) + dp.y() * y + dp.z())
                                            : (e[0] + e[1] + e[2]) * std::abs(t.invDet);
        // Nearer than the hither plane (orthographic: or behind the camera plane).
        if (!(invW <= invHither_) || (s_.orthographic && !(invW > 0.0))) continue;
        InsertNearest(&row[static_cast<size_t>(i) * layers_], layers_, invW, handleBase + k);
      }
    }
    stats.Raise(Counter::MaxActiveTriangles, activeNow);
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

  // The colour at (x, y); `f`, when given, receives the fragment there (Interpolate's).
  Rgb ShadeAt(int slot, double x, double y, std::int64_t& nCalls, Fragment* f = nullptr) const {
    const Active& at = active_[slot];
    const Interpolated a = InterpolateAt(at, x, y);
    if (shading_ == ShadingMode::Gouraud) {
      if (f) *f = a.f;
      return a.b[0] * at.vertexColour[0] + a.b[1] * at.vertexColour[1] + a.b[2] * at.vertexColour[2];
    }
    ++nCalls;
    return ShadeFragment(a.f, s_, &failed_, f);
  }

 private:
  struct Active {
    TriangleSetup setup;
    RasterVertex v[3];
    std::uint32_t surfaceId;
    int firstRow, lastRow;
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
    // Vertex colours (a polygon's "Cs") interpolated where they differ: equal ones are
    // taken as they are, so that a colour of 1 stays exactly 1.
    if (v0.colour == v1.colour && v1.colour == v2.colour)
      f.colour = v0.colour;
    else
      f.colour = a.b[0] * v0.colour + a.b[1] * v1.colour + a.b[2] * v2.colour;
    return a;
  }

  const RenderSettings& s_;
  const Lattice& lat_;
  int layers_;
  ShadingMode shading_;
  double invHither_;
  Counters& stats_;
  mutable std::atomic<bool> failed_ = false;  // a texture could not be read (set while shading, on any thread)
  // Slots in chunks that never move: one may be added while others are read.
  class Slots {
   public:
    Active& operator[](int k) { return chunks_[static_cast<std::size_t>(k) >> kChunkBits][k & kChunkMask]; }
    const Active& operator[](int k) const {
      return chunks_[static_cast<std::size_t>(k) >> kChunkBits][k & kChunkMask];
    }
    // A new slot's index; the chunk table is sized once, so reading never races a resize.
    int Grow() {
      const std::size_t c = static_cast<std::size_t>(size_) >> kChunkBits;
      if (c >= chunks_.size()) throw std::length_error("more than 2^24 triangles active at once");
      if (!chunks_[c]) chunks_[c] = std::make_unique_for_overwrite<Active[]>(std::size_t{1} << kChunkBits);
      return size_++;
    }

   private:
    static constexpr int kChunkBits = 10;
    static constexpr int kChunkMask = (1 << kChunkBits) - 1;
    std::vector<std::unique_ptr<Active[]>> chunks_ = std::vector<std::unique_ptr<Active[]>>(std::size_t{1} << 14);
    int size_ = 0;
  };
  Slots active_;
  std::vector<int> live_, retired_, freeSlots_;  // scanned; out of the scan, maybe in use; free
};

}  // namespace patchscan::raster
