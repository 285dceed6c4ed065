// The banded, threaded PNG encoder, decoded by OpenImageIO (libpng): the straight sRGB
// colour of its input to one code and its alpha exactly, every chunk's CRC and the
// stream's Adler-32 right, the same bytes for any number of threads, and a file about as
// small as libpng's single deflate of the same pixels.
#include <gtest/gtest.h>
#include <zlib.h>

#include <OpenImageIO/imageio.h>
#include <oneapi/tbb/global_control.h>
#include <oneapi/tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "raster/png_encoder.h"

namespace patchscan::raster {
namespace {

constexpr int kStride = 11;  // the back end's channels a pixel (only the first four are written)

// Premultiplied RGBA rows with what a render has: empty background, opaque shading, partly
// covered edge pixels, and a band of noise that deflate cannot shrink.
std::vector<float> TestImage(int width, int height, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  std::vector<float> px(static_cast<std::size_t>(width) * height * kStride, 0.0f);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      float* p = &px[(static_cast<std::size_t>(y) * width + x) * kStride];
      const float xf = static_cast<float>(x), yf = static_cast<float>(y);
      const float wf = static_cast<float>(width), hf = static_cast<float>(height);
      const float dx = (xf - 0.5f * wf) / (0.4f * wf + 1), dy = (yf - 0.5f * hf) / (0.4f * hf + 1);
      const float r2 = dx * dx + dy * dy;
      float a = r2 < 0.9f ? 1.0f : r2 < 1.0f ? (1.0f - r2) * 10.0f : 0.0f;  // a disk, soft rim
      if (y % 17 == 3) a = u(rng);                                           // noisy rows
      const float shade = 0.2f + 0.7f * (1.0f - r2) * (1.0f - r2);
      p[0] = a * shade;
      p[1] = a * (0.3f + 0.5f * xf / wf);
      p[2] = a * (y % 17 == 3 ? u(rng) : 0.5f);
      p[3] = a;
    }
  return px;
}

std::vector<unsigned char> ReadFile(const std::string& path) {
  std::FILE* f = std::fopen(path.c_str(), "rb");
  std::vector<unsigned char> bytes;
  if (!f) return bytes;
  unsigned char buf[65536];
  for (std::size_t n; (n = std::fread(buf, 1, sizeof buf, f)) > 0;) bytes.insert(bytes.end(), buf, buf + n);
  std::fclose(f);
  return bytes;
}

std::string Encode(const std::vector<float>& px, int width, int height, int threads, const std::string& path,
                   bool runLength = false) {
  std::FILE* f = std::fopen(path.c_str(), "wb");
  EXPECT_NE(f, nullptr);
  {
    PngEncoder enc(f, width, height, PngEncoder::Options{6, threads, runLength});
    for (int y = 0; y < height; ++y)
      EXPECT_TRUE(enc.WriteRow(&px[static_cast<std::size_t>(y) * width * kStride], kStride));
    EXPECT_TRUE(enc.Finish());
  }
  std::fclose(f);
  return path;
}

// Straight 8-bit RGBA bytes written by OpenImageIO's PNG writer (libpng) as they are.
void EncodeWithOiio(const std::vector<unsigned char>& bytes, int width, int height, const std::string& path) {
  auto out = OIIO::ImageOutput::create(path);
  ASSERT_TRUE(out);
  OIIO::ImageSpec spec(width, height, 4, OIIO::TypeDesc::UINT8);
  spec.alpha_channel = 3;
  spec.attribute("oiio:UnassociatedAlpha", 1);
  ASSERT_TRUE(out->open(path, spec));
  ASSERT_TRUE(out->write_image(OIIO::TypeDesc::UINT8, bytes.data()));
  ASSERT_TRUE(out->close());
}

// What the file must hold, computed here from the IEC 61966-2-1 formula: alpha rounded,
// the colour divided by alpha and sRGB-encoded (0 where alpha rounds to 0).
std::vector<unsigned char> ExpectedBytes(const std::vector<float>& px, int width, int height) {
  std::vector<unsigned char> out(static_cast<std::size_t>(width) * height * 4);
  for (std::size_t k = 0; k < static_cast<std::size_t>(width) * height; ++k) {
    const float* p = &px[k * kStride];
    const auto a = static_cast<unsigned char>(std::clamp(p[3], 0.0f, 1.0f) * 255.0f + 0.5f);
    out[k * 4 + 3] = a;
    for (int c = 0; c < 3; ++c) {
      const double v = a == 0 ? 0.0 : std::clamp(static_cast<double>(p[c]) / std::clamp(p[3], 0.0f, 1.0f), 0.0, 1.0);
      const double e = v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1.0 / 2.4) - 0.055;
      out[k * 4 + static_cast<std::size_t>(c)] = static_cast<unsigned char>(std::lround(255.0 * e));
    }
  }
  return out;
}

