#include "mpi/shared_scan.h"

#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <deque>
#include <limits>
#include <ostream>
#include <stdexcept>
#include <streambuf>
#include <thread>
#include <vector>

#include "cli/camera_options.h"
#include "cli/render_setup.h"
#include "raster/triangle_setup.h"
#include "xscan/polygon_feed.h"

namespace patchscan::mpi {
namespace {

enum Tag : int { kGo = 1, kRow, kPixels, kDone, kFinish };

double Now() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }

long PeakKiB() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return u.ru_maxrss;
}

// ---- the frame's rows and who renders them ----

struct Layout {
  int size = 1;                 // processes
  int aa = 1, height = 0, width = 0;  // the lattice: l, pixel rows and columns
  // Channels of a pixel row sent to process 0: colour and alpha, or with the AOVs (an EXR
  // with --aov, a depth map) all of raster::kChannels.
  int channels = raster::kChannels;
  int nRows = 0;                // sample rows
  double y0 = 0.0, dy = 1.0;    // sample row j lies at y0 + j dy
  int Owner(int p) const { return (p / kBandRows) % size; }
  int FirstSample(int p) const { return aa == 1 ? p : p * (aa - 1); }
  // The first pixel row that uses sample row j (with aa > 1 a row on a pixel edge is the
  // last of the pixel row above and the first of the one below).
  int FirstPixelOf(int j) const {
    if (aa == 1) return j;
    const int p = j / (aa - 1);
    return std::min(j % (aa - 1) == 0 && j > 0 ? p - 1 : p, height - 1);
  }
  // The first sample row at or below j that process o renders (nRows: none).
  int NextOwned(int o, int j) const {
    if (j >= nRows) return nRows;
    int p = FirstPixelOf(j);
    if (Owner(p) != o) {
      const int band = p / kBandRows;
      p = (band + ((o - band % size) % size + size) % size) * kBandRows;
      if (p >= height) return nRows;
    }
    return std::max(j, FirstSample(p));
  }
  bool Owns(int o, int j) const { return NextOwned(o, j) == j; }
  // The last pixel row process o renders (-1: none).
  int LastOwnedPixel(int o) const {
    const int bands = (height + kBandRows - 1) / kBandRows;
    for (int b = bands - 1; b >= 0 && b >= bands - size; --b)
      if (b % size == o) return std::min(height - 1, (b + 1) * kBandRows - 1);
    return -1;
  }
  // The last sample row a triangle covers, as the back end bounds it (FragmentGeometry).
  int LastRowOf(const raster::RasterVertex& a, const raster::RasterVertex& b, const raster::RasterVertex& c) const {
    if (!(a.h.z() > 0 && b.h.z() > 0 && c.h.z() > 0)) return nRows - 1;
    const double yMax = std::max({a.h.y() / a.h.z(), b.h.y() / b.h.z(), c.h.y() / c.h.z()}) + raster::kBoundsSlackPx;
    const double k = std::floor((yMax - y0) / dy);
    return k >= nRows - 1 ? nRows - 1 : (k >= -1.0 ? static_cast<int>(k) : -1);
  }
};

// ---- rows as flat messages of doubles (every value of a fragment or triangle is a double
// or an integer far below 2^53, so nothing is rounded on the way) ----

constexpr std::size_t kHeader = 5;     // row, ok, fragments, chords, triangles
constexpr std::size_t kFragmentBody = 17;  // w, position, normal, uv, duvdx, duvdy, id, colour
constexpr std::size_t kFragment = 2 + kFragmentBody;  // rank, column, fragment
// rank, xa, xb, orthographic, cubic, the ends' fragments, the normal's and depth's cubics
// and the root's u0
constexpr std::size_t kChord = 5 + 2 * kFragmentBody + 17;
constexpr std::size_t kVertex = 15;    // h, position, normal, uv, depth, colour
constexpr std::size_t kTriangle = 3 + 3 * kVertex;  // origin row, rank, id, three vertices

void Put(std::vector<double>& m, const Vec3& v) { m.insert(m.end(), {v.x(), v.y(), v.z()}); }
void Put(std::vector<double>& m, const Vec2& v) { m.insert(m.end(), {v.x(), v.y()}); }
Vec3 Get3(const double* d) { return Vec3(d[0], d[1], d[2]); }
Vec2 Get2(const double* d) { return Vec2(d[0], d[1]); }

