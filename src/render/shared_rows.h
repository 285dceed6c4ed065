// A direct render whose pixel rows are shared between processes (patchscan-mpi, src/mpi):
// the render-level interface the pipeline sees, so that neither the front end (src/xscan)
// nor the pipeline knows how rows travel between processes.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include "raster/scanline_renderer.h"
#include "render/report.h"
#include "xscan/partitioned_scan.h"

namespace patchscan::render {

class SharedRows {
 public:
  virtual ~SharedRows() = default;
  // This process's front end: its share of the surfaces, the rows it owns merged from every
  // process, and the scene's polygons.
  virtual DirectScanSource& Source() = 0;
  // The pixel rows rendered here (the back end's RenderSettings::ownsRow).
  virtual std::function<bool(int)> OwnedRows() const = 0;
  // The sink this process's finished rows go to, which brings the other processes' rows in
  // to `next` in order (null: straight to `next`).
  virtual std::unique_ptr<raster::RowSink> AssembleRows(raster::RowSink& next) = 0;
  // Every process's seconds, traffic and memory, for the report.
  virtual std::vector<ProcessReport> Processes() const = 0;
};

}  // namespace patchscan::render
