#include "raster/async_row_sink.h"

#include <algorithm>
#include <chrono>

namespace patchscan::raster {

AsyncRowSink::AsyncRowSink(RowSink& next, int width)
    : next_(next),
      rowSize_(static_cast<std::size_t>(width) * kChannels),
      slots_(kRowsQueued, std::vector<float>(rowSize_)),
      yOf_(kRowsQueued, 0),
      thread_([this] { Run(); }) {}

AsyncRowSink::~AsyncRowSink() {
  {
    std::lock_guard lock(m_);
    stop_ = true;
  }
  cv_.notify_all();
  thread_.join();
}

bool AsyncRowSink::WriteRow(int y, const float* pixels) {
  std::unique_lock lock(m_);
  cv_.wait(lock, [&] { return failed_ || queued_ - written_ < kRowsQueued; });
  if (failed_) return false;
  const auto k = static_cast<std::size_t>(queued_ % kRowsQueued);
  lock.unlock();
  // The writer leaves slot k alone until it is queued.
  std::copy(pixels, pixels + rowSize_, slots_[k].begin());
  yOf_[k] = y;
  lock.lock();
  ++queued_;
  lock.unlock();
  cv_.notify_all();
  return true;
}

bool AsyncRowSink::Finish() {
  std::unique_lock lock(m_);
  cv_.wait(lock, [&] { return failed_ || written_ == queued_; });
  return !failed_;
}

void AsyncRowSink::Run() {
  for (;;) {
    std::unique_lock lock(m_);
    cv_.wait(lock, [&] { return stop_ || written_ < queued_; });
    if (stop_ || failed_) return;
    const auto k = static_cast<std::size_t>(written_ % kRowsQueued);
    lock.unlock();
    const auto t0 = std::chrono::steady_clock::now();
    const bool ok = next_.WriteRow(yOf_[k], slots_[k].data());
    writerSeconds_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    lock.lock();
    if (!ok) failed_ = true;
    ++written_;
    lock.unlock();
    cv_.notify_all();
  }
}

}  // namespace patchscan::raster
