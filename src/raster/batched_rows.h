// The back end's row loop in batches, on threads: per batch of pixel rows the geometry
// prepares its sample rows (its serial part: a front end's Y scan, FragmentSource::
// ScansInBatches, xscan/row_scan.h; or a mesh's triangles reaching the batch set up), every
// thread resolves some of them (the rows' surfaces hiding each other's samples as in one
// scan), and a pixel row whose sample rows are all resolved is shaded by the thread that
// completed it, as a task that may run on while the next batch is prepared and resolved;
// the calling thread hands rows to the sink in order. Memory: one batch of pixel rows and
// the row above it.
#pragma once

#include <optional>

#include "raster/row_geometry.h"

namespace patchscan::raster::detail {

// Geometry: FragmentGeometry or TriangleGeometry (raster/row_geometry.h).
template <class Geometry>
std::optional<Counters> RenderBatches(Geometry& geo, const RenderSettings& s, const Lattice& lat, int layers,
                                      Counters& stats, RowSink& sink, BackEndTimes* times);

}  // namespace patchscan::raster::detail
