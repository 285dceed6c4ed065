// Finished rows handed to the next sink (the image writer) on a thread of its own, in order,
// so that encoding and writing the image overlap the rendering of the rows below. Rows wait
// in a ring of kRowsQueued rows: memory stays O(width).
#pragma once

#include <condition_variable>
#include <cstddef>
#include <mutex>
#include <thread>
#include <vector>

#include "raster/scanline_renderer.h"

namespace patchscan::raster {

class AsyncRowSink final : public RowSink {
 public:
  // Rows at most this far ahead of the writer: enough to ride out an encoder's bursts.
  static constexpr int kRowsQueued = 16;

  // `next` receives every row, in order, on the writer thread; it must outlive this sink.
  AsyncRowSink(RowSink& next, int width);
  // Stops the writer (rows still queued are dropped) and joins it.
  ~AsyncRowSink() override;

  // Queues a copy of the row; false once the next sink has refused a row.
  bool WriteRow(int y, const float* pixels) override;
  // Waits until every queued row is written; false if the next sink refused one.
  bool Finish();
  // Seconds the writer thread spent in the next sink.
  double WriterSeconds() const { return writerSeconds_; }

 private:
  void Run();

  RowSink& next_;
  std::size_t rowSize_;
  std::vector<std::vector<float>> slots_;
  std::vector<int> yOf_;
  std::mutex m_;
  std::condition_variable cv_;
  long queued_ = 0, written_ = 0;
  bool failed_ = false, stop_ = false;
  double writerSeconds_ = 0.0;
  std::thread thread_;
};

}  // namespace patchscan::raster