void PutFragment(std::vector<double>& m, const raster::Fragment& f) {
  m.push_back(f.w);
  Put(m, f.position);
  Put(m, f.normal);
  Put(m, f.uv);
  Put(m, f.duvdx);
  Put(m, f.duvdy);
  m.push_back(f.surfaceId);
  Put(m, f.colour);
}

raster::Fragment GetFragment(const double* d) {
  raster::Fragment f;
  f.w = d[0];
  f.position = Get3(d + 1);
  f.normal = Get3(d + 4);
  f.uv = Get2(d + 7);
  f.duvdx = Get2(d + 9);
  f.duvdy = Get2(d + 11);
  f.surfaceId = static_cast<std::uint32_t>(d[13]);
  f.colour = Get3(d + 14);
  return f;
}

// What one process's scan hands over on one sample row, each entry with its surface's
// rank in the scan order of all surfaces (polygons after every surface), each triangle
// with the last sample row it covers.
class RowEncoder final : public raster::FragmentRow {
 public:
  RowEncoder(const std::vector<std::uint32_t>& rank, const Layout& layout) : rank_(rank), layout_(layout) {}
  void Begin(int row) {
    row_ = row;
    fragments.clear();
    chords.clear();
    triangles.clear();
    lastRows.clear();
  }
  void Add(int column, const raster::Fragment& f) override {
    fragments.insert(fragments.end(), {Rank(f.surfaceId), static_cast<double>(column)});
    PutFragment(fragments, f);
  }
  // A chord travels whole, as the back end keeps it (its samples shaded from it, a run of
  // a pixel's at their mean column): ends and cubics, made again bit for bit.
  void AddChord(const raster::Chord& c, const raster::SampleColumns&) override {
    const raster::Chord::Cubics* cubics = c.cubics();
    chords.insert(chords.end(), {Rank(c.a().surfaceId), c.xa(), c.xb(), c.orthographic() ? 1.0 : 0.0,
                                 cubics ? 1.0 + cubics->root : 0.0});
    PutFragment(chords, c.a());
    PutFragment(chords, c.b());
    const raster::Chord::Cubics none;
    const raster::Chord::Cubics& k = cubics ? *cubics : none;
    for (const Vec3& n : k.normal) Put(chords, n);
    chords.insert(chords.end(), std::begin(k.depth), std::end(k.depth));
    chords.push_back(k.u0);
  }
  void AddTriangle(const raster::RasterVertex& a, const raster::RasterVertex& b, const raster::RasterVertex& c,
                   std::uint32_t surfaceId) override {
    triangles.insert(triangles.end(), {static_cast<double>(row_), Rank(surfaceId), static_cast<double>(surfaceId)});
    for (const raster::RasterVertex* v : {&a, &b, &c}) {
      Put(triangles, v->h);
      Put(triangles, v->position);
      Put(triangles, v->normal);
      Put(triangles, v->uv);
      triangles.push_back(v->depth);
      Put(triangles, v->colour);
    }
    lastRows.push_back(layout_.LastRowOf(a, b, c));
  }
  std::vector<double> fragments, chords, triangles;
  std::vector<int> lastRows;  // per triangle

 private:
  double Rank(std::uint32_t id) const { return id < rank_.size() ? rank_[id] : static_cast<double>(rank_.size()); }
  const std::vector<std::uint32_t>& rank_;
  const Layout& layout_;
  int row_ = 0;
};

raster::Chord DecodeChord(const double* d) {
  const double* cubic = d + 5 + 2 * kFragmentBody;
  raster::Chord::Cubics k;
  for (int i = 0; i < 4; ++i) k.normal[i] = Get3(cubic + 3 * i), k.depth[i] = cubic[12 + i];
  k.root = static_cast<int>(d[4]) - 1;
  k.u0 = cubic[16];
  return raster::Chord(d[1], GetFragment(d + 5), d[2], GetFragment(d + 5 + kFragmentBody), d[3] != 0.0,
                       d[4] != 0.0 ? &k : nullptr);
}

raster::RasterVertex DecodeVertex(const double* d) {
  raster::RasterVertex v;
  v.h = Get3(d);
  v.position = Get3(d + 3);
  v.normal = Get3(d + 6);
  v.uv = Get2(d + 9);
  v.depth = d[11];
  v.colour = Get3(d + 12);
  return v;
}

