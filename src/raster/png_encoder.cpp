#include "raster/png_encoder.h"
#include "raster/work_arena.h"

#include "raster/srgb.h"

#include <oneapi/tbb/info.h>
#include <oneapi/tbb/task_arena.h>
#include <zlib.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <condition_variable>
#include <cstdlib>
#include <cstring>
#include <mutex>
#include <vector>

namespace patchscan::raster {
namespace {

constexpr int kBytesPerPixel = 4;        // RGBA, 8 bits a sample
constexpr std::size_t kWindow = 32768;   // deflate's window: how far back a match may reach

void PutBigEndian(std::uint8_t* p, std::uint32_t v) {
  p[0] = static_cast<std::uint8_t>(v >> 24);
  p[1] = static_cast<std::uint8_t>(v >> 16);
  p[2] = static_cast<std::uint8_t>(v >> 8);
  p[3] = static_cast<std::uint8_t>(v);
}

// A chunk's CRC covers its type and data (ISO/IEC 15948 §5.3).
std::uint32_t ChunkCrc(const char* type, const std::uint8_t* data, std::size_t size) {
  const uLong crc = crc32(0L, reinterpret_cast<const Bytef*>(type), 4);
  return static_cast<std::uint32_t>(size ? crc32_z(crc, data, size) : crc);  // zlib: null data restarts
}

// Byte i of `row` filtered by filter `Type` (ISO/IEC 15948 §9.2), `prev` the row above;
// the bytes left of the row are zeros (Left: i >= bpp, there are bytes to the left).
template <int Type, bool Left>
std::uint8_t Filtered(const std::uint8_t* row, const std::uint8_t* prev, std::size_t i) {
  constexpr std::size_t bpp = kBytesPerPixel;
  const int x = row[i], a = Left ? row[i - bpp] : 0, b = prev[i], c = Left ? prev[i - bpp] : 0;
  if constexpr (Type == 0) {
    return static_cast<std::uint8_t>(x);
  } else if constexpr (Type == 1) {  // Sub
    return static_cast<std::uint8_t>(x - a);
  } else if constexpr (Type == 2) {  // Up
    return static_cast<std::uint8_t>(x - b);
  } else if constexpr (Type == 3) {  // Average
    return static_cast<std::uint8_t>(x - ((a + b) >> 1));
  } else {  // Paeth (§9.4): the one of left, above, upper left nearest to left + above - upper left
    const int pa = std::abs(b - c), pb = std::abs(a - c), pc = std::abs(a + b - 2 * c);
    return static_cast<std::uint8_t>(x - ((pa <= pb && pa <= pc) ? a : (pb <= pc ? b : c)));
  }
}

// Calls f(i, filtered byte i) for filter Type across a row of n bytes: the first pixel's
// bytes, then the rest in a loop of its own, without branches (for the compiler to vectorise).
template <int Type, class F>
void ForEachFiltered(const std::uint8_t* row, const std::uint8_t* prev, std::size_t n, F&& f) {
  const std::size_t head = std::min(n, static_cast<std::size_t>(kBytesPerPixel));
  for (std::size_t i = 0; i < head; ++i) f(i, Filtered<Type, false>(row, prev, i));
  for (std::size_t i = head; i < n; ++i) f(i, Filtered<Type, true>(row, prev, i));
}

// Filter Type's bytes of the row into f[0..n); returns the sum of their magnitudes, read as
// signed.
template <int Type>
std::uint32_t FilterAndCost(const std::uint8_t* row, const std::uint8_t* prev, std::size_t n, std::uint8_t* f) {
  std::uint32_t s = 0;  // at most 128 a byte: no overflow below 2^24 bytes a row
  ForEachFiltered<Type>(row, prev, n, [&s, f](std::size_t i, std::uint8_t b) {
    f[i] = b;
    const int v = static_cast<std::int8_t>(b);
    s += static_cast<std::uint32_t>(v < 0 ? -v : v);
  });
  return s;
}

// Filters `row` (with `prev` the row above, zeros for the first) into out[0] = filter type
// and out[1..n]: of the five filters, the one whose bytes, read as signed, have the least sum
// of magnitudes (the heuristic of the PNG specification's §12.8, libpng's default), ties to
// the lowest type. Each filter is one loop of its own, its bytes and their cost at once, so
// that the compiler vectorises it; the trials stop at a filter of cost 0 (a row of
// background), which no other can beat.
void FilterRow(const std::uint8_t* row, const std::uint8_t* prev, std::size_t n, std::uint8_t* out,
               std::array<std::vector<std::uint8_t>, 5>& trial) {
  constexpr std::array<std::uint32_t (*)(const std::uint8_t*, const std::uint8_t*, std::size_t, std::uint8_t*), 5>
      filters = {FilterAndCost<0>, FilterAndCost<1>, FilterAndCost<2>, FilterAndCost<3>, FilterAndCost<4>};
  int best = 0;
  std::uint32_t bestCost = 0;
  for (int type = 0; type < 5; ++type) {
    const std::uint32_t c = filters[static_cast<std::size_t>(type)](row, prev, n, trial[static_cast<std::size_t>(type)].data());
    if (type == 0 || c < bestCost) best = type, bestCost = c;
    if (bestCost == 0) break;
  }
  out[0] = static_cast<std::uint8_t>(best);
  std::memcpy(out + 1, trial[static_cast<std::size_t>(best)].data(), n);
}

}  // namespace

// One band of rows on its way to the file: the raw rows (with the rows before it that its
// dictionary is filtered from), then its IDAT chunk, whole.
struct Band {
  int firstRow = 0, rows = 0;       // the band's rows in the image
  int contextRows = 0;              // raw rows before firstRow kept in `raw`
  bool last = false;                // the image's last band: ends the zlib stream
  std::vector<std::uint8_t> raw;    // (contextRows + rows) rows of width * 4 bytes
  std::vector<std::uint8_t> filtered;
  std::vector<std::uint8_t> chunk;  // length, "IDAT", data, CRC
  std::array<std::vector<std::uint8_t>, 5> trial;
  uLong adler = 1, length = 0;      // Adler-32 and size of the band's filtered data
  z_stream zs{};
  bool zsReady = false;
  bool pending = false;             // submitted and not yet written
  bool claimed = true;              // a thread has taken up its deflate (or it is not submitted)
  bool done = false;                // deflated
};

struct PngEncoder::Impl {
  std::FILE* file = nullptr;
  int width = 0, height = 0, level = 6, threads = 1;
  bool runLength = false;
  std::size_t rowBytes = 0;         // raw bytes a row
  int rowsPerBand = 1, dictRows = 0;
  std::vector<Band> bands;          // a ring: band k in bands[k % size]
  std::vector<std::uint8_t> history;  // the last dictRows + 1 raw rows, a ring by row
  std::vector<std::uint8_t> zeroRow;  // the row above the first
  int nextRow = 0, filling = -1, nextBand = 0, written = 0;
  int tasks = 0;                    // deflate tasks enqueued and not yet finished
  uLong adler = 1;
  bool failed = false, finished = false;
  std::shared_ptr<tbb::task_arena> arena;
  std::mutex m;
  std::condition_variable cv;

