#include "render/report.h"

#include <sys/resource.h>

#include <cstdio>
#include <ostream>
#include <sstream>

namespace patchscan::render {
namespace {

// The counter groups a mode runs, in the table's order.
bool Runs(RenderMode mode, CounterGroup g) {
  switch (g) {
    case CounterGroup::BackEnd: return true;
    case CounterGroup::Theta:
    case CounterGroup::Slabs: return mode == RenderMode::Theta;
    default: return Direct(mode);
  }
}

}  // namespace

long PeakResidentKiB() {
  // The kernel's high-water mark of this process's own memory (VmHWM, proc(5)). Not
  // getrusage's ru_maxrss: Linux carries that across exec, so a program started by a
  // larger one (a Python bench) would report its parent's peak as its own.
  if (std::FILE* f = std::fopen("/proc/self/status", "r")) {
    char line[256];
    long kib = -1;
    while (kib < 0 && std::fgets(line, sizeof line, f))
      if (std::sscanf(line, "VmHWM: %ld kB", &kib) != 1) kib = -1;
    std::fclose(f);
    if (kib >= 0) return kib;
  }
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return u.ru_maxrss;
}

void PrintReport(const RenderReport& r, std::ostream& out) {
  char line[256];
  for (std::size_t g = 0; g < kCounterGroupTitles.size(); ++g) {
    const auto group = static_cast<CounterGroup>(g);
    if (!Runs(r.mode, group)) continue;
    out << kCounterGroupTitles[g] << ":\n";
    for (const CounterInfo& c : kCounterTable) {
      if (c.group != group) continue;
      std::snprintf(line, sizeof line, "  %-36s %12lld %-12s %.*s\n", std::string(c.key).c_str(),
                    static_cast<long long>(r.counters[c.counter]), std::string(c.unit).c_str(),
                    static_cast<int>(c.description.size()), c.description.data());
      out << line;
    }
    for (const CounterRatio& q : kCounterRatios) {
      if (q.group != group) continue;
      std::snprintf(line, sizeof line, "  %-36s %12.3f %-12s %.*s\n", std::string(q.key).c_str(), r.counters.Ratio(q),
                    "", static_cast<int>(q.description.size()), q.description.data());
      out << line;
    }
  }
  if (!r.workerSeconds.empty()) {
    out << "workers: " << r.workerSeconds.size() << ", seconds scanning each:";
    for (double t : r.workerSeconds) out << ' ' << t;
    out << "; compositor " << r.compositeSeconds << " s (" << (r.render > 0 ? 100.0 * r.compositeSeconds / r.render : 0.0)
        << " % of the render)\n";
  }
  {
    const raster::BackEndTimes& b = r.backEnd;
    double shading = 0.0;
    int busy = 0;
    for (const double t : b.shading) shading += t, busy += t > 0.0;
    out << "time in the back end: resolving rows " << b.resolve << " s and handing them over " << b.handOver
        << " s on the calling thread; shading " << shading << " s on " << busy << " thread" << (busy == 1 ? "" : "s")
        << ":";
    for (const double t : b.shading)
      if (t > 0.0) out << ' ' << t;
    out << '\n';
  }
  for (const ProcessReport& p : r.processes)
    out << "process " << p.rank << ": scanning " << p.seconds << " s, sent " << p.bytesSent << " bytes, received "
        << p.bytesReceived << " bytes, peak memory " << p.peakKiB << " KiB\n";
  out << "time: load " << r.load << " s, " << (Direct(r.mode) ? "set up " : "tessellate ") << r.setUp
      << " s, render " << r.render << " s (of which writing the image " << r.output << " s)\npeak memory: "
      << r.peakKiB << " KiB\ntexture: " << r.texture << "\nimage library (OpenImageIO): "
      << (r.imageLibrary ? "loaded" : "not loaded") << "\nCAD library (Open CASCADE): "
      << (r.cadLibrary ? "loaded" : "not loaded") << '\n';
}

std::string ReportJson(const RenderReport& r) {
  std::ostringstream js;
  js << "{\"mode\": \"" << ModeName(r.mode) << '"';
  for (const CounterInfo& c : kCounterTable) js << ", \"" << c.key << "\": " << r.counters[c.counter];
  for (const CounterRatio& q : kCounterRatios) js << ", \"" << q.key << "\": " << r.counters.Ratio(q);
  js << ", \"seconds_load\": " << r.load << ", \"seconds_tessellate\": " << r.setUp << ", \"seconds_render\": "
     << r.render << ", \"seconds_output\": " << r.output << ", \"seconds_workers\": [";
  for (std::size_t k = 0; k < r.workerSeconds.size(); ++k) js << (k ? ", " : "") << r.workerSeconds[k];
  js << "], \"seconds_composite\": " << r.compositeSeconds << ", \"seconds_resolve\": " << r.backEnd.resolve
     << ", \"seconds_hand_over\": " << r.backEnd.handOver << ", \"seconds_shading\": [";
  for (std::size_t k = 0; k < r.backEnd.shading.size(); ++k) js << (k ? ", " : "") << r.backEnd.shading[k];
  js << "], \"peak_rss_kib\": " << r.peakKiB
     << ", \"image_library_loaded\": " << (r.imageLibrary ? "true" : "false")
     << ", \"cad_library_loaded\": " << (r.cadLibrary ? "true" : "false");
  if (!r.processes.empty()) {
    js << ", \"processes\": [";
    for (std::size_t k = 0; k < r.processes.size(); ++k) {
      const ProcessReport& p = r.processes[k];
      js << (k ? ", " : "") << "{\"rank\": " << p.rank << ", \"seconds_scanning\": " << p.seconds
         << ", \"bytes_sent\": " << p.bytesSent << ", \"bytes_received\": " << p.bytesReceived
         << ", \"peak_rss_kib\": " << p.peakKiB << '}';
    }
    js << ']';
  }
  js << "}\n";
  return js.str();
}

}  // namespace patchscan::render
