#include "mpi/wire.h"

#include <iterator>

namespace patchscan::mpi {
namespace {

void Put(std::vector<double>& m, const Vec3& v) { m.insert(m.end(), {v.x(), v.y(), v.z()}); }
void Put(std::vector<double>& m, const Vec2& v) { m.insert(m.end(), {v.x(), v.y()}); }
Vec3 Get3(const double* d) { return Vec3(d[0], d[1], d[2]); }
Vec2 Get2(const double* d) { return Vec2(d[0], d[1]); }

}  // namespace

void PutFragment(std::vector<double>& m, const raster::Fragment& f) {
  m.push_back(f.w);
  Put(m, f.position);
  Put(m, f.normal);
  Put(m, f.uv);
  Put(m, f.duvdx);
  Put(m, f.duvdy);
  m.push_back(f.surfaceId);
  Put(m, f.colour);
}

raster::Fragment GetFragment(const double* d) {
  raster::Fragment f;
  f.w = d[0];
  f.position = Get3(d + 1);
  f.normal = Get3(d + 4);
  f.uv = Get2(d + 7);
  f.duvdx = Get2(d + 9);
  f.duvdy = Get2(d + 11);
  f.surfaceId = static_cast<std::uint32_t>(d[13]);
  f.colour = Get3(d + 14);
  return f;
}

void RowEncoder::Add(int column, const raster::Fragment& f) {
  fragments.insert(fragments.end(), {Rank(f.surfaceId), static_cast<double>(column)});
  PutFragment(fragments, f);
}

void RowEncoder::AddChord(const raster::Chord& c, const raster::SampleColumns&) {
  const raster::Chord::Cubics* cubics = c.cubics();
  chords.insert(chords.end(), {Rank(c.a().surfaceId), c.xa(), c.xb(), c.orthographic() ? 1.0 : 0.0,
                               cubics ? 1.0 + cubics->root : 0.0});
  PutFragment(chords, c.a());
  PutFragment(chords, c.b());
  const raster::Chord::Cubics none;
  const raster::Chord::Cubics& k = cubics ? *cubics : none;
  for (const Vec3& n : k.normal) Put(chords, n);
  chords.insert(chords.end(), std::begin(k.depth), std::end(k.depth));
  chords.push_back(k.u0);
}

void RowEncoder::AddTriangle(const raster::RasterVertex& a, const raster::RasterVertex& b, const raster::RasterVertex& c,
                             std::uint32_t surfaceId) {
  triangles.insert(triangles.end(), {static_cast<double>(row_), Rank(surfaceId), static_cast<double>(surfaceId)});
  for (const raster::RasterVertex* v : {&a, &b, &c}) {
    Put(triangles, v->h);
    Put(triangles, v->position);
    Put(triangles, v->normal);
    Put(triangles, v->uv);
    triangles.push_back(v->depth);
    Put(triangles, v->colour);
  }
  lastRows.push_back(layout_.LastRowOf(a, b, c));
}

raster::Chord DecodeChord(const double* d) {
  const double* cubic = d + 5 + 2 * kFragmentBody;
  raster::Chord::Cubics k;
  for (int i = 0; i < 4; ++i) k.normal[i] = Get3(cubic + 3 * i), k.depth[i] = cubic[12 + i];
  k.root = static_cast<int>(d[4]) - 1;
  k.u0 = cubic[16];
  return raster::Chord(d[1], GetFragment(d + 5), d[2], GetFragment(d + 5 + kFragmentBody), d[3] != 0.0,
                       d[4] != 0.0 ? &k : nullptr);
}

raster::RasterVertex DecodeVertex(const double* d) {
  raster::RasterVertex v;
  v.h = Get3(d);
  v.position = Get3(d + 3);
  v.normal = Get3(d + 6);
  v.uv = Get2(d + 9);
  v.depth = d[11];
  v.colour = Get3(d + 12);
  return v;
}

std::vector<double> Text(const std::string& s) { return std::vector<double>(s.begin(), s.end()); }
std::string TextOf(const double* d, std::size_t n) {
  std::string s;
  for (std::size_t k = 0; k < n; ++k) s += static_cast<char>(d[k]);
  return s;
}

// The request's values in a fixed order: frame, extrapolate, θ steps, slab rows, the
// sample columns (x0, dx, n), y0, dy, rows, aa, channels.
constexpr std::size_t kRequestValues = 12;

std::vector<double> FrameRequest::Encode() const {
  return {static_cast<double>(frame), extrapolate ? 1.0 : 0.0, static_cast<double>(thetaSteps),
          static_cast<double>(slabRows), columns.x0, columns.dx, static_cast<double>(columns.n), y0, dy,
          static_cast<double>(nRows), static_cast<double>(aa), static_cast<double>(channels)};
}

std::optional<FrameRequest> FrameRequest::Decode(const std::vector<double>& m) {
  if (m.size() != kRequestValues) return std::nullopt;
  for (const double v : m)
    if (!std::isfinite(v)) return std::nullopt;
  // Every count is a whole number in int's range.
  for (const std::size_t k : {0u, 2u, 3u, 6u, 9u, 10u, 11u})
    if (m[k] != std::floor(m[k]) || std::abs(m[k]) > 1e9) return std::nullopt;
  FrameRequest r;
  r.frame = static_cast<int>(m[0]);
  r.extrapolate = m[1] != 0.0;
  r.thetaSteps = static_cast<int>(m[2]);
  r.slabRows = static_cast<int>(m[3]);
  r.columns = raster::SampleColumns{m[4], m[5], static_cast<int>(m[6])};
  r.y0 = m[7];
  r.dy = m[8];
  r.nRows = static_cast<int>(m[9]);
  r.aa = static_cast<int>(m[10]);
  r.channels = static_cast<int>(m[11]);
  return r;
}

}  // namespace patchscan::mpi
