// patchscan-mpi: Molnar's object partition and z-composition (paper 002) across MPI
// processes. Every process reads the scene; its surfaces, in scan order, are dealt out to
// the processes as PartitionSurfaces deals them to workers; each process scans its share
// row by row on its own threads (a PartitionedScan of that share) and sends each row to
// process 0, whose back end takes every process's rows merged in the scan order of all
// surfaces: the same fragments in the same order as one process scanning everything, so
// the image is the same, bit for bit, for any number of processes.
//
// The protocol, between process 0 and each other process (messages from one process to
// another arrive in the order sent):
//   0 -> k  kGo       a frame begins: its number, scan options and rows
//   k -> 0  kRow      a row's fragments and triangles, each with its surface's scan rank
//   k -> 0  kVote     at a θ slab interval: whether k's surfaces allow a slab
//   0 -> k  kVerdict  every process's vote, taken together
//   0 -> k  kCredit   rows 0 has merged: k stays at most kRowsInFlight rows ahead
//   0 -> k  kStop     stop the frame now (an error, an interruption)
//   k -> 0  kError    k failed (the reason); then kDone
//   k -> 0  kDone     k's frame is over: its counts, seconds, traffic and memory
//   0 -> k  kFinish   the program is over: the exit code every process returns
// Process 0 drains every process's messages to its kDone before it returns from a frame,
// so nothing waits forever, whatever fails where.
#pragma once

#include <mpi.h>

#include <memory>
#include <string>

#include "cli/render.h"

namespace patchscan::mpi {

// Rows a process may send ahead of what process 0 has merged: memory on process 0 stays
// O(width x processes x kRowsInFlight).
constexpr int kRowsInFlight = 32;

// Process 0's front end: its own share's scan and the other processes' rows, merged.
// Made by RenderOptions::makeDirectScan for each frame of a direct render.
std::unique_ptr<DirectScanSource> MakeSharedScan(MPI_Comm comm, int frame, const Scene& scene, const Camera& camera,
                                                 const ExactScanOptions& options, int threads);

// The other processes: scan the frames process 0 asks for, until it says the program is
// over; returns the exit code it sends. `options` is the same command line process 0 has.
int ServeFrames(MPI_Comm comm, const cli::RenderOptions& options);

// Process 0, when the program is over: every other process returns `code`.
void FinishAll(MPI_Comm comm, int code);

}  // namespace patchscan::mpi
