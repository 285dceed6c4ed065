// The wire format of patchscan-mpi (mpi/shared_scan.h): how a frame's sample rows are laid
// out between the processes, and what travels as flat messages of doubles. Every value of
// a fragment or triangle is a double or an integer far below 2^53, so nothing is rounded
// on the way.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "raster/fragment.h"
#include "raster/mesh.h"
#include "raster/scanline_renderer.h"
#include "raster/triangle_setup.h"

namespace patchscan::mpi {

// Pixel rows of a band: bands are dealt out to the processes round robin, so each renders
// a share of every part of the image (a scene's busy parts are shared too). Small bands
// share the load evenly; each band's first sample row is also its neighbour's last (with
// aa > 1), and triangles reaching across a band go to each owner.
constexpr int kBandRows = 8;

// The messages (mpi/shared_scan.h says who sends which).
enum Tag : int { kGo = 1, kRow, kPixels, kDone, kFinish };

// The frame's rows and who renders them.
struct Layout {
  int size = 1;                 // processes
  int aa = 1, height = 0, width = 0;  // the lattice: l, pixel rows and columns
  // Channels of a pixel row sent to process 0: colour and alpha, or with the AOVs (an EXR
  // with --aov, a depth map) all of raster::kChannels.
  int channels = raster::kChannels;
  int nRows = 0;                // sample rows
  double y0 = 0.0, dy = 1.0;    // sample row j lies at y0 + j dy
  int Owner(int p) const { return (p / kBandRows) % size; }
  int FirstSample(int p) const { return aa == 1 ? p : p * (aa - 1); }
  // The first pixel row that uses sample row j (with aa > 1 a row on a pixel edge is the
  // last of the pixel row above and the first of the one below).
  int FirstPixelOf(int j) const {
    if (aa == 1) return j;
    const int p = j / (aa - 1);
    return std::min(j % (aa - 1) == 0 && j > 0 ? p - 1 : p, height - 1);
  }
  // The first sample row at or below j that process o renders (nRows: none).
  int NextOwned(int o, int j) const {
    if (j >= nRows) return nRows;
    int p = FirstPixelOf(j);
    if (Owner(p) != o) {
      const int band = p / kBandRows;
      p = (band + ((o - band % size) % size + size) % size) * kBandRows;
      if (p >= height) return nRows;
    }
    return std::max(j, FirstSample(p));
  }
  bool Owns(int o, int j) const { return NextOwned(o, j) == j; }
  // The last pixel row process o renders (-1: none).
  int LastOwnedPixel(int o) const {
    const int bands = (height + kBandRows - 1) / kBandRows;
    for (int b = bands - 1; b >= 0 && b >= bands - size; --b)
      if (b % size == o) return std::min(height - 1, (b + 1) * kBandRows - 1);
    return -1;
  }
  // The last sample row a triangle covers, as the back end bounds it (FragmentGeometry).
  int LastRowOf(const raster::RasterVertex& a, const raster::RasterVertex& b, const raster::RasterVertex& c) const {
    if (!(a.h.z() > 0 && b.h.z() > 0 && c.h.z() > 0)) return nRows - 1;
    const double yMax = std::max({a.h.y() / a.h.z(), b.h.y() / b.h.z(), c.h.y() / c.h.z()}) + raster::kBoundsSlackPx;
    const double k = std::floor((yMax - y0) / dy);
    return k >= nRows - 1 ? nRows - 1 : (k >= -1.0 ? static_cast<int>(k) : -1);
  }
};

// What process 0 tells the others when a frame begins (kGo): the frame, the scan's
// options and the back end's sample lattice, so that every process scans the same rows.
struct FrameRequest {
  int frame = 0;
  bool extrapolate = true;
  int thetaSteps = 0, slabRows = 0;
  raster::SampleColumns columns;
  double y0 = 0.0, dy = 1.0;  // sample row j lies at y0 + j dy
  int nRows = 0, aa = 1;
  int channels = raster::kChannels;  // of a pixel row sent to process 0
  // As a message, and back (nullopt: not a request's length or values).
  std::vector<double> Encode() const;
  static std::optional<FrameRequest> Decode(const std::vector<double>& message);
};

// Sizes of the entries of a row's message, in doubles.
constexpr std::size_t kHeader = 5;     // row, ok, fragments, chords, triangles
constexpr std::size_t kFragmentBody = 17;  // w, position, normal, uv, duvdx, duvdy, id, colour
constexpr std::size_t kFragment = 2 + kFragmentBody;  // rank, column, fragment
// rank, xa, xb, orthographic, cubic, the ends' fragments, the normal's and depth's cubics
// and the root's u0
constexpr std::size_t kChord = 5 + 2 * kFragmentBody + 17;
constexpr std::size_t kVertex = 15;    // h, position, normal, uv, depth, colour
constexpr std::size_t kTriangle = 3 + 3 * kVertex;  // origin row, rank, id, three vertices

// A fragment's values (kFragmentBody of them) appended to a message, and read back.
void PutFragment(std::vector<double>& m, const raster::Fragment& f);
raster::Fragment GetFragment(const double* d);
// A chord (kChord values from its rank on) and a triangle's vertex (kVertex) read back.
raster::Chord DecodeChord(const double* d);
raster::RasterVertex DecodeVertex(const double* d);
// A message's text (a failure's reason), one character per double.
std::vector<double> Text(const std::string& s);
std::string TextOf(const double* d, std::size_t n);

// What one process's scan hands over on one sample row, each entry with its surface's
// rank in the scan order of all surfaces (polygons after every surface), each triangle
// with the last sample row it covers.
class RowEncoder final : public raster::FragmentRow {
 public:
  RowEncoder(const std::vector<std::uint32_t>& rank, const Layout& layout) : rank_(rank), layout_(layout) {}
  void Begin(int row) {
    row_ = row;
    fragments.clear();
    chords.clear();
    triangles.clear();
    lastRows.clear();
  }
  void Add(int column, const raster::Fragment& f) override;
  // A chord travels whole, as the back end keeps it (its samples shaded from it, a run of
  // a pixel's at their mean column): ends and cubics, made again bit for bit.
  void AddChord(const raster::Chord& c, const raster::SampleColumns&) override;
  void AddTriangle(const raster::RasterVertex& a, const raster::RasterVertex& b, const raster::RasterVertex& c,
                   std::uint32_t surfaceId) override;
  std::vector<double> fragments, chords, triangles;
  std::vector<int> lastRows;  // per triangle

