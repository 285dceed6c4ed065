// The back end's row loop for a source that scans in batches (FragmentSource::ScansInBatches,
// xscan/row_scan.h): per batch of pixel rows, the source prepares its sample rows (its
// serial part), every thread resolves some of them (the source's X scans straight into the
// rows' samples, the rows' surfaces hiding each other's samples as in one scan), the batch
// is finished, and its pixel rows are shaded as tasks while the next batch is prepared and
// resolved; the calling thread hands rows to the sink in order. Memory: two batches of pixel
// rows and the row above them.
#pragma once

#include <optional>

#include "raster/row_geometry.h"

namespace patchscan::raster::detail {

std::optional<Counters> RenderBatches(FragmentGeometry& geo, FragmentSource& source, const RenderSettings& s,
                                      const Lattice& lat, int layers, Counters& stats, RowSink& sink,
                                      BackEndTimes* times);

}  // namespace patchscan::raster::detail