// A row as received, and where its lists are.
struct RowMessage {
  std::vector<double> data;
  std::size_t nFragments = 0, nChords = 0, nTriangles = 0;
  bool ok = true;
  bool Parse(int row) {
    if (data.size() < kHeader || data[0] != row) return false;
    ok = data[1] != 0.0;
    nFragments = static_cast<std::size_t>(data[2]);
    nChords = static_cast<std::size_t>(data[3]);
    nTriangles = static_cast<std::size_t>(data[4]);
    return data.size() == kHeader + nFragments * kFragment + nChords * kChord + nTriangles * kTriangle;
  }
  const double* Fragment(std::size_t k) const { return data.data() + kHeader + k * kFragment; }
  const double* Chord(std::size_t k) const { return data.data() + kHeader + nFragments * kFragment + k * kChord; }
  const double* Triangle(std::size_t k) const {
    return data.data() + kHeader + nFragments * kFragment + nChords * kChord + k * kTriangle;
  }
};

// The entries of several messages in the order of their keys (fragments: the rank;
// triangles: the row they were handed over on, then the rank): each message's are in that
// order already and no two messages share a rank, so a k-way merge, ties kept in order.
template <class Count, class Less, class At, class Take>
void Merge(const std::vector<RowMessage>& m, Count count, At at, Less less, Take take, std::vector<std::size_t>* next) {
  next->assign(m.size(), 0);
  for (;;) {
    std::size_t best = m.size();
    for (std::size_t k = 0; k < m.size(); ++k)
      if ((*next)[k] < count(m[k]) && (best == m.size() || less(at(m[k], (*next)[k]), at(m[best], (*next)[best]))))
        best = k;
    if (best == m.size()) return;
    take(at(m[best], (*next)[best]++));
  }
}

std::vector<double> Text(const std::string& s) { return std::vector<double>(s.begin(), s.end()); }
std::string TextOf(const double* d, std::size_t n) {
  std::string s;
  for (std::size_t k = 0; k < n; ++k) s += static_cast<char>(d[k]);
  return s;
}

// Point to point: sends that do not wait (each buffer kept until its send completes), and
// receives of one tag from one process; bytes counted.
class Link {
 public:
  explicit Link(MPI_Comm comm) : comm_(comm) {
    MPI_Comm_rank(comm, &rank_);
    MPI_Comm_size(comm, &size_);
  }
  ~Link() { WaitAll(); }
  int Rank() const { return rank_; }
  int Size() const { return size_; }
  template <class T>
  void Send(int to, Tag tag, std::vector<T> data) {
    Pending p;
    p.doubles = std::is_same_v<T, double>;
    if constexpr (std::is_same_v<T, double>) p.d = std::move(data);
    else p.f = std::move(data);
    const int n = static_cast<int>(p.doubles ? p.d.size() : p.f.size());
    pending_.push_back(std::move(p));
    Pending& q = pending_.back();
    MPI_Isend(q.doubles ? static_cast<void*>(q.d.data()) : static_cast<void*>(q.f.data()), n,
              q.doubles ? MPI_DOUBLE : MPI_FLOAT, to, tag, comm_, &q.request);
    sent += static_cast<std::int64_t>(n) * (q.doubles ? 8 : 4);
    // Buffers of sends that completed are let go.
    while (!pending_.empty()) {
      int done = 0;
      MPI_Test(&pending_.front().request, &done, MPI_STATUS_IGNORE);
      if (!done) break;
      pending_.pop_front();
    }
  }
  void Receive(int from, Tag tag, std::vector<double>* data) { ReceiveAs(from, tag, MPI_DOUBLE, data); }
  void Receive(int from, Tag tag, std::vector<float>* data) { ReceiveAs(from, tag, MPI_FLOAT, data); }
  void WaitAll() {
    for (Pending& p : pending_) MPI_Wait(&p.request, MPI_STATUS_IGNORE);
    pending_.clear();
  }
  std::int64_t sent = 0, received = 0;

 private:
  template <class T>
  void ReceiveAs(int from, Tag tag, MPI_Datatype type, std::vector<T>* data) {
    MPI_Status status;
    MPI_Probe(from, tag, comm_, &status);
    int n = 0;
    MPI_Get_count(&status, type, &n);
    data->resize(static_cast<std::size_t>(n));
    MPI_Recv(data->data(), n, type, from, tag, comm_, MPI_STATUS_IGNORE);
    received += static_cast<std::int64_t>(n) * static_cast<std::int64_t>(sizeof(T));
  }
  struct Pending {
    MPI_Request request = MPI_REQUEST_NULL;
    bool doubles = true;
    std::vector<double> d;
    std::vector<float> f;
  };
  MPI_Comm comm_;
  int rank_ = 0, size_ = 1;
  std::deque<Pending> pending_;  // a deque: its elements stay where they are while it grows
};

