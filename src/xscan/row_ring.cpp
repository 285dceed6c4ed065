#include "xscan/row_ring.h"

namespace patchscan {

RowRing::RowRing(int depth, const raster::KeptDepths& kept, int columns)
    : slots_(static_cast<std::size_t>(depth)), okOf_(static_cast<std::size_t>(depth), 1) {
  for (StoredRow& slot : slots_) slot.depth.Reset(kept, columns);
}

RowRing::~RowRing() { Stop(); }

void RowRing::Stop() {
  if (!producer_.joinable()) return;
  {
    std::lock_guard lock(m_);
    cancel_ = true;
  }
  space_.notify_one();
  producer_.join();
}

void RowRing::Start(std::function<void()> produce) {
  producer_ = std::thread([this, produce = std::move(produce)] {
    try {
      produce();
    } catch (...) {
      std::lock_guard lock(m_);
      error_ = std::current_exception();
      ready_.notify_one();
    }
  });
}

bool RowRing::Reserve(int end) {
  std::unique_lock lock(m_);
  const int need = end - Depth();
  if (!cancel_ && consumed_ < need) {
    producerNeeds_ = need;
    space_.wait(lock, [&] { return cancel_ || consumed_ >= producerNeeds_; });
    producerNeeds_ = -1;
  }
  return !cancel_;
}

StoredRow& RowRing::Slot(int j) {
  StoredRow& slot = slots_[static_cast<std::size_t>(j % Depth())];
  slot.Clear();
  return slot;
}

void RowRing::Publish(int j, bool ok) {
  bool wake = false;
  {
    std::lock_guard lock(m_);
    okOf_[static_cast<std::size_t>(j % Depth())] = ok;
    produced_ = j + 1;
    wake = consumerNeeds_ >= 0 && produced_ >= consumerNeeds_;
  }
  if (wake) ready_.notify_one();
}

bool RowRing::Replay(int j, raster::FragmentRow& out) {
  std::unique_lock lock(m_);
  if (produced_ <= j && !error_) {
    consumerNeeds_ = j + 1;
    ready_.wait(lock, [&] { return produced_ > j || error_; });
    consumerNeeds_ = -1;
  }
  if (error_) std::rethrow_exception(error_);
  lock.unlock();
  // The producer leaves slot j alone until row j is replayed.
  const auto k = static_cast<std::size_t>(j % Depth());
  slots_[k].Replay(out);
  const bool ok = okOf_[k] != 0;
  lock.lock();
  consumed_ = j + 1;
  const bool wake = producerNeeds_ >= 0 && consumed_ >= producerNeeds_;
  lock.unlock();
  if (wake) space_.notify_one();
  return ok;
}

}  // namespace patchscan
