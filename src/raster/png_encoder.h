// A PNG encoder (ISO/IEC 15948) for the back end's rows that deflates on several threads and
// still writes the same bytes for any number of them.
//
// The image data of a PNG is one zlib stream, which a single deflate would make serial. The
// rows are cut into bands of a fixed number of rows (a function of the width alone); each
// band is filtered and deflated on its own as a run of deflate blocks that ends on a byte
// boundary (a sync flush), primed with the 32 KiB of filtered data before it as its
// dictionary, so matches still reach back across the cut and the file is as small as one
// deflate would make it, to a few bytes a band. Each band becomes one IDAT chunk; the
// stream's Adler-32 is combined from the bands' in order. Bands are deflated as oneTBB tasks
// and written in order; at most a few are in flight, so memory stays O(width).
//
// Pixels: 8-bit RGBA with straight (unassociated) alpha, as PNG prescribes: each sample is
// quantised by rounding, then the colour is divided by the alpha in integers.
#pragma once

#include <cstdint>
#include <cstdio>
#include <memory>
#include <string>

namespace patchscan::raster {

class PngEncoder {
 public:
  struct Options {
    int level = 6;           // zlib's compression level, 0 (stored) to 9
    int threads = 1;         // threads deflating bands; the bytes do not depend on it
    bool runLength = false;  // zlib's Z_RLE strategy: matches only within runs of a byte (level ignored)
  };

  // Writes the signature and header to `file`, which the caller owns and closes.
  PngEncoder(std::FILE* file, int width, int height, Options options);
  ~PngEncoder();
  PngEncoder(const PngEncoder&) = delete;
  PngEncoder& operator=(const PngEncoder&) = delete;

  // The next row, top to bottom: `pixels` holds width pixels of premultiplied RGBA floats,
  // `stride` floats apart. False once writing has failed.
  bool WriteRow(const float* pixels, int stride);
  // After the last row: waits for every band, writes the stream's end and IEND. False if
  // any write failed or rows are missing.
  bool Finish();

  // Rows per band for a given width: whole rows making at least kBandBytes of filtered data.
  static int RowsPerBand(int width);
  static constexpr int kBandBytes = 512 * 1024;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace patchscan::raster