// ---- one frame on one process ----

// A process's part of a frame: it scans its share of the surfaces on every sample row,
// sends each owner what lands on the owner's rows, and hands its own back end its rows
// merged from every process. It goes on with the frame's messages after a failure
// (Fail), sending empty rows, so that the others finish.
class Band final : public DirectScanSource {
 public:
  Band(MPI_Comm comm, const Scene& scene, const Camera& camera, const ExactScanOptions& options, int threads,
       const std::vector<double>* go)
      : link_(comm), options_(options) {
    const std::vector<ScanEntry> order = ScanOrder(scene.surfaces, camera);
    local_ = std::make_unique<PartitionedScan>(scene.surfaces, camera, options, threads, threads,
                                               PartitionSurfaces(order, camera, link_.Size())[link_.Rank()]);
    layout_.size = link_.Size();
    layout_.height = camera.height;
    layout_.width = camera.width;
    encoder_ = std::make_unique<RowEncoder>(local_->Ranks(), layout_);
    carry_.resize(static_cast<std::size_t>(link_.Size()));
    messages_.resize(static_cast<std::size_t>(link_.Size()));
    // Process 0 hands the polygons over with its rows, after every surface (their rank).
    if (link_.Rank() == 0 && !scene.polygons.empty()) {
      raster::TriangleMesh triangles;
      AppendPolygonTriangles(scene.polygons, camera, static_cast<std::uint32_t>(scene.surfaces.size()), &triangles);
      polygons_ = std::make_unique<PolygonQueue>(std::move(triangles));
    }
    // A test's fault: a process other than 0 fails at that sample row
    // (PATCHSCAN_MPI_FAIL_AT_ROW).
    if (const char* at = std::getenv("PATCHSCAN_MPI_FAIL_AT_ROW"); at && link_.Rank() != 0) failAt_ = std::atoi(at);
    if (go) Start(*go);
  }

  ~Band() override {
    // However the frame went, it ends here for this process: it goes on with the frame's
    // messages (empty rows) so that no other process waits forever; process 0 takes the
    // others' pixel rows and their ends.
    if (!started_ || completed_) return;
    Fail("stopped");
    try {
      Finish();
      if (link_.Rank() == 0) {
        BringIn(layout_.height, nullptr);
        CollectDone();
      }
    } catch (...) {
    }
  }

  // The frame's rows, as the back end announces them (process 0: and the others are told).
  void BeginRows(const raster::SampleColumns& columns, double y0, double dy, int nRows,
                 const raster::KeptDepths& kept) override {
    // Every process's back end keeps the same of each sample (the same settings).
    local_->KeepDepths(kept, columns.n);
    if (started_) return;
    std::vector<double> go = {0.0, options_.extrapolate ? 1.0 : 0.0, static_cast<double>(options_.thetaSteps),
                              static_cast<double>(options_.slabRows), columns.x0, columns.dx,
                              static_cast<double>(columns.n), y0, dy, static_cast<double>(nRows),
                              static_cast<double>(aa_), static_cast<double>(layout_.channels)};
    go[0] = frame_;
    for (int k = 1; k < link_.Size(); ++k) link_.Send(k, kGo, go);
    Start(go);
  }
  void SetFrame(int frame, int aa, int channels) {
    frame_ = frame;
    aa_ = aa;
    layout_.channels = channels;
  }

