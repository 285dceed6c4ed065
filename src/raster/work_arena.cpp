#include "raster/work_arena.h"

#include <oneapi/tbb/global_control.h>
#include <oneapi/tbb/info.h>
#include <oneapi/tbb/task_arena.h>

#include <algorithm>
#include <mutex>

namespace patchscan::raster {

namespace {

// oneTBB keeps `threads` workers (one more than its default of a worker less than the
// cores: the caller's thread is busy handing rows over in order), and the arena a slot for
// each of them and for the two threads from outside.
constexpr int kOutsideThreads = 2;
struct Shared {
  explicit Shared(int threads)
      : control(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(threads) + 1),
        arena(threads + kOutsideThreads, kOutsideThreads) {}
  tbb::global_control control;
  tbb::task_arena arena;
};

}  // namespace

std::shared_ptr<tbb::task_arena> WorkArena(int threads) {
  static std::mutex m;
  static std::weak_ptr<Shared> held;
  static int heldThreads = 0;
  threads = std::clamp(threads, 2, std::max(2, tbb::info::default_concurrency()));
  std::lock_guard lock(m);
  std::shared_ptr<Shared> s = heldThreads == threads ? held.lock() : nullptr;
  if (!s) {
    s = std::make_shared<Shared>(threads);
    held = s;
    heldThreads = threads;
  }
  return {s, &s->arena};
}

}  // namespace patchscan::raster