 private:
  double Rank(std::uint32_t id) const { return id < rank_.size() ? rank_[id] : static_cast<double>(rank_.size()); }
  const std::vector<std::uint32_t>& rank_;
  const Layout& layout_;
  int row_ = 0;
};

// A row as received, and where its lists are.
struct RowMessage {
  std::vector<double> data;
  std::size_t nFragments = 0, nChords = 0, nTriangles = 0;
  bool ok = true;
  bool Parse(int row) {
    if (data.size() < kHeader || data[0] != row) return false;
    ok = data[1] != 0.0;
    nFragments = static_cast<std::size_t>(data[2]);
    nChords = static_cast<std::size_t>(data[3]);
    nTriangles = static_cast<std::size_t>(data[4]);
    return data.size() == kHeader + nFragments * kFragment + nChords * kChord + nTriangles * kTriangle;
  }
  const double* Fragment(std::size_t k) const { return data.data() + kHeader + k * kFragment; }
  const double* Chord(std::size_t k) const { return data.data() + kHeader + nFragments * kFragment + k * kChord; }
  const double* Triangle(std::size_t k) const {
    return data.data() + kHeader + nFragments * kFragment + nChords * kChord + k * kTriangle;
  }
};

// The entries of several messages in the order of their keys (fragments: the rank;
// triangles: the row they were handed over on, then the rank): each message's are in that
// order already and no two messages share a rank, so a k-way merge, ties kept in order.
template <class Count, class Less, class At, class Take>
void Merge(const std::vector<RowMessage>& m, Count count, At at, Less less, Take take, std::vector<std::size_t>* next) {
  next->assign(m.size(), 0);
  for (;;) {
    std::size_t best = m.size();
    for (std::size_t k = 0; k < m.size(); ++k)
      if ((*next)[k] < count(m[k]) && (best == m.size() || less(at(m[k], (*next)[k]), at(m[best], (*next)[best]))))
        best = k;
    if (best == m.size()) return;
    take(at(m[best], (*next)[best]++));
  }
}

}  // namespace patchscan::mpi