  bool ScanRow(double y, const raster::SampleColumns& columns, raster::FragmentRow& out) override {
    const int j = static_cast<int>(std::lround((y - layout_.y0) / layout_.dy));
    ScanThrough(j);
    // This process's own part of the row, and every other process's.
    messages_[static_cast<std::size_t>(link_.Rank())] = std::move(own_.front());
    own_.pop_front();
    for (int k = 0; k < link_.Size(); ++k) {
      RowMessage& m = messages_[static_cast<std::size_t>(k)];
      if (k != link_.Rank()) link_.Receive(k, kRow, &m.data);
      if (!m.Parse(j)) throw std::runtime_error("process " + std::to_string(k) + " sent a malformed row");
    }
    received_ = j + 1;
    const double t0 = Now();
    Merge(
        messages_, [](const RowMessage& m) { return m.nFragments; },
        [](const RowMessage& m, std::size_t i) { return m.Fragment(i); },
        [](const double* a, const double* b) { return a[0] < b[0]; },
        [&](const double* d) { out.Add(static_cast<int>(d[1]), GetFragment(d + 2)); }, &next_);
    Merge(
        messages_, [](const RowMessage& m) { return m.nChords; },
        [](const RowMessage& m, std::size_t i) { return m.Chord(i); },
        [](const double* a, const double* b) { return a[0] < b[0]; },
        [&](const double* d) { out.AddChord(DecodeChord(d), columns); }, &next_);
    Merge(
        messages_, [](const RowMessage& m) { return m.nTriangles; },
        [](const RowMessage& m, std::size_t i) { return m.Triangle(i); },
        [](const double* a, const double* b) { return a[0] < b[0] || (a[0] == b[0] && a[1] < b[1]); },
        [&](const double* d) {
          out.AddTriangle(DecodeVertex(d + 3), DecodeVertex(d + 3 + kVertex), DecodeVertex(d + 3 + 2 * kVertex),
                          static_cast<std::uint32_t>(d[2]));
        },
        &next_);
    compositeSeconds_ += Now() - t0;
    bool ok = true;
    for (const RowMessage& m : messages_) ok = ok && m.ok;
    return ok;
  }

  // Scans every row not yet scanned, drains the rows sent here that the back end did not
  // take, and waits for this process's sends.
  void Finish() {
    if (!started_ || finished_) return;
    finished_ = true;
    ScanThrough(layout_.nRows - 1);
    std::vector<double> dropped;
    for (int j = layout_.NextOwned(link_.Rank(), received_); j < layout_.nRows;
         j = layout_.NextOwned(link_.Rank(), j + 1))
      for (int k = 0; k < link_.Size(); ++k)
        if (k != link_.Rank()) link_.Receive(k, kRow, &dropped);
    own_.clear();
    link_.WaitAll();
  }

  // From now on this process's rows are empty (a failure, an interruption); `why` goes to
  // process 0 with kDone.
  void Fail(const std::string& why) {
    if (why_.empty()) why_ = why;
  }
  const std::string& Why() const { return why_; }

  Counters Stats() const override {
    Counters total = local_->Stats();
    total.Merge(remote_);
    return total;
  }
  Timing Times() const override {
    Timing t = local_->Times();
    for (const Process& p : processes_) t.workerSeconds.push_back(p.seconds);
    t.compositeSeconds = compositeSeconds_;
    return t;
  }
  std::vector<Process> Processes() const override {
    std::vector<Process> p = {Own()};
    p.insert(p.end(), processes_.begin(), processes_.end());
    return p;
  }
  void SetTrace(TraceSink*) override {}
  std::function<bool(int)> OwnedRows() const override {
    const Layout l = layout_;
    const int me = link_.Rank();
    return [l, me](int p) { return l.Owner(p) == me; };
  }
  bool FeedsPolygons() const override { return true; }
  std::unique_ptr<raster::RowSink> AssembleRows(raster::RowSink& next) override;