// The largest difference between two byte images.
int MaxByteDifference(const std::vector<unsigned char>& a, const std::vector<unsigned char>& b) {
  int worst = a.size() == b.size() ? 0 : 256;
  for (std::size_t k = 0; k < std::min(a.size(), b.size()); ++k) worst = std::max(worst, std::abs(a[k] - b[k]));
  return worst;
}

std::vector<unsigned char> Decode(const std::string& path, int width, int height) {
  // Straight alpha as stored: no premultiplication on the way in, so the bytes compare.
  OIIO::ImageSpec config;
  config.attribute("oiio:UnassociatedAlpha", 1);
  auto in = OIIO::ImageInput::open(path, &config);
  EXPECT_TRUE(in);
  std::vector<unsigned char> px(static_cast<std::size_t>(width) * height * 4);
  if (!in) return px;
  EXPECT_EQ(in->spec().width, width);
  EXPECT_EQ(in->spec().height, height);
  EXPECT_EQ(in->spec().nchannels, 4);
  EXPECT_TRUE(in->read_image(0, 0, 0, 4, OIIO::TypeDesc::UINT8, px.data()));
  return px;
}

// Walks the chunks: every CRC right, IHDR first and IEND last; inflates the IDATs, which
// checks the stream's Adler-32; returns the filtered bytes (empty on any fault).
std::vector<unsigned char> CheckChunks(const std::vector<unsigned char>& png, int* idats) {
  static const unsigned char kSig[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  if (png.size() < 8 || std::memcmp(png.data(), kSig, 8) != 0) return {};
  std::vector<unsigned char> stream;
  std::string first, last;
  *idats = 0;
  for (std::size_t i = 8; i + 12 <= png.size();) {
    const std::uint32_t n = (png[i] << 24) | (png[i + 1] << 16) | (png[i + 2] << 8) | png[i + 3];
    if (i + 12 + n > png.size()) return {};
    const std::string type(reinterpret_cast<const char*>(&png[i + 4]), 4);
    const std::uint32_t crc = (png[i + 8 + n] << 24) | (png[i + 9 + n] << 16) | (png[i + 10 + n] << 8) | png[i + 11 + n];
    if (crc32(0L, &png[i + 4], 4 + n) != crc) return {};
    if (first.empty()) first = type;
    last = type;
    if (type == "IDAT") stream.insert(stream.end(), &png[i + 8], &png[i + 8] + n), ++*idats;
    i += 12 + n;
  }
  if (first != "IHDR" || last != "IEND") return {};
  std::vector<unsigned char> raw(1 << 26);
  uLongf size = raw.size();
  if (uncompress(raw.data(), &size, stream.data(), stream.size()) != Z_OK) return {};
  raw.resize(size);
  return raw;
}

class PngEncoderTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("patchscan_png_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::string Path(const std::string& name) const { return (dir_ / name).string(); }
  std::filesystem::path dir_;
};

TEST_F(PngEncoderTest, SrgbOfItsInputAndSameBytesForAnyThreads) {
  // Band edges everywhere they can fall: one row, a band less one, a band, several and a bit;
  // deflate's default matching and zlib's runs alike.
  for (const bool runLength : {false, true})
  for (const int width : {1, 5, 333, 1500}) {
    const int band = PngEncoder::RowsPerBand(width);
    for (const int height : {1, band - 1, band, 3 * band + 1}) {
      if (height < 1 || static_cast<long>(width) * height > 4'000'000) continue;
      SCOPED_TRACE("image " + std::to_string(width) + "x" + std::to_string(height) + (runLength ? " runs" : ""));
      const auto px = TestImage(width, height, static_cast<unsigned>(width * 7 + height));
      const auto expected = ExpectedBytes(px, width, height);
      const auto one = ReadFile(Encode(px, width, height, 1, Path("t1.png"), runLength));
      int idats = 0;
      const auto filtered = CheckChunks(one, &idats);
      ASSERT_EQ(filtered.size(), static_cast<std::size_t>(height) * (width * 4 + 1));
      EXPECT_EQ(idats, (height + band - 1) / band);  // one IDAT a band
      // One code: the encoder's table steps linear values by 1/65535 (and rounds halves its way).
      EXPECT_LE(MaxByteDifference(Decode(Path("t1.png"), width, height), expected), 1);
      for (const int threads : {2, 3, 7})
        EXPECT_EQ(ReadFile(Encode(px, width, height, threads, Path("tn.png"), runLength)), one) << threads << " threads";
    }
  }
}

TEST_F(PngEncoderTest, AsSmallAsOneDeflate) {
  // The bands' cuts cost a sync flush (5 bytes) and a fresh block header each; their
  // dictionaries keep matches reaching back across the cut. Against libpng's single stream
  // (same level, same filter heuristic) the file may grow by this fraction at most.
  constexpr double kGrowthTol = 0.02;
  const int width = 1024, height = 768;
  const auto px = TestImage(width, height, 11);
  const auto ours = ReadFile(Encode(px, width, height, 2, Path("ours.png")));
  EncodeWithOiio(Decode(Path("ours.png"), width, height), width, height, Path("libpng.png"));
  const auto theirs = ReadFile(Path("libpng.png"));
  EXPECT_LE(static_cast<double>(ours.size()), (1.0 + kGrowthTol) * static_cast<double>(theirs.size()))
      << "ours " << ours.size() << " bytes, libpng " << theirs.size();
}

TEST_F(PngEncoderTest, WritesWhenNoThreadIsFreeToDeflate) {
  // The back end hands rows over from a thread that may hold the only worker busy: a band
  // no task has taken up is deflated by the thread that needs it written. Here the one
  // worker is held by a task of another arena until the image is written (or, were the
  // encoder to wait for its tasks, until kPatience runs out, which the test then reports).
  constexpr auto kPatience = std::chrono::seconds(20);
  tbb::global_control one(tbb::global_control::max_allowed_parallelism, 2);  // one worker
  tbb::task_arena other(1, 0);
  std::atomic<bool> held = false, written = false, outwaited = false;
  other.enqueue([&] {
    held = true;
    const auto until = std::chrono::steady_clock::now() + kPatience;
    while (!written && std::chrono::steady_clock::now() < until) std::this_thread::yield();
    outwaited = !written;
  });
  while (!held) std::this_thread::yield();
  const int width = 400, height = 6 * PngEncoder::RowsPerBand(400);
  const auto px = TestImage(width, height, 21);
  std::FILE* f = std::fopen(Path("busy.png").c_str(), "wb");
  ASSERT_NE(f, nullptr);
  {
    PngEncoder enc(f, width, height, PngEncoder::Options{6, 2, true});
    for (int y = 0; y < height; ++y)
      EXPECT_TRUE(enc.WriteRow(&px[static_cast<std::size_t>(y) * width * kStride], kStride));
    EXPECT_TRUE(enc.Finish());
    written = true;  // the tasks still queued run now, finding their bands taken up
  }
  std::fclose(f);
  EXPECT_FALSE(outwaited) << "the encoder waited for a thread to deflate";
  EXPECT_EQ(ReadFile(Path("busy.png")), ReadFile(Encode(px, width, height, 1, Path("one.png"), true)));
}

TEST_F(PngEncoderTest, AFailedWriteIsReported) {
  if (!std::filesystem::exists("/dev/full")) GTEST_SKIP() << "no /dev/full";
  const int width = 640, height = 200;
  const auto px = TestImage(width, height, 3);
  for (const int threads : {1, 2}) {
    std::FILE* f = std::fopen("/dev/full", "wb");
    ASSERT_NE(f, nullptr);
    // Unbuffered, so the first write fails rather than the close.
    std::setvbuf(f, nullptr, _IONBF, 0);
    bool ok = true;
    {
      PngEncoder enc(f, width, height, PngEncoder::Options{6, threads});
      for (int y = 0; y < height && ok; ++y) ok = enc.WriteRow(&px[static_cast<std::size_t>(y) * width * kStride], kStride);
      if (ok) ok = enc.Finish();
    }
    std::fclose(f);
    EXPECT_FALSE(ok) << threads << " threads";
  }
}

TEST_F(PngEncoderTest, MissingRowsAreAnError) {
  const int width = 64, height = 10;
  const auto px = TestImage(width, height, 5);
  std::FILE* f = std::fopen(Path("short.png").c_str(), "wb");
  ASSERT_NE(f, nullptr);
  PngEncoder enc(f, width, height, PngEncoder::Options{6, 2});
  for (int y = 0; y < height - 1; ++y) ASSERT_TRUE(enc.WriteRow(&px[static_cast<std::size_t>(y) * width * kStride], kStride));
  EXPECT_FALSE(enc.Finish());
  std::fclose(f);
}

}  // namespace
}  // namespace patchscan::raster
