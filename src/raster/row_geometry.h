// The back end's two kinds of geometry (raster/scanline_renderer.h): the triangles of a
// mesh (TriangleGeometry) and a front end's exact fragments, chords and triangles row by
// row (FragmentGeometry). RenderRows, a template over them, takes each sample row's
// samples from either; they are here whole so that its inner loops inline them.
#pragma once

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "raster/scanline_renderer.h"
#include "raster/triangle_store.h"
#include "raster/work_arena.h"

namespace patchscan::raster::detail {

// Sample rows of a batch of a mesh's rows resolved on threads at once (RenderBatches): the
// threads fork and join once a batch, against about 25 microseconds to resolve one sample
// row of the 2048x1536 teapot's mesh at aa 3 (--stats: 0.078 s for 3073 rows); a batch's
// pixel rows are held until shaded (about 0.4 MB each at that size).
constexpr int kTriangleBatchSampleRows = 16;

// The triangles of a mesh as the back end's geometry: the y-sorted list with integer
// sample-row bounds feeding the active store.
class TriangleGeometry {
 public:
  TriangleGeometry(const TriangleMesh& mesh, const RenderSettings& s, const Lattice& lat,
                   int layers, Counters& stats)
      : mesh_(mesh), lat_(lat), store_(s, lat, layers, s.shading, stats), stats_(stats) {
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

  // Resolves sample row j, the r-th of its pixel row: the nearest triangles per sample.
  void ScanRow(int j, int r, double y, Sample* row, Rows& /*rows*/) {
    AddUpTo(j);
    store_.ScanRow(j, j - r, y, row, 0, stats_);
  }

  // The rows in batches (RenderBatches, on threads): whole pixel rows, about
  // kTriangleBatchSampleRows sample rows. `row` is a pixel row's last sample row.
  bool EndsBatch(int row) const {
    return EndsRowBlock(row, lat_.l == 1 ? 1 : lat_.l - 1, kTriangleBatchSampleRows);
  }
  // Sample rows [first, first + count): every triangle reaching them set up, in the order
  // one row at a time adds them.
  void PrepareRows(int first, int count) {
    first_ = first;
    AddUpTo(first + count - 1);
  }
  // The k-th prepared row, the r-th of its pixel row, counting into `stats`: on any thread,
  // other rows of the batch at once.
  void ScanPreparedRow(int k, int r, Sample* row, Rows& /*rows*/, Counters& stats) const {
    const int j = first_ + k;
    store_.ScanRow(j, j - r, lat_.At(j), row, 0, stats);
  }
  void FinishRows() {}

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
  // Sets up the triangles whose first sample row is at or above j.
  void AddUpTo(int j) {
    for (; nextY_ < ySorted_.size() && ySorted_[nextY_].first <= j; ++nextY_) {
      const YEntry& e = ySorted_[nextY_];
      const RasterTriangle& t = mesh_.triangles[e.index];
      store_.Add(mesh_.vertices[t.v[0]], mesh_.vertices[t.v[1]], mesh_.vertices[t.v[2]], t.surfaceId, e.last, e.first);
    }
  }

  const TriangleMesh& mesh_;
  const Lattice& lat_;
  TriangleStore store_;
  Counters& stats_;
  std::vector<YEntry> ySorted_;
  size_t nextY_ = 0;
  int first_ = 0;  // the prepared batch's first sample row
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
class FragmentGeometry {
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

  // One sample row being resolved: what the source hands its fragments, chords and
  // triangles to. Rows of a batch (FragmentSource::ScansInBatches) are resolved on any
  // threads at once, each with its own Target and counts; their sources hand over no
  // triangles (the store is scanned in row order).
  class Target final : public FragmentRow {
   public:
    Target(FragmentGeometry& geo, Sample* row, std::vector<Fragment>* pool, std::vector<Chord>* chords,
           Counters& stats, bool triangles)
        : geo_(geo), row_(row), pool_(pool), chords_(chords), stats_(stats), triangles_(triangles) {
      pool_->clear();
      chords_->clear();
    }

    void Add(int column, const Fragment& f) override {
      ++stats_[Counter::SamplesTested];
      if (column < 0 || column >= geo_.lat_.nx || !(f.w >= geo_.s_.hither) || !geo_.Shows(f)) return;
      Sample* keep = Of(column);
      // One layer: a nearer fragment takes the place of the pool's fragment it hides, which
      // nothing else refers to, so a row's pool holds at most a fragment a sample (within
      // its reserve: no allocation while rows are scanned).
      if (geo_.layers_ == 1 && keep->handle >= 0 && keep->handle < kChordHandle) {
        if (Behind(keep, 1, 1.0 / f.w)) return;
        keep->invW = 1.0 / f.w;
        (*pool_)[static_cast<std::size_t>(keep->handle)] = f;
        return;
      }
      const auto handle = static_cast<std::int32_t>(pool_->size());
      if (InsertNearest(keep, geo_.layers_, 1.0 / f.w, handle)) pool_->push_back(f);
    }

    bool Hidden(int column, double w) const override {
      return column < 0 || column >= geo_.lat_.nx || !(w >= geo_.s_.hither) ||
             Behind(Of(column), geo_.layers_, 1.0 / w);
    }

    // A chord is kept whole, and a sample of it made only when shaded (a hidden one never),
    // or when its side may drop it (culling, a one-sided material): then a sample the depth
    // test would keep is made first to ask its side.
    void AddChord(const Chord& c, const SampleColumns& columns) override {
      const auto handle = kChordHandle + static_cast<std::int32_t>(chords_->size());
      const int layers = geo_.layers_;
      bool kept = false;
      const double nearest = 1.0 / geo_.s_.hither;  // the largest 1/w in front of the hither plane
      const auto inFront = [&](double invW) { return invW > 0.0 && invW <= nearest; };  // false for NaN
      if (!geo_.sided_) {
        stats_[Counter::SamplesTested] += c.ForEachColumnInverseDepth(columns, [&](int column, double invW) {
          kept |= inFront(invW) && InsertNearest(Of(column), layers, invW, handle);
        });
      } else {
        c.ForEachColumnInverseDepth(columns, [&](int column, double invW) {
          if (!inFront(invW) || Behind(Of(column), layers, invW)) return;
          ++stats_[Counter::SamplesTested];
          if (!geo_.Shows(c.At(columns.At(column)))) return;
          if (InsertNearest(Of(column), layers, invW, handle)) kept = true;
        });
      }
      if (kept) chords_->push_back(c);
    }

    void AddTriangle(const RasterVertex& a, const RasterVertex& b, const RasterVertex& c,
                     std::uint32_t surfaceId) override {
      if (!triangles_) {
        geo_.failed_ = true;  // a batch's source broke its contract: stop, rather than draw it wrong
        return;
      }
      geo_.AddTriangle(a, b, c, surfaceId, std::numeric_limits<int>::min(), stats_);
    }

   private:
    Sample* Of(int column) const { return row_ + static_cast<std::ptrdiff_t>(column) * geo_.layers_; }
    FragmentGeometry& geo_;
    Sample* row_;
    std::vector<Fragment>* pool_;
    std::vector<Chord>* chords_;
    Counters& stats_;
    bool triangles_;
  };

  // What a batch's source hands its rows' triangles to (PreparedTriangles): the store, each
  // triangle from the row it came with.
  class TriangleTarget final : public FragmentRow {
   public:
    TriangleTarget(FragmentGeometry& geo, int row) : geo_(geo), row_(row) {}
    void Add(int, const Fragment&) override { geo_.failed_ = true; }  // ScanPreparedRow's
    bool Hidden(int, double) const override { return false; }
    void AddChord(const Chord&, const SampleColumns&) override { geo_.failed_ = true; }
    void AddTriangle(const RasterVertex& a, const RasterVertex& b, const RasterVertex& c,
                     std::uint32_t surfaceId) override {
      geo_.AddTriangle(a, b, c, surfaceId, row_, geo_.stats_);
    }

   private:
    FragmentGeometry& geo_;
    int row_;
  };

  // Resolves sample row j, the r-th of its pixel row, from the source's ScanRow.
  void ScanRow(int j, int r, double y, Sample* row, Rows& rows) {
    Target target(*this, row, &rows.pools[static_cast<size_t>(r)], &rows.chords[static_cast<size_t>(r)], stats_, true);
    if (!source_.ScanRow(y, Columns(), target)) failed_ = true;
    if (!store_.Empty()) store_.ScanRow(j, j - r, y, row, kTriangleHandle, stats_);
  }
  // The source's batches (FragmentSource::ScansInBatches). The triangles the batch's rows
  // hand over join the store first, each from the row it came with.
  bool EndsBatch(int row) const { return source_.EndsBatch(row); }
  void PrepareRows(int first, int count) {
    first_ = first;
    source_.PrepareRows(first, count);
    for (int k = 0; k < count; ++k) {
      TriangleTarget target(*this, first + k);
      source_.PreparedTriangles(k, target);
    }
  }
  void FinishRows() { source_.FinishRows(); }
  // Resolves the k-th row of the source's batch, the r-th of its pixel row, counting into
  // `stats`: on any thread, other rows at once.
  void ScanPreparedRow(int k, int r, Sample* row, Rows& rows, Counters& stats) {
    Target target(*this, row, &rows.pools[static_cast<size_t>(r)], &rows.chords[static_cast<size_t>(r)], stats, false);
    if (!source_.ScanPreparedRow(k, target)) failed_ = true;
    const int j = first_ + k;
    if (!store_.Empty()) store_.ScanRow(j, j - r, lat_.At(j), row, kTriangleHandle, stats);
  }
  SampleColumns Columns() const { return {lat_.offset, lat_.spacing, lat_.nx}; }

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
    return ShadeFragment(GroupFragment(rows, m, n, cx, cy), s_, &failed_, f);
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

  // A triangle a source hands over on sample row `firstRow` (or, row by row, the current):
  // into the store until its last sample row.
  void AddTriangle(const RasterVertex& a, const RasterVertex& b, const RasterVertex& c, std::uint32_t surfaceId,
                   int firstRow, Counters& stats) {
    ++stats[Counter::Triangles];
    double yMax = s_.height;
    if (a.h.z() > 0 && b.h.z() > 0 && c.h.z() > 0)
      yMax = std::max({a.h.y() / a.h.z(), b.h.y() / b.h.z(), c.h.y() / c.h.z()}) + kBoundsSlackPx;
    store_.Add(a, b, c, surfaceId, lat_.Floor(yMax, lat_.ny), firstRow);
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
  bool sided_ = false;  // !DepthDecides()
  TriangleStore store_;
  int first_ = 0;  // the prepared batch's first sample row
};

}  // namespace patchscan::raster::detail
