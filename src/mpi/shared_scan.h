// patchscan-mpi: Molnar's object partition and z-composition (1990) across MPI
// processes, composited by direct send (as IceT does it). Every process reads the scene;
// its surfaces, in scan order, are dealt out to the processes as PartitionSurfaces deals
// them to workers, and each process scans its share row by row on its own threads (a
// PartitionedScan of that share). The pixel rows are dealt out too, in bands of kBandRows
// round robin: each process renders the bands it owns, and every process sends each owner
// what its surfaces put on the owner's sample rows (the fragments, θ's chords whole, and
// the triangles that reach them, carried to the owner's next row when handed over on
// another's). An owner merges the processes' rows in the scan order of all surfaces
// (triangles by the row they were handed over on, then that order): the same fragments,
// chords and triangles in the same order as one process scanning everything, so every
// pixel is the same, bit for bit, for any number of processes. Process 0 writes the
// image, taking each band's rows from its owner as they come: no process holds a frame.
//
// Messages (between two processes they arrive in the order sent):
//   0 -> k  kGo      a frame begins: its number, scan options, rows
//   j -> k  kRow     what j's surfaces put on one of k's sample rows
//   k -> 0  kPixels  one of k's finished pixel rows
//   k -> 0  kDone    k's frame is over: whether it failed (why), its counts, seconds,
//                    traffic and memory
//   0 -> k  kFinish  the program is over: the exit code every process returns
// A process that fails (or is interrupted) goes on with the frame's messages, sending
// empty rows, so that no process waits forever; process 0 then fails the frame: no image,
// the same exit code on every process.
#pragma once

#include <mpi.h>

#include <memory>
#include <string>

#include "mpi/wire.h"
#include "render/options.h"
#include "render/shared_rows.h"

namespace patchscan::mpi {

// Process 0's front end for a frame of a direct render (RenderOptions::shareRows): its
// share's scan, the rows it owns merged from every process, the others' finished rows
// brought in to the image (SharedRows::AssembleRows).
std::unique_ptr<render::SharedRows> MakeSharedScan(MPI_Comm comm, const render::RenderOptions& options, const Scene& scene,
                                                 const Camera& camera, const ExactScanOptions& scanOptions, int aa,
                                                 int threads);

// The other processes: scan and render their parts of the frames process 0 asks for, until
// it says the program is over; returns the exit code it sends. `options` is the command
// line process 0 has.
int ServeFrames(MPI_Comm comm, const render::RenderOptions& options);

// Process 0, when the program is over: every other process returns `code`.
void FinishAll(MPI_Comm comm, int code);

}  // namespace patchscan::mpi
