// ExactScan's state per active surface (xscan/exact_scan.h), shared by its two files:
// exact_scan.cpp (set-up, the active set, exact and θ rows, the trace) and
// exact_scan_slabs.cpp (θ slab intervals).
#pragma once

#include <cmath>
#include <cstddef>
#include <memory>
#include <vector>

#include "xscan/exact_scan.h"

namespace patchscan {

// Rows this far above a surface's first line (SurfaceScan::FirstY) are skipped: LineFor
// moves a line by at most 64 of its 4e-6 px steps.
constexpr double kFirstYSlackPx = 1e-3;

// A surface being scanned: its Y scan, and what its X scan keeps from line to line.
struct ExactScan::Active {
  std::size_t index;
  double yMax = INFINITY;
  // θ and exact rows: above yFirst the surface has no tracker and none is born
  // (SurfaceScan::FirstY), so its rows are not visited; done once the scan has passed all
  // of it (SurfaceScan::Done): then it leaves the active set before its box's bottom. A
  // surface's box (its hull's) is often several times its height on the screen (a
  // subdivision face's ring of cage points): most of its rows have nothing of it.
  double yFirst = -INFINITY;
  bool done = false;
  // Whether the scan has left the surface behind on line y: below its box, or done.
  bool Passed(double y) const { return yMax < y || done; }
  // θ slabs: the surface's intervals so far lay wholly above yFirst (its scan still at its
  // set-up line, nothing of it walked).
  bool idle = false;
  std::unique_ptr<SurfaceScan> scan;
  // Sort-first: the counts of a surface set up apart from the scan's thread, and of its Y
  // scan after (ExactScan::GatherCounts adds them to the scan's); null: the scan's own.
  std::unique_ptr<Counters> own;
  std::size_t nextStationary = 0;  // for the trace: the next stationary point to pass
  // θ slabs: the chains on the interval's top line and on its bottom line (whether a walk
  // there failed or repaired a tracker miss), the trackers on the top line and on each of
  // its sample rows, and when it is taken row by row (byRows) each row's chains. θ rows:
  // the chains of the row before (line, at lineY) and of this row (next).
  ChainSet line, next;
  double lineY = 0.0;
  bool lineBroken = false, nextBroken = false;
  // Whether those lines were walked (an interval taken row by row walks neither), and
  // the trackers on a top line not walked yet.
  bool lineWalked = false, nextWalked = false;
  // Whether the surface's sections keep their shape (Calm) from the line or row before to
  // each sample row of the interval, and from its last row to the bottom line (m + 1
  // steps): a slab wants all, and taken row by row, a row is advanced from the one before
  // unless an event lies between them, as on θ rows. The chains of the last row of an
  // interval taken row by row (at carryY), when they may be advanced to the next
  // interval's top line or first row (carried).
  std::vector<char> stepCalm;
  bool byRows = false, carried = false;
  // θ slabs: a surface that was a slab through the interval before is advanced straight
  // from the top line to the bottom one (jumped), the scan's state on the top line saved
  // to come back to for its rows where the interval turns out not to be a slab.
  bool slabBefore = false, jumped = false;
  SurfaceScan::State topState;
  ChainSet carry;
  double carryY = 0.0;
  // θ rows: the vertices of the surface's chains that are solved by Newton (not their ends
  // and silhouettes: the Y scan's trackers) and the samples they covered, summed over its
  // rows so far, and whether it has gone over to the exact X scan for good (where its
  // chains hold more such vertices per sample than kThetaVerticesPerSampleMax).
  long thetaVertices = 0, thetaSamples = 0;
  bool exactX = false;
  // Sort-first: the silhouettes the X scan found untracked on a batch's last row, to take up.
  std::vector<Vec2> adopt;
  // θ: whether the surface's object-to-world map is the identity (ThetaFrame::worldIsObject).
  bool worldIsObject = false;
  RowTrackers topTrackers;
  std::vector<RowTrackers> rowTrackers;
  std::vector<ChainSet> rows;
  std::vector<ChainPair> pairs;
  std::vector<ThetaVertex> ordered;
  // θ slabs: the chains of line and next with vertices added along their links' cubics
  // (RefineChains), which the slabs are zipped from, and whether they are those of the
  // chains line and next hold now.
  ChainSet lineFine, nextFine;
  bool lineRefined = false, nextRefined = false;
};

}  // namespace patchscan
