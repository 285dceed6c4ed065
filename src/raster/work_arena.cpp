#include "raster/work_arena.h"

#include <oneapi/tbb/global_control.h>
#include <oneapi/tbb/info.h>
#include <oneapi/tbb/task_arena.h>

#include <algorithm>
#include <mutex>

namespace patchscan::raster {

namespace {

// oneTBB keeps `threads` workers (one more than its default of a worker less than the
// cores: the caller's thread is busy handing rows over in order); the arena asks for as
// many, or for `threads` - 1 where the caller works, and keeps a slot for each of them and
// for the two threads from outside.
constexpr int kOutsideThreads = 2;
struct Shared {
  Shared(int threads, bool callerWorks)
      : control(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(threads) + 1),
        arena(threads - (callerWorks ? 1 : 0) + kOutsideThreads, kOutsideThreads) {}
  tbb::global_control control;
  tbb::task_arena arena;
};

}  // namespace

std::shared_ptr<tbb::task_arena> WorkArena(int threads, bool callerWorks) {
  static std::mutex m;
  static std::weak_ptr<Shared> held;
  static int heldThreads = 0;
  static bool heldCallerWorks = false;
  threads = std::clamp(threads, 2, std::max(2, tbb::info::default_concurrency()));
  std::lock_guard lock(m);
  std::shared_ptr<Shared> s = heldThreads == threads && heldCallerWorks == callerWorks ? held.lock() : nullptr;
  if (!s) {
    s = std::make_shared<Shared>(threads, callerWorks);
    held = s;
    heldThreads = threads;
    heldCallerWorks = callerWorks;
  }
  return {s, &s->arena};
}

void CancelAndWait(tbb::task_arena& arena, std::vector<tbb::task_group>& groups) noexcept {
  for (auto& g : groups) {
    g.cancel();
    try {
      arena.execute([&] { g.wait(); });
    } catch (...) {
    }
  }
}

}  // namespace patchscan::raster
