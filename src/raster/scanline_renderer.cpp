#include "raster/scanline_renderer.h"
#include "raster/work_arena.h"

#include <algorithm>
#include <limits>
#include <array>
#include <cmath>
#include <memory>

#include <oneapi/tbb/info.h>
#include <oneapi/tbb/task_arena.h>
#include <oneapi/tbb/task_group.h>

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

  // What a pixel row's samples refer to beyond the store: nothing.
  struct Rows {
    int j0 = 0;
  };
  Rows MakeRows() const { return {}; }

  bool Failed() const { return store_.Failed(); }
  void BeginPixelRow(int j0, int oldestInUse) { store_.BeginPixelRow(j0, oldestInUse); }
  void CopySampleRow(const Rows&, int, Rows&, int) {}

  // Resolves sample row j: the nearest triangles per sample.
  void ScanRow(int j, int /*r*/, double y, Sample* row, Rows& /*rows*/) {
    for (; nextY_ < ySorted_.size() && ySorted_[nextY_].first <= j; ++nextY_) {
      const YEntry& e = ySorted_[nextY_];
      const RasterTriangle& t = mesh_.triangles[e.index];
      store_.Add(mesh_.vertices[t.v[0]], mesh_.vertices[t.v[1]], mesh_.vertices[t.v[2]], t.surfaceId, e.last);
    }
    store_.ScanRow(j, y, row, 0);
  }

  std::uint32_t SurfaceOf(const Rows&, int /*r*/, const Sample& smp) const { return store_.SurfaceOf(smp.handle); }
  double EdgeDistance(const Rows&, int /*r*/, const Sample& smp, double x, double y) const {
    return store_.EdgeDistance(smp.handle, x, y);
  }
  Rgb ShadeSample(const Rows&, int /*r*/, const Sample& smp, double x, double y, std::int64_t& nCalls) const {
    return store_.ShadeAt(smp.handle, x, y, nCalls);
  }
  // A group of samples of one triangle-meshed surface is shaded once, at its centroid;
  // `f` receives the fragment shaded (GroupFragment's).
  Rgb ShadeGroup(const Rows&, const Member* m, int /*n*/, double cx, double cy, std::int64_t& nCalls,
                 Fragment* f) const {
    return store_.ShadeAt(m[0].smp.handle, cx, cy, nCalls, f);
  }
  Fragment GroupFragment(const Rows&, const Member* m, int /*n*/, double cx, double cy) const {
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
// Handles from this one below kTriangleHandle are chords (handle - kChordHandle: the
// index in their sample row's chords), below it fragments of the row's pool.
constexpr std::int32_t kChordHandle = std::int32_t{1} << 29;

// A direct render's geometry: exact per-sample fragments, each sample row's in a pool of
// that row which lasts while the pixel row needs it, and the triangles of θ slabs the
// source hands over as it goes (always shaded per sample's interpolated normal, as the
// fragments are: flat, Gouraud and hidden-line modes need a mesh).
class FragmentGeometry final : public FragmentRow {
 public:
  FragmentGeometry(FragmentSource& source, const RenderSettings& s, const Lattice& lat,
                   int layers, Counters& stats)
      : source_(source), s_(s), lat_(lat), layers_(layers), stats_(stats),
        store_(s, lat, layers, ShadingMode::Phong, stats) {
    sided_ = s.cullBackFaces || !s.material.twoSided;
    for (const Material& m : s.materials) sided_ = sided_ || !m.twoSided;
  }

  // Whether a fragment's depth alone decides whether it is kept (else its side may drop it
  // too: culling, or a one-sided material).
  bool DepthDecides() const { return !sided_; }

  // What a pixel row's samples refer to beyond the store: the fragments and chords of each
  // of its sample rows (a sample's handle below kTriangleHandle indexes its row's pool or
  // chords).
  struct Rows {
    int j0 = 0;  // the pixel row's first sample row
    std::vector<std::vector<Fragment>> pools;
    std::vector<std::vector<Chord>> chords;
  };
  Rows MakeRows() const {
    Rows rows;
    rows.pools.resize(static_cast<size_t>(s_.aa));
    for (auto& p : rows.pools) p.reserve(static_cast<size_t>(lat_.nx) * layers_);
    rows.chords.resize(static_cast<size_t>(s_.aa));
    return rows;
  }

  bool Failed() const { return failed_ || store_.Failed(); }
  void BeginPixelRow(int j0, int oldestInUse) { store_.BeginPixelRow(j0, oldestInUse); }
  void CopySampleRow(const Rows& from, int rFrom, Rows& to, int rTo) {
    to.pools[static_cast<size_t>(rTo)] = from.pools[static_cast<size_t>(rFrom)];  // within the reserve
    to.chords[static_cast<size_t>(rTo)] = from.chords[static_cast<size_t>(rFrom)];
  }

  void ScanRow(int j, int r, double y, Sample* row, Rows& rows) {
    pool_ = &rows.pools[static_cast<size_t>(r)];
    pool_->clear();
    chords_ = &rows.chords[static_cast<size_t>(r)];
    chords_->clear();
    row_ = row;
    const SampleColumns columns{lat_.offset, lat_.spacing, lat_.nx};
    if (!source_.ScanRow(y, columns, *this)) failed_ = true;
    if (!store_.Empty()) store_.ScanRow(j, y, row, kTriangleHandle);
  }

  void Add(int column, const Fragment& f) override {
    ++stats_[Counter::SamplesTested];
    if (column < 0 || column >= lat_.nx || !(f.w >= s_.hither) || !Shows(f)) return;
    const auto handle = static_cast<std::int32_t>(pool_->size());
    if (InsertNearest(&row_[static_cast<size_t>(column) * layers_], layers_, 1.0 / f.w, handle))
      pool_->push_back(f);
  }

  bool Hidden(int column, double w) const override {
    return column < 0 || column >= lat_.nx || !(w >= s_.hither) ||
           Behind(&row_[static_cast<size_t>(column) * layers_], layers_, 1.0 / w);
  }

  // A chord is kept whole, and a sample of it made only when shaded (a hidden one never),
  // or when its side may drop it (culling, a one-sided material): then a sample the depth
  // test would keep is made first to ask its side.
  void AddChord(const Chord& c, const SampleColumns& columns) override {
    const auto handle = kChordHandle + static_cast<std::int32_t>(chords_->size());
    bool kept = false;
    const double nearest = 1.0 / s_.hither;  // the largest 1/w in front of the hither plane
    const auto inFront = [&](double invW) { return invW > 0.0 && invW <= nearest; };  // false for NaN
    if (!sided_) {
      stats_[Counter::SamplesTested] += c.ForEachColumnInverseDepth(columns, [&](int column, double invW) {
        kept |= inFront(invW) && InsertNearest(&row_[static_cast<size_t>(column) * layers_], layers_, invW, handle);
      });
    } else {
      c.ForEachColumnInverseDepth(columns, [&](int column, double invW) {
        if (!inFront(invW) || Behind(&row_[static_cast<size_t>(column) * layers_], layers_, invW)) return;
        ++stats_[Counter::SamplesTested];
        if (!Shows(c.At(columns.At(column)))) return;
        if (InsertNearest(&row_[static_cast<size_t>(column) * layers_], layers_, invW, handle)) kept = true;
      });
    }
    if (kept) chords_->push_back(c);
  }

  void AddTriangle(const RasterVertex& a, const RasterVertex& b, const RasterVertex& c,
                   std::uint32_t surfaceId) override {
    ++stats_[Counter::Triangles];
    double yMax = s_.height;
    if (a.h.z() > 0 && b.h.z() > 0 && c.h.z() > 0)
      yMax = std::max({a.h.y() / a.h.z(), b.h.y() / b.h.z(), c.h.y() / c.h.z()}) + kBoundsSlackPx;
    store_.Add(a, b, c, surfaceId, lat_.Floor(yMax, lat_.ny));
  }

  std::uint32_t SurfaceOf(const Rows& rows, int r, const Sample& smp) const {
    if (smp.handle >= kTriangleHandle) return store_.SurfaceOf(smp.handle - kTriangleHandle);
    if (smp.handle >= kChordHandle) return rows.chords[static_cast<size_t>(r)][smp.handle - kChordHandle].a().surfaceId;
    return rows.pools[static_cast<size_t>(r)][smp.handle].surfaceId;
  }
  double EdgeDistance(const Rows&, int, const Sample&, double, double) const { return INFINITY; }
  Rgb ShadeSample(const Rows& rows, int r, const Sample& smp, double x, double y, std::int64_t& nCalls) const {
    if (smp.handle >= kTriangleHandle) return store_.ShadeAt(smp.handle - kTriangleHandle, x, y, nCalls);
    ++nCalls;
    if (smp.handle >= kChordHandle)
      return ShadeFragment(rows.chords[static_cast<size_t>(r)][smp.handle - kChordHandle].At(x), s_, &failed_);
    return ShadeFragment(rows.pools[static_cast<size_t>(r)][smp.handle], s_, &failed_);
  }
  Rgb ShadeGroup(const Rows& rows, const Member* m, int n, double cx, double cy, std::int64_t& nCalls,
                 Fragment* f) const {
    ++nCalls;
    *f = GroupFragment(rows, m, n, cx, cy);
    return ShadeFragment(*f, s_, &failed_);
  }
  // A group of exact samples of one surface is shaded once, with its samples' attributes
  // averaged: the surface at their centroid to second order. A group with slab samples
  // takes the slab triangle of the sample nearest the centroid, at the centroid.
  Fragment GroupFragment(const Rows& rows, const Member* m, int n, double cx, double cy) const {
    // A lone exact or chord sample (every pixel at aa 1): its own fragment, no search.
    if (n == 1 && m[0].smp.handle < kTriangleHandle) return FragmentOf(rows, m[0], lat_.At(m[0].i));
    int nearest = -1;
    double best = INFINITY;
    const auto consider = [&](int k) {
      if (m[k].smp.handle < kTriangleHandle) return;
      const double dx = lat_.At(m[k].i) - cx, dy = lat_.At(rows.j0 + m[k].r) - cy;
      const double d = dx * dx + dy * dy;  // squared: the order is the distance's, without hypot's cost
      if (d < best) best = d, nearest = k;
    };
    // A group of all the pixel's aa x aa samples (member r aa + c: row r's column c) has its
    // centroid at the pixel's middle, nearer the middle samples (rows and columns (aa-1)/2
    // and aa/2) than any other: they are searched alone, in the members' order, so the one
    // chosen is the full search's. Most groups are whole pixels.
    const int aa = s_.aa, lo = (aa - 1) / 2, hi = aa / 2;
    if (n == aa * aa)
      for (int r = lo; r <= hi; ++r)
        for (int c = lo; c <= hi; ++c) consider(r * aa + c);
    if (nearest < 0)
      for (int k = 0; k < n; ++k) consider(k);
    if (nearest >= 0) return store_.Interpolate(m[nearest].smp.handle - kTriangleHandle, cx, cy);
    // The members come row by row, each row's from left to right: a run of samples of one
    // chord is taken at its mean column, once (a chord's attributes are smooth along it,
    // so to second order as their mean), weighted by its length.
    Fragment f;  // the first member sets every field; the zeros only tell the compiler so
    f.position.setZero(), f.normal.setZero(), f.uv.setZero(), f.duvdx.setZero(), f.duvdy.setZero();
    for (int k = 0, run = 1; k < n; k += run) {
      const Member& x = m[k];
      run = 1;
      double sx = lat_.At(x.i);
      if (x.smp.handle >= kChordHandle)
        for (; k + run < n && m[k + run].r == x.r && m[k + run].smp.handle == x.smp.handle; ++run)
          sx += lat_.At(m[k + run].i);
      const Fragment g = FragmentOf(rows, x, sx / run);
      // The first member's fragment is taken as it is (a lone sample, or exact mode's first
      // fragment: the sum starts from its values, signed zeros included, as it always has).
      if (k == 0) {
        f = g;
        if (run == 1) continue;
        f.w = 0.0, f.position.setZero(), f.normal.setZero(), f.uv.setZero(), f.duvdx.setZero(), f.duvdy.setZero();
      }
      const double weight = run;
      f.w += weight * g.w;
      f.position += weight * g.position;
      f.normal += weight * g.normal;
      f.uv += weight * g.uv;
      f.duvdx += weight * g.duvdx;
      f.duvdy += weight * g.duvdy;
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
  // The fragment of an exact or chord sample; a chord's at screen x.
  static Fragment FragmentOf(const Rows& rows, const Member& x, double sx) {
    if (x.smp.handle >= kChordHandle) return rows.chords[static_cast<size_t>(x.r)][x.smp.handle - kChordHandle].At(sx);
    return rows.pools[static_cast<size_t>(x.r)][x.smp.handle];
  }

  // Whether a fragment's side lets it be seen: not culled, and a one-sided material's front.
  bool Shows(const Fragment& f) const {
    if (s_.cullBackFaces && f.normal.dot(s_.EyeFor(f.position) - f.position) < 0.0) return false;
    const Material& m = s_.MaterialOf(f.surfaceId);
    return m.twoSided || ShowsFront(m, f.normal, f.position, s_.EyeFor(f.position));
  }

  FragmentSource& source_;
  const RenderSettings& s_;
  const Lattice& lat_;
  int layers_;
  Counters& stats_;
  // The source failed, or a texture (set while shading, on any thread).
  mutable std::atomic<bool> failed_ = false;
  std::vector<Fragment>* pool_ = nullptr;  // the pool of the sample row being scanned
  std::vector<Chord>* chords_ = nullptr;   // and its chords
  bool sided_ = false;                     // !DepthDecides()
  Sample* row_ = nullptr;
  TriangleStore store_;
};

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
                                      int layers, Counters& stats, RowSink& sink) {
  const int threads = s.threads > 1 ? std::min(s.threads, tbb::info::default_concurrency()) : 1;
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
  auto shade = [&](PixelRow<Geometry>& pr) {
    for (int px = 0; px < s.width; ++px) ShadePixel(geo, s, lat, layers, pr, px);
  };
  auto emit = [&](PixelRow<Geometry>& pr) {
    shaded.Merge(pr.stats);
    // Rows still in flight when the render stopped are dropped.
    if (stopped || geo.Failed() || !sink.WriteRow(pr.py, pr.pixels.data())) stopped = true;
    written = pr.py + 1;
  };

  if (threads <= 1) {
    while (PixelRow<Geometry>* pr = resolve()) {
      shade(*pr);
      emit(*pr);
    }
  } else {
    const std::shared_ptr<tbb::task_arena> shared = WorkArena(threads);
    tbb::task_arena& arena = *shared;
    std::vector<tbb::task_group> shading(ring.size());  // per ring slot, its row's task
    std::size_t oldest = 0;                             // rows handed over: the oldest in flight
    // Waits for the oldest row in flight (running other rows' tasks meanwhile) and hands it over.
    auto finishOldest = [&] {
      const std::size_t k = oldest++ % ring.size();
      arena.execute([&] { shading[k].wait(); });
      emit(ring[k]);
    };
    try {
      while (PixelRow<Geometry>* pr = resolve()) {
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
  source.BeginRows(SampleColumns{lat.offset, lat.spacing, lat.nx}, lat.At(0), lat.spacing, lat.ny,
                   KeptDepths{s.hither, geo.DepthDecides() ? layers : 0});
  return RenderRows(geo, s, lat, layers, stats, sink);
}

}  // namespace patchscan::raster