  Band& Slot(int k) { return bands[static_cast<std::size_t>(k) % bands.size()]; }
  void Write(const void* data, std::size_t size) {
    if (!failed && std::fwrite(data, 1, size, file) != size) failed = true;
  }
  void WriteChunk(const char* type, const std::uint8_t* data, std::size_t size) {
    std::uint8_t head[8], tail[4];
    PutBigEndian(head, static_cast<std::uint32_t>(size));
    std::memcpy(head + 4, type, 4);
    PutBigEndian(tail, ChunkCrc(type, data, size));
    Write(head, 8);
    if (size) Write(data, size);
    Write(tail, 4);
  }
  void Deflate(Band& b);
  void Submit(Band& b);
  void WriteDone(bool wait);
  void BeginBand();
};

// Filters the band and deflates it into its chunk: raw deflate, primed with the filtered
// bytes before it, ended by a sync flush (or, last, by the end of the stream).
void PngEncoder::Impl::Deflate(Band& b) {
  const std::size_t fr = rowBytes + 1;
  const int filterFrom = std::max(0, b.firstRow - dictRows);  // first row filtered here
  const int nFiltered = b.firstRow + b.rows - filterFrom;
  b.filtered.resize(static_cast<std::size_t>(nFiltered) * fr);
  for (auto& t : b.trial) t.resize(rowBytes);
  const int rawFrom = b.firstRow - b.contextRows;
  for (int r = filterFrom; r < b.firstRow + b.rows; ++r) {
    const std::uint8_t* row = b.raw.data() + static_cast<std::size_t>(r - rawFrom) * rowBytes;
    // Above the image's first row: a row of zeros.
    const std::uint8_t* prev = r > rawFrom ? row - rowBytes : zeroRow.data();
    FilterRow(row, prev, rowBytes, b.filtered.data() + static_cast<std::size_t>(r - filterFrom) * fr, b.trial);
  }
  const std::size_t dictBytes = static_cast<std::size_t>(b.firstRow - filterFrom) * fr;
  const std::uint8_t* data = b.filtered.data() + dictBytes;
  const std::size_t size = static_cast<std::size_t>(b.rows) * fr;

  if (!b.zsReady) {
    if (deflateInit2(&b.zs, level, Z_DEFLATED, -15, 8, runLength ? Z_RLE : Z_DEFAULT_STRATEGY) != Z_OK)
      std::abort();
    b.zsReady = true;
  } else {
    deflateReset(&b.zs);
  }
  if (dictBytes && !runLength) {  // a run reaches back one byte, not into the dictionary
    const std::size_t n = std::min(dictBytes, kWindow);
    deflateSetDictionary(&b.zs, b.filtered.data() + dictBytes - n, static_cast<uInt>(n));
  }
  const bool first = b.firstRow == 0;
  const std::size_t header = 8 + (first ? 2 : 0);
  b.chunk.resize(header + deflateBound(&b.zs, static_cast<uLong>(size)) + 64);
  if (first) {
    // The zlib header (RFC 1950): deflate, 32 KiB window, the level's class (runs: the
    // fastest, as zlib itself says of Z_RLE), no dictionary.
    const int flevel = runLength || level < 2 ? 0 : level < 6 ? 1 : level == 6 ? 2 : 3;
    const unsigned cmf = 0x78, flg0 = static_cast<unsigned>(flevel) << 6;
    const unsigned flg = flg0 + (31 - (cmf * 256 + flg0) % 31) % 31;
    b.chunk[8] = static_cast<std::uint8_t>(cmf);
    b.chunk[9] = static_cast<std::uint8_t>(flg);
  }
  b.zs.next_in = const_cast<Bytef*>(data);
  b.zs.avail_in = static_cast<uInt>(size);
  std::size_t used = header;
  const int flush = b.last ? Z_FINISH : Z_SYNC_FLUSH;
  for (;;) {
    if (b.chunk.size() - used < 64) b.chunk.resize(b.chunk.size() * 2);
    b.zs.next_out = b.chunk.data() + used;
    b.zs.avail_out = static_cast<uInt>(b.chunk.size() - used);
    const int rc = deflate(&b.zs, flush);
    used = b.chunk.size() - b.zs.avail_out;
    if (b.last ? rc == Z_STREAM_END : (rc == Z_OK && b.zs.avail_out > 0 && b.zs.avail_in == 0)) break;
    if (rc != Z_OK && rc != Z_BUF_ERROR) std::abort();
  }
  // Room for the CRC and, last, the stream's Adler-32: WriteDone fills them in.
  b.chunk.resize(used + 4 + (b.last ? 4 : 0));
  std::memcpy(b.chunk.data() + 4, "IDAT", 4);
  b.adler = adler32_z(1L, data, size);
  b.length = static_cast<uLong>(size);
}

// A band is deflated by whichever thread takes it up first: a task on the render's arena,
// or the thread that needs it written (WriteDone), which so never waits for a task that no
// thread is free to run (the rows may come from a task of the arena itself).
void PngEncoder::Impl::Submit(Band& b) {
  b.pending = true;
  b.done = false;
  if (!arena) {
    Deflate(b);
    b.done = true;
    WriteDone(false);
    return;
  }
  {
    std::lock_guard lock(m);
    b.claimed = false;
    ++tasks;
  }
  arena->enqueue([this, &b] {
    // The slot may hold a later band by now, or one taken up already: either way the task
    // deflates what is submitted and unclaimed there.
    bool mine = false;
    {
      std::lock_guard lock(m);
      mine = !b.claimed;
      b.claimed = true;
    }
    if (mine) Deflate(b);
    // Notified under the lock: once the lock is released this task touches nothing of the
    // encoder, which its destructor may then free.
    std::lock_guard lock(m);
    if (mine) b.done = true;
    --tasks;
    cv.notify_all();
  });
  WriteDone(false);
}

// Writes the bands deflated so far, in order; with `wait`, waits for the oldest first.
void PngEncoder::Impl::WriteDone(bool wait) {
  while (written < nextBand) {
    Band& b = Slot(written);
    {
      std::unique_lock lock(m);
      if (!wait && !b.done) return;
      if (!b.claimed) {
        b.claimed = true;
        lock.unlock();
        Deflate(b);
        lock.lock();
        b.done = true;
      }
      cv.wait(lock, [&] { return b.done; });
    }
    adler = written == 0 ? b.adler : adler32_combine(adler, b.adler, static_cast<z_off_t>(b.length));
    const std::size_t dataSize = b.chunk.size() - 12;
    // The stream ends with its Adler-32 (RFC 1950): the bands' combined in order.
    if (b.last) PutBigEndian(b.chunk.data() + 8 + dataSize - 4, static_cast<std::uint32_t>(adler));
    PutBigEndian(b.chunk.data(), static_cast<std::uint32_t>(dataSize));
    PutBigEndian(b.chunk.data() + 8 + dataSize, ChunkCrc("IDAT", b.chunk.data() + 8, dataSize));
    Write(b.chunk.data(), b.chunk.size());
    b.pending = false;
    ++written;
    if (wait) return;
  }
}

// Starts the next band in its slot (waiting for the band there to be written), with the raw
// rows before it that its dictionary is filtered from.
void PngEncoder::Impl::BeginBand() {
  Band& b = Slot(nextBand);
  while (b.pending) WriteDone(true);
  b.firstRow = nextRow;
  b.rows = 0;
  b.last = nextRow + rowsPerBand >= height;
  b.contextRows = std::min(nextRow, dictRows + 1);
  b.raw.resize(static_cast<std::size_t>(b.contextRows + std::min(rowsPerBand, height - nextRow)) * rowBytes);
  const int hist = dictRows + 1;
  for (int i = 0; i < b.contextRows; ++i) {
    const int r = nextRow - b.contextRows + i;
    std::memcpy(b.raw.data() + static_cast<std::size_t>(i) * rowBytes,
                history.data() + static_cast<std::size_t>(r % hist) * rowBytes, rowBytes);
  }
  filling = nextBand;
}

int PngEncoder::RowsPerBand(int width) {
  const std::size_t fr = static_cast<std::size_t>(width) * kBytesPerPixel + 1;
  return static_cast<int>((kBandBytes + fr - 1) / fr);
}

PngEncoder::PngEncoder(std::FILE* file, int width, int height, Options options)
    : impl_(std::make_unique<Impl>()) {
  Impl& s = *impl_;
  s.file = file;
  s.width = width;
  s.height = height;
  s.level = std::clamp(options.level, 0, 9);
  s.runLength = options.runLength;
  // No more bands in flight than the machine has cores to deflate them (the bytes do not
  // depend on it).
  s.threads = std::clamp(options.threads, 1, std::max(1, tbb::info::default_concurrency()));
  s.rowBytes = static_cast<std::size_t>(width) * kBytesPerPixel;
  s.rowsPerBand = RowsPerBand(width);
  s.dictRows = static_cast<int>((kWindow + s.rowBytes) / (s.rowBytes + 1));  // ceil(32 KiB / row)
  s.history.resize(static_cast<std::size_t>(s.dictRows + 1) * s.rowBytes);
  s.zeroRow.assign(s.rowBytes, 0);
  // A band a thread and one more: every thread may deflate while the oldest finished band
  // waits its turn. A band holds about 1 MiB (its filtered rows, zlib's state and its
  // output): twice as many cost the 2048-wide teapot at two threads 4 MB more at its peak.
  s.bands = std::vector<Band>(s.threads > 1 ? static_cast<std::size_t>(s.threads + 1) : 1);
  // More threads than cores would only queue (and oneTBB warns); the bytes do not change.
  if (s.threads > 1 && tbb::info::default_concurrency() > 1) s.arena = WorkArena(s.threads);

  static const std::uint8_t kSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  s.Write(kSignature, 8);
  std::uint8_t ihdr[13];
  PutBigEndian(ihdr, static_cast<std::uint32_t>(width));
  PutBigEndian(ihdr + 4, static_cast<std::uint32_t>(height));
  ihdr[8] = 8;   // bits a sample
  ihdr[9] = 6;   // colour type: RGBA
  ihdr[10] = 0;  // deflate
  ihdr[11] = 0;  // adaptive filtering
  ihdr[12] = 0;  // not interlaced
  s.WriteChunk("IHDR", ihdr, sizeof ihdr);
  // The colour is sRGB-encoded (PNG 1.2 §4.2.2.5: rendering intent 0, perceptual), with the
  // gAMA chunk readers without sRGB support fall back to (1/2.2 as 45455).
  const std::uint8_t intent = 0;
  s.WriteChunk("sRGB", &intent, 1);
  std::uint8_t gamma[4];
  PutBigEndian(gamma, 45455);
  s.WriteChunk("gAMA", gamma, 4);
}

PngEncoder::~PngEncoder() {
  Impl& s = *impl_;
  {
    std::unique_lock lock(s.m);
    s.cv.wait(lock, [&] { return s.tasks == 0; });
  }
  for (Band& b : s.bands)
    if (b.zsReady) deflateEnd(&b.zs);
}

bool PngEncoder::WriteRow(const float* pixels, int stride) {
  Impl& s = *impl_;
  if (s.failed || s.nextRow >= s.height) return false;
  if (s.filling < 0) s.BeginBand();
  Band& b = s.Slot(s.filling);
  std::uint8_t* row = b.raw.data() + static_cast<std::size_t>(b.contextRows + b.rows) * s.rowBytes;
  // Straight alpha, sRGB-encoded colour (the sRGB chunk says so).
  StraightSrgba8Row(pixels, s.width, stride, row);
  std::memcpy(s.history.data() + static_cast<std::size_t>(s.nextRow % (s.dictRows + 1)) * s.rowBytes, row, s.rowBytes);
  ++s.nextRow;
  if (++b.rows == std::min(s.rowsPerBand, s.height - b.firstRow)) {
    s.filling = -1;
    ++s.nextBand;
    s.Submit(b);
  }
  return !s.failed;
}

bool PngEncoder::Finish() {
  Impl& s = *impl_;
  if (s.finished) return !s.failed;
  s.finished = true;
  if (s.nextRow != s.height) return false;
  while (s.written < s.nextBand) s.WriteDone(true);
  s.WriteChunk("IEND", nullptr, 0);
  return !s.failed;
}

}  // namespace patchscan::raster