  // This process's figures, and (process 0) the others' from their kDone.
  Process Own() const {
    double seconds = 0.0;
    for (const double t : local_->Times().workerSeconds) seconds += t;
    return {link_.Rank(), seconds, link_.sent, link_.received, PeakKiB()};
  }
  std::vector<double> DoneMessage(const Counters& backEnd) const {
    Counters all = local_->Stats();
    all.Merge(backEnd);
    std::vector<double> d;
    for (const CounterInfo& info : kCounterTable) d.push_back(static_cast<double>(all[info.counter]));
    const Process p = Own();
    d.insert(d.end(), {p.seconds, static_cast<double>(p.bytesSent), static_cast<double>(p.bytesReceived),
                       static_cast<double>(p.peakKiB)});
    const std::vector<double> why = Text(why_);
    d.insert(d.end(), why.begin(), why.end());
    return d;
  }
  // Process 0: every other process's kDone; the first failure's reason ("" when none).
  std::string CollectDone() {
    completed_ = true;
    std::string failure;
    std::vector<double> d;
    for (int k = 1; k < link_.Size(); ++k) {
      link_.Receive(k, kDone, &d);
      const std::size_t n = kNumCounters;
      if (d.size() < n + 4) throw std::runtime_error("process " + std::to_string(k) + " ended its frame malformed");
      Counters c;
      std::size_t at = 0;
      for (const CounterInfo& info : kCounterTable) c[info.counter] = static_cast<std::int64_t>(d[at++]);
      remote_.Merge(c);
      processes_.push_back({k, d[n], static_cast<std::int64_t>(d[n + 1]), static_cast<std::int64_t>(d[n + 2]),
                            static_cast<long>(d[n + 3])});
      const std::string why = TextOf(d.data() + n + 4, d.size() - n - 4);
      if (failure.empty() && !why.empty()) failure = "process " + std::to_string(k) + ": " + why;
    }
    return failure;
  }
  // Process 0: the others' pixel rows up to (not with) pixel row `end`, in order, to `next`
  // (null: dropped); false if `next` stops.
  bool BringIn(int end, raster::RowSink* next) {
    for (; pixelsIn_ < end; ++pixelsIn_) {
      const int owner = layout_.Owner(pixelsIn_);
      if (owner == 0) continue;
      link_.Receive(owner, kPixels, &sent_);
      const auto w = static_cast<std::size_t>(layout_.width), c = static_cast<std::size_t>(layout_.channels);
      if (sent_.size() != w * c) throw std::runtime_error("process " + std::to_string(owner) + " sent a malformed pixel row");
      pixels_.assign(w * raster::kChannels, 0.0f);
      for (std::size_t x = 0; x < w; ++x)
        std::copy(sent_.begin() + static_cast<std::ptrdiff_t>(x * c), sent_.begin() + static_cast<std::ptrdiff_t>((x + 1) * c),
                  pixels_.begin() + static_cast<std::ptrdiff_t>(x * raster::kChannels));
      if (next && !next->WriteRow(pixelsIn_, pixels_.data())) return false;
    }
    return true;
  }
  // The rows below this process's last, scanned for the others once its own are done.
  void ScanRest() { ScanThrough(layout_.nRows - 1); }
  // Process 0, after one of its own pixel rows went to the image.
  void PassedOwnRow(int y) { pixelsIn_ = std::max(pixelsIn_, y + 1); }
  // Process 0, after the image's last row: the frame's end; the first failure, if any.
  std::string Complete() {
    Finish();
    return CollectDone();
  }
  Link& Channel() { return link_; }
  const Layout& Rows() const { return layout_; }

 private:
  void Start(const std::vector<double>& go) {
    layout_.y0 = go[7];
    layout_.dy = go[8];
    layout_.nRows = static_cast<int>(go[9]);
    layout_.aa = static_cast<int>(go[10]);
    layout_.channels = static_cast<int>(go[11]);
    columns_ = raster::SampleColumns{go[4], go[5], static_cast<int>(go[6])};
    started_ = true;
  }

  void ScanThrough(int last) {
    for (; scanned_ <= last && scanned_ < layout_.nRows; ++scanned_) ScanOne(scanned_);
  }

  // Scans sample row j (a failed process: nothing) and sends each owner its part.
  void ScanOne(int j) {
    const double y = layout_.y0 + j * layout_.dy;
    // Step 1: this process's surfaces on the row (a θ slab interval's surfaces each decide
    // alone whether they are slabs: no process waits for another's).
    encoder_->Begin(j);
    bool ok = true;
    if (why_.empty() && j == failAt_) Fail("a fault injected at row " + std::to_string(j));
    if (why_.empty()) {
      try {
        ok = local_->ScanRowNow(y, columns_, *encoder_);
        if (polygons_) polygons_->HandOver(y, layout_.dy, *encoder_);
      } catch (const std::exception& e) {
        Fail(e.what());
      }
    }
    if (!why_.empty()) encoder_->Begin(j);  // empty from the failure on
    // Step 2: each owner of this row gets its fragments and the triangles reaching its
    // rows, with those carried from rows it does not render.
    const std::size_t nTriangles = encoder_->lastRows.size();
    for (int o = 0; o < link_.Size(); ++o) {
      std::vector<double>& carry = carry_[static_cast<std::size_t>(o)];
      const bool owns = layout_.Owns(o, j);
      const int next = owns ? j : layout_.NextOwned(o, j);
      for (std::size_t t = 0; t < nTriangles; ++t)
        if (next <= encoder_->lastRows[t])
          carry.insert(carry.end(), encoder_->triangles.begin() + static_cast<std::ptrdiff_t>(t * kTriangle),
                       encoder_->triangles.begin() + static_cast<std::ptrdiff_t>((t + 1) * kTriangle));
      if (!owns) continue;
      std::vector<double> m = {static_cast<double>(j), ok ? 1.0 : 0.0,
                               static_cast<double>(encoder_->fragments.size() / kFragment),
                               static_cast<double>(encoder_->chords.size() / kChord),
                               static_cast<double>(carry.size() / kTriangle)};
      m.reserve(kHeader + encoder_->fragments.size() + encoder_->chords.size() + carry.size());
      m.insert(m.end(), encoder_->fragments.begin(), encoder_->fragments.end());
      m.insert(m.end(), encoder_->chords.begin(), encoder_->chords.end());
      m.insert(m.end(), carry.begin(), carry.end());
      carry.clear();
      if (o == link_.Rank()) {
        RowMessage own;
        own.data = std::move(m);
        own_.push_back(std::move(own));
      } else {
        link_.Send(o, kRow, std::move(m));
      }
    }
  }

