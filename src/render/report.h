// What a render took: every counter of the table (core/counters.h) of the groups the mode
// runs, the ratios derived from them, the time of each phase and the peak memory; printed
// for people (`render --stats`) or written as JSON (`--stats-json`).
#pragma once

#include <cstdint>
#include <iosfwd>
#include <string>
#include <vector>

#include "core/counters.h"
#include "render/options.h"

namespace patchscan::render {

// One process of a render shared between processes (render/shared_rows.h): its rank, its
// seconds scanning, the bytes it sent and received, its peak resident memory.
struct ProcessReport {
  int rank = 0;
  double seconds = 0.0;
  std::int64_t bytesSent = 0, bytesReceived = 0;
  long peakKiB = 0;
};

struct RenderReport {
  RenderMode mode = RenderMode::Exact;
  // The image written: its file, its size in pixels (the crop window's, with a crop), and
  // whether it is a depth map (a "zfile" or "shadow" Display) rather than a picture.
  std::string image;
  int width = 0, height = 0;
  bool depthMap = false;
  Counters counters;  // the front end's and the back end's
  // Seconds: reading the scene, setting up (the scan, or tessellation), rendering (with
  // the output), of which encoding and writing the image.
  double load = 0.0, setUp = 0.0, render = 0.0, output = 0.0;
  long peakKiB = 0;
  // Direct modes: each worker's seconds scanning its share of the surfaces, and the
  // compositor's merging their rows.
  std::vector<double> workerSeconds;
  double compositeSeconds = 0.0;
  // The back end's seconds: resolving rows and handing them over (the calling thread's,
  // serial), and shading on each thread.
  raster::BackEndTimes backEnd;
  std::string texture;  // what became of the texture: "none", "opened, N lookups", ...
  bool imageLibrary = false;  // whether OpenImageIO's module was loaded (raster/image_io.h)
  bool cadLibrary = false;    // whether the CAD module was loaded (scene/cad_library.h)
  // A render shared between processes: each process's seconds, traffic and peak memory.
  std::vector<ProcessReport> processes;
};

// The human-readable report, one group of counters after another.
void PrintReport(const RenderReport& report, std::ostream& out);

// The report as one JSON object: "mode", every counter and ratio by its key (all groups,
// zero where the mode does not run them), "seconds_load", "seconds_tessellate" (the set-up),
// "seconds_render", "seconds_output", "seconds_workers" (each scanning worker's),
// "seconds_composite", "seconds_resolve" and "seconds_hand_over" (the back end's serial
// part, on the calling thread), "seconds_shading" (each thread's), "peak_rss_kib" and
// "image_library_loaded".
std::string ReportJson(const RenderReport& report);

// Peak resident memory of this process so far, in KiB.
long PeakResidentKiB();

}  // namespace patchscan::render
