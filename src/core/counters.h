// Every count the renderer keeps (what the papers count), declared once
// in the table below: its key in `--stats-json`, what it counts, and the unit of one count.
// A stage bumps the Counters its owner hands it (`++counters[Counter::Walks]`); `--stats`,
// `--stats-json` and the tests read them through this table. Counters are reports only:
// no decision of the renderer reads one.
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <string_view>

namespace patchscan {

// Which part of the pipeline a counter belongs to, in the order `--stats` prints them.
enum class CounterGroup : std::uint8_t {
  Setup,    // surfaces set up and the maxima pre-pass (Blinn 1978 §3.2.2.1)
  YScan,    // edge and silhouette trackers and their events (§3.2)
  XScan,    // walks along each scan line's level curves, exact samples (§3.3)
  Theta,    // θ chains and θ and turn trackers (§4)
  Slabs,    // θ slabs handed to the back end as triangles
  BackEnd,  // the scan-line back end (Woo and Chall 1990)
};
inline constexpr std::array<std::string_view, 6> kCounterGroupTitles = {
    "set up", "y scan", "x scan", "theta", "slabs", "back end"};

// How the counts of two workers combine: added, or (Max) the larger: counts every worker
// keeps alike (the rows and intervals all of them scan) and peaks (the most active at once).
enum class CounterMerge : std::uint8_t { Sum, Max };

// X(group, Name, key, description, unit, merge)
#define PATCHSCAN_COUNTERS(X)                                                                                      \
  X(Setup, Surfaces, "surfaces", "in the scene", "surfaces", Sum)                                                  \
  X(Setup, SurfacesSetUp, "surfaces_set_up", "set up when the scan reached them", "surfaces", Sum)                 \
  X(Setup, MaxActiveSurfaces, "max_active_surfaces", "active at once, at most", "surfaces", Max)                   \
  X(Setup, MaximaSeeds, "maxima_seeds", "hill climbs of the maxima pre-pass", "climbs", Sum)                       \
  X(Setup, MaximaClimbIterations, "maxima_climb_iterations", "hill-climbing steps", "steps", Sum)                  \
  X(Setup, MaximaNewtonIterations, "maxima_newton_iterations", "Newton iterations on grad y = 0", "iterations", Sum) \
  X(Setup, MaximaDuplicates, "maxima_duplicates", "climbs that found a point already found", "climbs", Sum)         \
  X(Setup, MaximaProvenMonotone, "maxima_proven_monotone", "surfaces whose y is proven monotone in u and v: one corner maximum, no climbs", "surfaces", Sum) \
  X(Setup, MaximaRejectedCollapsed, "maxima_rejected_collapsed", "climbs stopped on a collapsed edge that is no maximum", "climbs", Sum) \
  X(Setup, Stationary, "stationary_points", "maxima and saddles", "points", Sum)                                   \
  X(YScan, SampleRows, "sample_rows", "sample rows scanned", "rows", Max)                                          \
  X(YScan, TrackerRows, "tracker_rows", "edge and silhouette trackers advanced, summed over rows", "tracker-rows", Sum) \
  X(YScan, EdgeNewtonCalls, "edge_newton_calls", "edge-tracker Newton solves", "calls", Sum)                        \
  X(YScan, EdgeNewtonIterations, "edge_newton_iterations", "edge-tracker Newton iterations", "iterations", Sum)     \
  X(YScan, EdgeRepairs, "edge_repairs", "edge trackers repaired inside their piece", "repairs", Sum)                \
  X(YScan, EdgeBorn, "edge_trackers_born", "edge trackers born at the top of a monotone piece", "trackers", Sum)    \
  X(YScan, EdgeDied, "edge_trackers_died", "edge trackers died at the bottom of a piece", "trackers", Sum)          \
  X(YScan, TrimNewtonCalls, "trim_newton_calls", "trim-curve tracker Newton solves", "calls", Sum)               \
  X(YScan, TrimNewtonIterations, "trim_newton_iterations", "trim-curve tracker Newton iterations", "iterations", Sum) \
  X(YScan, TrimRepairs, "trim_repairs", "trim-curve trackers repaired inside their piece", "repairs", Sum)            \
  X(YScan, TrimBorn, "trim_trackers_born", "trim-curve trackers born at the top of a monotone piece", "trackers", Sum) \
  X(YScan, TrimDied, "trim_trackers_died", "trim-curve trackers died at the bottom of a piece", "trackers", Sum)   \
  X(YScan, Folds, "folds", "silhouettes crossing a boundary edge (J changed sign)", "folds", Sum)                  \
  X(YScan, SilhouetteNewtonCalls, "silhouette_newton_calls", "silhouette-tracker Newton solves", "calls", Sum)      \
  X(YScan, SilhouetteNewtonIterations, "silhouette_newton_iterations", "silhouette-tracker Newton iterations", "iterations", Sum) \
  X(YScan, SilhouettesBornAtMaxima, "silhouettes_born_at_maxima", "silhouette trackers born at maxima", "trackers", Sum) \
  X(YScan, SilhouettesBornAtFolds, "silhouettes_born_at_folds", "silhouette trackers born at folds", "trackers", Sum) \
  X(YScan, SilhouettesBornAtSaddles, "silhouettes_born_at_saddles", "silhouette trackers born at saddles", "trackers", Sum) \
  X(YScan, SilhouettesDied, "silhouettes_died", "silhouette trackers whose Newton failed (a minimum)", "trackers", Sum) \
  X(YScan, SilhouettesLeft, "silhouettes_left", "silhouette trackers that left the domain", "trackers", Sum)       \
  X(YScan, SilhouettesMerged, "silhouettes_merged", "silhouette trackers merged with another", "trackers", Sum)     \
  X(YScan, SilhouettesAdopted, "silhouettes_adopted", "silhouettes found by the x scan and tracked from then on", "trackers", Sum) \
  X(YScan, RepairSearches, "repair_searches", "subdivision searches after an unexplained event", "searches", Sum)  \
  X(YScan, RepairedBySearch, "repaired_by_search", "lost crossings the searches found", "crossings", Sum)         \
  X(YScan, MinimumSearches, "minimum_searches", "searches around a pair of trackers that met (a minimum of the curve)", "searches", Sum) \
  X(XScan, Walks, "walks", "walks along level curves", "walks", Sum)                                               \
  X(XScan, ClosedWalks, "closed_walks", "walks around closed level curves", "walks", Sum)                           \
  X(XScan, ColumnSteps, "column_steps", "walk steps aimed at a sample column", "steps", Sum)                        \
  X(XScan, ArcSteps, "arc_steps", "walk steps along the curve between columns", "steps", Sum)                      \
  X(XScan, ColumnsSolved, "columns_solved", "sample columns solved on a curve", "samples", Sum)                     \
  X(XScan, XscanNewtonCalls, "xscan_newton_calls", "per-sample Newton solves", "calls", Sum)                       \
  X(XScan, XscanNewtonIterations, "xscan_newton_iterations", "per-sample Newton iterations", "iterations", Sum)    \
  X(XScan, SilhouettePoints, "silhouette_points", "silhouette points passed by the walks", "points", Sum)          \
  X(XScan, UntrackedSilhouettes, "untracked_silhouettes", "silhouettes found with no tracker (repaired)", "points", Sum) \
  X(XScan, UntrackedExits, "untracked_exits", "boundary exits found with no edge tracker (repaired)", "points", Sum) \
  X(XScan, TrimCrossings, "trim_crossings", "trim-curve crossings passed by the walks", "points", Sum)         \
  X(XScan, Failures, "failures", "walks or samples given up", "failures", Sum)                                     \
  X(XScan, Fragments, "fragments", "exact or chord fragments of the samples covered (made, or skipped as hidden by depth)", "fragments", Sum)            \
  X(Theta, ThetaChains, "theta_chains", "chains crawled", "chains", Sum)                                          \
  X(Theta, ThetaVertices, "theta_vertices", "chain vertices", "vertices", Sum)                                      \
  X(Theta, ThetaSteps, "theta_steps", "crawl steps", "steps", Sum)                                                 \
  X(Theta, ThetaTurnPoints, "theta_turn_points", "turn points found by the crawl (§4.3)", "vertices", Sum)         \
  X(Theta, ThetaTilts, "theta_tilts", "tilt vertices (the normal left the scan plane)", "vertices", Sum)           \
  X(Theta, ThetaChordSplits, "theta_chord_splits", "of those, where a link's chord missed the surface's normal", "vertices", Sum) \
  X(Theta, ThetaCrawlIterations, "theta_crawl_iterations", "Newton iterations placing the crawl's tracker vertices", "iterations", Sum) \
  X(Theta, ThetaTrackers, "theta_trackers", "θ trackers advanced from the line before", "trackers", Sum)            \
  X(Theta, ThetaTrackerIterations, "theta_tracker_iterations", "θ-tracker Newton iterations", "iterations", Sum)    \
  X(Theta, ThetaTrackersLost, "theta_trackers_lost", "θ trackers lost (left the patch or no convergence)", "trackers", Sum) \
  X(Theta, ThetaTurnTrackers, "theta_turn_trackers", "turn points advanced from the line before", "trackers", Sum) \
  X(Theta, ThetaTurnIterations, "theta_turn_iterations", "turn-tracker Newton iterations", "iterations", Sum)      \
  X(Theta, ThetaTurnsLost, "theta_turns_lost", "turn trackers lost (the turn pair met)", "trackers", Sum)          \
  X(Theta, ThetaTiltTrackers, "theta_tilt_trackers", "tilt trackers solved: tilt vertices advanced from the line before, and links' middles checked", "trackers", Sum) \
  X(Theta, ThetaTiltIterations, "theta_tilt_iterations", "tilt-tracker Newton iterations", "iterations", Sum)      \
  X(Theta, ThetaLinkRepairs, "theta_link_repairs", "links repaired sideways (§4.2)", "links", Sum)                 \
  X(Theta, ThetaLinksFilled, "theta_links_filled", "of those, mended by Newton: tabulated vertices filled in, or split by tilt vertices", \
    "links", Sum)                                                                                                      \
  X(Theta, ThetaLineRepairs, "theta_line_repairs", "quiet lines crawled afresh (a chain could not be advanced)", "lines", Sum) \
  X(Theta, ThetaRowsAdvanced, "theta_rows_advanced", "surface rows whose chains were advanced from the row before", "rows", Sum) \
  X(Theta, ThetaExactSurfaces, "theta_exact_surfaces", "surfaces that take the exact X scan: their normal turns many θ steps per pixel, or their chains came to hold more vertices than samples pay for", "surfaces", Sum) \
  X(Theta, ThetaExactJudged, "theta_exact_judged", "of those, sent by their rows: chains holding more vertices per sample than pay (the others by their normal, before their first row)", "surfaces", Sum) \
  X(Slabs, SlabIntervals, "slab_intervals", "surfaces' intervals between two lines taken as slabs", "intervals", Sum) \
  X(Slabs, RowIntervals, "row_intervals", "surfaces' intervals taken row by row", "intervals", Sum)                 \
  X(Slabs, EventIntervals, "event_intervals", "of those, with an event of the surface's Y scan (no line walked)", "intervals", Sum) \
  X(Slabs, SlabLines, "slab_lines", "surface lines whose chains were walked or advanced", "lines", Sum)            \
  X(Slabs, SlabTriangles, "slab_triangles", "slab triangles made", "triangles", Sum)                               \
  X(BackEnd, Triangles, "triangles", "triangles (n)", "triangles", Sum)                                            \
  X(BackEnd, TrianglesSetUp, "triangles_set_up", "triangles set up", "triangles", Sum)                              \
  X(BackEnd, MaxActiveTriangles, "max_active", "most triangles active on one sample row (m)", "triangles", Max)     \
  X(BackEnd, SamplesTested, "samples_tested", "samples tested", "samples", Sum)                                    \
  X(BackEnd, SamplesCovered, "samples_covered", "samples covered", "samples", Sum)                                  \
  X(BackEnd, ShadingCalls, "shading_calls", "shading calls", "calls", Sum)                                         \
  X(BackEnd, ExtraShadingCalls, "extra_shading_calls", "adaptive-stochastic extra shading calls", "calls", Sum)      \
  X(BackEnd, SuperSampledPixels, "super_sampled_pixels", "pixels super-sampled", "pixels", Sum)

enum class Counter : std::uint8_t {
#define PATCHSCAN_COUNTER_ENUM(group, name, key, description, unit, merge) name,
  PATCHSCAN_COUNTERS(PATCHSCAN_COUNTER_ENUM)
#undef PATCHSCAN_COUNTER_ENUM
};

struct CounterInfo {
  CounterGroup group;
  Counter counter;
  std::string_view key;          // the --stats-json key
  std::string_view description;  // what it counts, for --stats
  std::string_view unit;         // what one count is
  CounterMerge merge;
};

inline constexpr auto kCounterTable = std::to_array<CounterInfo>({
#define PATCHSCAN_COUNTER_INFO(group, name, key, description, unit, merge) \
  {CounterGroup::group, Counter::name, key, description, unit, CounterMerge::merge},
    PATCHSCAN_COUNTERS(PATCHSCAN_COUNTER_INFO)
#undef PATCHSCAN_COUNTER_INFO
});
inline constexpr std::size_t kNumCounters = kCounterTable.size();

// Figures derived from the counters: (a + b) / c, reported beside them (0 when c is 0).
struct CounterRatio {
  CounterGroup group;
  std::string_view key, description;
  Counter a, b, per;  // b == a: a alone
};
inline constexpr auto kCounterRatios = std::to_array<CounterRatio>({
    // Paper 001 §3.5: ~2.5 without extrapolation, under 1 with.
    {CounterGroup::YScan, "newton_iterations_per_tracker_row", "Newton iterations per tracker per row",
     Counter::EdgeNewtonIterations, Counter::SilhouetteNewtonIterations, Counter::TrackerRows},
    {CounterGroup::XScan, "xscan_newton_iterations_per_call", "Newton iterations per sample solve",
     Counter::XscanNewtonIterations, Counter::XscanNewtonIterations, Counter::XscanNewtonCalls},
    {CounterGroup::Theta, "theta_iterations_per_tracker", "Newton iterations per θ tracker",
     Counter::ThetaTrackerIterations, Counter::ThetaTrackerIterations, Counter::ThetaTrackers},
    {CounterGroup::Theta, "theta_iterations_per_turn_tracker", "Newton iterations per turn tracker",
     Counter::ThetaTurnIterations, Counter::ThetaTurnIterations, Counter::ThetaTurnTrackers},
    {CounterGroup::Theta, "theta_iterations_per_tilt_tracker", "Newton iterations per tilt tracker",
     Counter::ThetaTiltIterations, Counter::ThetaTiltIterations, Counter::ThetaTiltTrackers},
});

// One set of counts, one per counter of the table; zero to begin with. Never allocates.
class Counters {
 public:
  std::int64_t& operator[](Counter c) { return n_[static_cast<std::size_t>(c)]; }
  std::int64_t operator[](Counter c) const { return n_[static_cast<std::size_t>(c)]; }
  // Raises a Max counter to v if v is larger.
  void Raise(Counter c, std::int64_t v) { (*this)[c] = std::max((*this)[c], v); }
  // Adds another set of counts in: sums, or the larger of Max counters.
  void Merge(const Counters& o) {
    for (const CounterInfo& info : kCounterTable) {
      std::int64_t& n = (*this)[info.counter];
      n = info.merge == CounterMerge::Max ? std::max(n, o[info.counter]) : n + o[info.counter];
    }
  }
  double Ratio(const CounterRatio& r) const {
    const auto per = (*this)[r.per];
    if (per == 0) return 0.0;
    const auto a = (*this)[r.a], b = r.b == r.a ? 0 : (*this)[r.b];
    return static_cast<double>(a + b) / static_cast<double>(per);
  }

 private:
  std::array<std::int64_t, kNumCounters> n_{};
};

}  // namespace patchscan