  Link link_;
  ExactScanOptions options_;
  Layout layout_;
  raster::SampleColumns columns_;
  std::unique_ptr<PartitionedScan> local_;
  std::unique_ptr<RowEncoder> encoder_;
  std::unique_ptr<PolygonQueue> polygons_;
  std::vector<std::vector<double>> carry_;  // per owner: triangles for its next row
  std::deque<RowMessage> own_;              // this process's part of its own rows, scanned ahead
  std::vector<RowMessage> messages_;
  std::vector<std::size_t> next_;
  int scanned_ = 0, received_ = 0;
  int pixelsIn_ = 0;  // process 0: the next pixel row to bring in
  int frame_ = -1, aa_ = 1, failAt_ = -1;
  bool started_ = false, finished_ = false, completed_ = false;
  std::string why_;
  Counters remote_;
  std::vector<Process> processes_;
  std::vector<float> sent_, pixels_;
  double compositeSeconds_ = 0.0;
};

// Process 0's rows to the image: its own as its back end finishes them, the others' from
// their owners, in order; after the last row, the frame's end (every process's kDone: a
// process that failed fails the render, and no image is written).
class Assembler final : public raster::RowSink {
 public:
  Assembler(Band& band, raster::RowSink& next) : band_(band), next_(next) {}
  bool WriteRow(int y, const float* pixels) override {
    if (!band_.BringIn(y, &next_) || !next_.WriteRow(y, pixels)) return false;
    band_.PassedOwnRow(y);
    if (y == band_.Rows().LastOwnedPixel(0)) {
      band_.ScanRest();
      if (!band_.BringIn(band_.Rows().height, &next_)) return false;
      if (const std::string failure = band_.Complete(); !failure.empty()) throw std::runtime_error(failure);
    }
    return true;
  }

 private:
  Band& band_;
  raster::RowSink& next_;
};

std::unique_ptr<raster::RowSink> Band::AssembleRows(raster::RowSink& next) {
  return std::make_unique<Assembler>(*this, next);
}

// A process's finished pixel rows to process 0; rows it owes after a failure go empty.
class SendRows final : public raster::RowSink {
 public:
  SendRows(Link& link, const Layout& layout) : link_(link), layout_(layout) {}
  bool WriteRow(int y, const float* pixels) override {
    const auto w = static_cast<std::size_t>(layout_.width), c = static_cast<std::size_t>(layout_.channels);
    std::vector<float> row(w * c);
    for (std::size_t x = 0; x < w; ++x) std::copy(pixels + x * raster::kChannels, pixels + x * raster::kChannels + c, row.begin() + static_cast<std::ptrdiff_t>(x * c));
    link_.Send(0, kPixels, std::move(row));
    next_ = y + 1;
    return cli::gInterrupted == 0;
  }
  void SendTheRest() {
    for (; next_ < layout_.height; ++next_)
      if (layout_.Owner(next_) == link_.Rank()) link_.Send(0, kPixels, std::vector<float>(Size(), 0.0f));
  }

 private:
  std::size_t Size() const { return static_cast<std::size_t>(layout_.width) * static_cast<std::size_t>(layout_.channels); }
  Link& link_;
  const Layout& layout_;
  int next_ = 0;
};

