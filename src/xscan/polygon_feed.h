// Feeds a scene's polygons to the back end: their triangles in homogeneous screen space,
// handed over with the rows of a direct render (as a θ slab's are) or appended to a
// tessellated mesh. Polygons are planar: their triangles are exact in every mode.
#pragma once

#include <cstdint>
#include <vector>

#include "patch/camera.h"
#include "patch/polygon.h"
#include "raster/fragment.h"
#include "raster/mesh.h"

namespace patchscan {

// The triangles of `mesh` for `camera` appended to `out`, with surface id `id`.
void AppendPolygonTriangles(const PolygonMesh& mesh, const Camera& camera, std::uint32_t id, raster::TriangleMesh* out);

// Polygon triangles handed over row by row: at sample row y, those whose top is above the
// next row (y + dy), in the order of their tops (then as given).
class PolygonQueue {
 public:
  explicit PolygonQueue(raster::TriangleMesh triangles);
  // Hands over the triangles due at sample row y, the rows being dy apart.
  void HandOver(double y, double dy, raster::FragmentRow& out);

 private:
  raster::TriangleMesh mesh_;
  std::vector<double> top_;           // per triangle of order_, its highest screen y
  std::vector<std::uint32_t> order_;  // triangles by top
  std::size_t next_ = 0;
};

// A direct render's source with polygons: each row is the inner source's, then the
// polygons' triangles due there (PolygonQueue), so the row's fragments and triangles reach
// the back end in an order that depends on the scene alone, whatever the inner source's
// number of workers.
class PolygonFeed final : public raster::FragmentSource {
 public:
  // `inner` must outlive the feed.
  PolygonFeed(raster::FragmentSource& inner, raster::TriangleMesh triangles);

  void BeginRows(const raster::SampleColumns& columns, double y0, double dy, int nRows,
                 const raster::KeptDepths& kept) override;
  bool ScanRow(double y, const raster::SampleColumns& columns, raster::FragmentRow& out) override;

  // In batches when the inner source is: a row's polygon triangles follow its own (all
  // handed over by PreparedTriangles, in row order).
  bool ScansInBatches() const override { return inner_.ScansInBatches(); }
  bool EndsBatch(int row) const override { return inner_.EndsBatch(row); }
  void PrepareRows(int first, int count) override;
  void PreparedTriangles(int k, raster::FragmentRow& out) override;
  bool ScanPreparedRow(int k, raster::FragmentRow& out) override { return inner_.ScanPreparedRow(k, out); }
  void FinishRows() override { inner_.FinishRows(); }

 private:
  raster::FragmentSource& inner_;
  PolygonQueue queue_;
  double y0_ = 0.0, dy_ = 1.0;
  int first_ = 0;  // the prepared batch's first row
};

}  // namespace patchscan
