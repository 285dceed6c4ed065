#include "xscan/polygon_feed.h"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace patchscan {

void AppendPolygonTriangles(const PolygonMesh& mesh, const Camera& camera, std::uint32_t id, raster::TriangleMesh* out) {
  const Mat4 screenFromWorld = ScreenFromWorld(camera);
  const Vec4 depthRow = ViewDepthRow(camera);
  const auto base = static_cast<std::uint32_t>(out->vertices.size());
  for (const PolygonVertex& v : mesh.vertices) {
    const Vec4 h = screenFromWorld * v.position.homogeneous();
    out->vertices.push_back({Vec3(h.x(), h.y(), h.w()), v.position, v.normal, v.st,
                             depthRow.dot(v.position.homogeneous()), v.colour});
  }
  for (const auto& t : mesh.triangles) out->triangles.push_back({{base + t[0], base + t[1], base + t[2]}, id});
}

PolygonQueue::PolygonQueue(raster::TriangleMesh triangles) : mesh_(std::move(triangles)) {
  const std::size_t n = mesh_.triangles.size();
  std::vector<double> top(n);
  for (std::size_t k = 0; k < n; ++k) {
    double y = INFINITY;
    for (const std::uint32_t v : mesh_.triangles[k].v) {
      const Vec3& h = mesh_.vertices[v].h;
      // A triangle reaching behind the eye has no screen bound: it starts with the image.
      y = h.z() > 0.0 ? std::min(y, h.y() / h.z()) : -INFINITY;
      if (y == -INFINITY) break;
    }
    top[k] = std::isnan(y) ? -INFINITY : y;
  }
  order_.resize(n);
  std::iota(order_.begin(), order_.end(), 0u);
  std::stable_sort(order_.begin(), order_.end(), [&](std::uint32_t a, std::uint32_t b) { return top[a] < top[b]; });
  top_.resize(n);
  for (std::size_t k = 0; k < n; ++k) top_[k] = top[order_[k]];
}

void PolygonFeed::BeginRows(const raster::SampleColumns& columns, double y0, double dy, int nRows,
                            const raster::KeptDepths& kept) {
  y0_ = y0;
  dy_ = dy;
  inner_.BeginRows(columns, y0, dy, nRows, kept);
}

void PolygonFeed::PrepareRows(int first, int count) {
  first_ = first;
  inner_.PrepareRows(first, count);
}

void PolygonFeed::PreparedTriangles(int k, raster::FragmentRow& out) {
  inner_.PreparedTriangles(k, out);
  queue_.HandOver(raster::RowY(y0_, dy_, first_ + k), dy_, out);
}

void PolygonQueue::HandOver(double y, double dy, raster::FragmentRow& out) {
  // A triangle whose top lies above the next row has no sample above this one: it is
  // handed over now (Woo and Chall 1990 §3.3's y-sorted list, met row by row).
  for (; next_ < order_.size() && top_[next_] < y + dy; ++next_) {
    const raster::RasterTriangle& t = mesh_.triangles[order_[next_]];
    out.AddTriangle(mesh_.vertices[t.v[0]], mesh_.vertices[t.v[1]], mesh_.vertices[t.v[2]], t.surfaceId);
  }
}

PolygonFeed::PolygonFeed(raster::FragmentSource& inner, raster::TriangleMesh triangles)
    : inner_(inner), queue_(std::move(triangles)) {}

bool PolygonFeed::ScanRow(double y, const raster::SampleColumns& columns, raster::FragmentRow& out) {
  if (!inner_.ScanRow(y, columns, out)) return false;
  queue_.HandOver(y, dy_, out);
  return true;
}

}  // namespace patchscan
