// The threads of a render: one oneTBB arena that every parallel stage shares (the
// partition's scanning workers, shading, PNG deflate), so that a thread done with one
// stage's tasks takes up another's instead of spinning idle in an arena of its own.
#pragma once

#include <oneapi/tbb/task_arena.h>
#include <oneapi/tbb/task_group.h>

#include <memory>
#include <vector>

namespace patchscan::raster {

// The arena for renders on `threads` threads (at least 2; capped at the machine's cores),
// shared while any holder keeps it. Two threads outside it may enter at once (the caller
// and a scan-ahead). oneTBB keeps a worker a thread, or a worker less where the caller
// takes tasks itself (`callerWorks`: it waits on them rather than handing rows over), so
// that no more threads run than asked for.
std::shared_ptr<tbb::task_arena> WorkArena(int threads, bool callerWorks = false);

// Cancels the groups' tasks and waits until none runs, swallowing what they throw: on the
// way out of a loop that failed, so that no task outlives the rows it works on.
void CancelAndWait(tbb::task_arena& arena, std::vector<tbb::task_group>& groups) noexcept;

}  // namespace patchscan::raster