// Discards what is written to it: only process 0 speaks to the user.
class NullBuffer final : public std::streambuf {
 protected:
  int overflow(int c) override { return c; }
};

// One frame on a process other than 0, as process 0 asked for it in `go`.
void ServeFrame(MPI_Comm comm, const cli::RenderOptions& o, const std::vector<double>& go) {
  if (go.size() != 12) throw std::runtime_error("a malformed frame request");
  NullBuffer none;
  std::ostream quiet(&none);
  cli::CameraOptions cameraOptions = o.camera;
  cameraOptions.frame = static_cast<int>(go[0]);
  ExactScanOptions options;
  options.extrapolate = go[1] != 0.0;
  options.thetaSteps = static_cast<int>(go[2]);
  options.slabRows = static_cast<int>(go[3]);
  const int aa = static_cast<int>(go[10]);
  const int threads = o.threads > 0 ? o.threads : std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
  auto loaded = cli::LoadSceneAndCamera(o.file, cameraOptions, quiet);
  // A scene this process cannot read: it still takes its part in the frame's messages.
  Scene empty;
  const Scene& scene = std::holds_alternative<cli::LoadedScene>(loaded) ? std::get<cli::LoadedScene>(loaded).scene : empty;
  Camera camera;
  if (std::holds_alternative<cli::LoadedScene>(loaded)) camera = std::get<cli::LoadedScene>(loaded).view.camera;
  Band band(comm, scene, camera, options, threads, &go);
  band.SetFrame(static_cast<int>(go[0]), aa, static_cast<int>(go[11]));
  SendRows sink(band.Channel(), band.Rows());
  Counters counted;
  if (!std::holds_alternative<cli::LoadedScene>(loaded)) band.Fail("cannot read " + o.file);
  if (band.Why().empty()) {
    try {
      auto setup = cli::SetUpBackEnd(o, scene, camera, aa, quiet);
      if (std::holds_alternative<int>(setup)) throw std::runtime_error("cannot set up the back end");
      raster::RenderSettings& settings = std::get<std::unique_ptr<cli::BackEndSetup>>(setup)->settings;
      settings.threads = threads;
      settings.ownsRow = band.OwnedRows();
      if (auto c = raster::RenderFragments(band, settings, sink)) counted = *c;
      else band.Fail(cli::gInterrupted ? "interrupted" : "its render stopped");
    } catch (const std::exception& e) {
      band.Fail(e.what());
    }
  }
  // The pixel rows owed to process 0 first (empty after a failure: process 0 waits for
  // them in order), then the rest of the frame's rows for the other owners.
  sink.SendTheRest();
  band.Finish();
  band.Channel().Send(0, kDone, band.DoneMessage(counted));
  band.Channel().WaitAll();
}

}  // namespace

std::unique_ptr<DirectScanSource> MakeSharedScan(MPI_Comm comm, const cli::RenderOptions& o, const Scene& scene,
                                                 const Camera& camera, const ExactScanOptions& options, int aa,
                                                 int threads) {
  auto band = std::make_unique<Band>(comm, scene, camera, options, threads, nullptr);
  // The AOVs travel only when the image keeps them: an EXR with --aov, or a depth map
  // (a "zfile" or "shadow" Display, as render writes it when no -o is given).
  band->SetFrame(o.camera.frame, aa, o.aov || cli::WritesDepthMap(o, scene) ? raster::kChannels : 4);
  return band;
}

int ServeFrames(MPI_Comm comm, const cli::RenderOptions& options) {
  cli::CatchInterrupts();  // process 0 decides when to stop; an interrupt reaches it too
  Link link(comm);
  std::vector<double> in;
  for (;;) {
    MPI_Status status;
    MPI_Probe(0, MPI_ANY_TAG, comm, &status);
    if (status.MPI_TAG == kFinish) {
      link.Receive(0, kFinish, &in);
      return in.empty() ? 70 : static_cast<int>(in[0]);
    }
    link.Receive(0, static_cast<Tag>(status.MPI_TAG), &in);
    if (status.MPI_TAG == kGo) ServeFrame(comm, options, in);
  }
}

void FinishAll(MPI_Comm comm, int code) {
  int size = 1;
  MPI_Comm_size(comm, &size);
  const double c = code;
  for (int k = 1; k < size; ++k) MPI_Send(&c, 1, MPI_DOUBLE, k, kFinish, comm);
}

}  // namespace patchscan::mpi
