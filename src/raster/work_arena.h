// The threads of a render: one oneTBB arena that every parallel stage shares (the
// partition's scanning workers, shading, PNG deflate), so that a thread done with one
// stage's tasks takes up another's instead of spinning idle in an arena of its own.
#pragma once

#include <oneapi/tbb/task_arena.h>

#include <memory>

namespace patchscan::raster {

// The arena for renders on `threads` threads (at least 2; capped at the machine's cores),
// shared while any holder keeps it. Two threads outside it may enter at once (the caller
// and a scan-ahead); oneTBB keeps a worker a thread.
std::shared_ptr<tbb::task_arena> WorkArena(int threads);

}  // namespace patchscan::raster
