// What `render --stats` prints and `--stats-json` writes: every counter of the table
// (core/counters.h) of the groups the mode runs, the ratios derived from them, the time
// of each phase and the peak memory.
#pragma once

#include <iosfwd>
#include <string>
#include <vector>

#include "cli/render.h"
#include "core/counters.h"

namespace patchscan::cli {

struct RenderReport {
  RenderMode mode = RenderMode::Exact;
  Counters counters;  // the front end's and the back end's
  // Seconds: reading the scene, setting up (the scan, or tessellation), rendering (with
  // the output), of which encoding and writing the image.
  double load = 0.0, setUp = 0.0, render = 0.0, output = 0.0;
  long peakKiB = 0;
  // Direct modes: each worker's seconds scanning its share of the surfaces, and the
  // compositor's merging their rows.
  std::vector<double> workerSeconds;
  double compositeSeconds = 0.0;
  std::string texture;  // what became of the texture: "none", "opened, N lookups", ...
  bool imageLibrary = false;  // whether OpenImageIO's module was loaded (raster/image_io.h)
  // patchscan-mpi: each process's seconds, traffic and peak memory.
  std::vector<DirectScanSource::Process> processes;
};

// The human-readable report (--stats), one group of counters after another.
void PrintReport(const RenderReport& report, std::ostream& out);

// The report as one JSON object: "mode", every counter and ratio by its key (all groups,
// zero where the mode does not run them), "seconds_load", "seconds_tessellate" (the set-up),
// "seconds_render", "seconds_output", "peak_rss_kib" and "image_library_loaded".
std::string ReportJson(const RenderReport& report);

}  // namespace patchscan::cli
