#include "mpi/shared_scan.h"

#include <sys/resource.h>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <ostream>
#include <stdexcept>
#include <streambuf>
#include <vector>

#include "cli/camera_options.h"
#include "cli/render_setup.h"

namespace patchscan::mpi {
namespace {

enum Tag : int { kGo = 1, kRow, kVote, kVerdict, kCredit, kStop, kError, kDone, kFinish };

double Now() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }

long PeakKiB() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return u.ru_maxrss;
}

// ---- a row as a flat message of doubles (every value of a fragment or triangle is a
// double or an integer far below 2^53, so nothing is rounded on the way) ----

constexpr std::size_t kHeader = 4;     // row, ok, fragments, triangles
constexpr std::size_t kFragment = 19;  // rank, column, w, position, normal, uv, duvdx, duvdy, id, colour
constexpr std::size_t kVertex = 15;    // h, position, normal, uv, depth, colour
constexpr std::size_t kTriangle = 2 + 3 * kVertex;  // rank, id, three vertices

void Put(std::vector<double>& m, const Vec3& v) { m.insert(m.end(), {v.x(), v.y(), v.z()}); }
void Put(std::vector<double>& m, const Vec2& v) { m.insert(m.end(), {v.x(), v.y()}); }
Vec3 Get3(const double* d) { return Vec3(d[0], d[1], d[2]); }
Vec2 Get2(const double* d) { return Vec2(d[0], d[1]); }

// Encodes what a scan hands over, each entry with its surface's scan rank: fragments and
// triangles in two lists (the back end takes them so), joined into one message.
class RowEncoder final : public raster::FragmentRow {
 public:
  explicit RowEncoder(const PartitionedScan& scan) : scan_(scan) {}
  void Begin(int row) {
    row_ = row;
    fragments_.clear();
    triangles_.clear();
    nFragments_ = nTriangles_ = 0;
  }
  void Add(int column, const raster::Fragment& f) override {
    fragments_.insert(fragments_.end(), {static_cast<double>(scan_.RankOf(f.surfaceId)), static_cast<double>(column), f.w});
    Put(fragments_, f.position);
    Put(fragments_, f.normal);
    Put(fragments_, f.uv);
    Put(fragments_, f.duvdx);
    Put(fragments_, f.duvdy);
    fragments_.push_back(f.surfaceId);
    Put(fragments_, f.colour);
    ++nFragments_;
  }
  void AddTriangle(const raster::RasterVertex& a, const raster::RasterVertex& b, const raster::RasterVertex& c,
                   std::uint32_t surfaceId) override {
    triangles_.insert(triangles_.end(), {static_cast<double>(scan_.RankOf(surfaceId)), static_cast<double>(surfaceId)});
    for (const raster::RasterVertex* v : {&a, &b, &c}) {
      Put(triangles_, v->h);
      Put(triangles_, v->position);
      Put(triangles_, v->normal);
      Put(triangles_, v->uv);
      triangles_.push_back(v->depth);
      Put(triangles_, v->colour);
    }
    ++nTriangles_;
  }
  // The message: header, fragments, triangles.
  const std::vector<double>& Message(bool ok) {
    message_.assign({static_cast<double>(row_), ok ? 1.0 : 0.0, static_cast<double>(nFragments_),
                     static_cast<double>(nTriangles_)});
    message_.insert(message_.end(), fragments_.begin(), fragments_.end());
    message_.insert(message_.end(), triangles_.begin(), triangles_.end());
    return message_;
  }

 private:
  const PartitionedScan& scan_;
  int row_ = 0;
  std::size_t nFragments_ = 0, nTriangles_ = 0;
  std::vector<double> fragments_, triangles_, message_;
};

raster::Fragment DecodeFragment(const double* d, int* column) {
  *column = static_cast<int>(d[1]);
  raster::Fragment f;
  f.w = d[2];
  f.position = Get3(d + 3);
  f.normal = Get3(d + 6);
  f.uv = Get2(d + 9);
  f.duvdx = Get2(d + 11);
  f.duvdy = Get2(d + 13);
  f.surfaceId = static_cast<std::uint32_t>(d[15]);
  f.colour = Get3(d + 16);
  return f;
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

// A received message, and where its lists are.
struct RowMessage {
  std::vector<double> data;
  std::size_t nFragments = 0, nTriangles = 0;
  bool ok = true;
  bool Parse(int row) {
    if (data.size() < kHeader || data[0] != row) return false;
    ok = data[1] != 0.0;
    nFragments = static_cast<std::size_t>(data[2]);
    nTriangles = static_cast<std::size_t>(data[3]);
    return data.size() == kHeader + nFragments * kFragment + nTriangles * kTriangle;
  }
  const double* Fragment(std::size_t k) const { return data.data() + kHeader + k * kFragment; }
  const double* Triangle(std::size_t k) const {
    return data.data() + kHeader + nFragments * kFragment + k * kTriangle;
  }
};

// The entries of several messages in scan rank order: each message's are in that order
// already, and no two share a rank (a surface is one process's), so a k-way merge.
template <class Count, class At, class Take>
void Merge(const std::vector<RowMessage>& m, Count count, At at, Take take, std::vector<std::size_t>* next) {
  next->assign(m.size(), 0);
  for (;;) {
    std::size_t best = m.size();
    double bestRank = 0.0;
    for (std::size_t k = 0; k < m.size(); ++k)
      if ((*next)[k] < count(m[k]) && (best == m.size() || at(m[k], (*next)[k])[0] < bestRank)) {
        best = k;
        bestRank = at(m[k], (*next)[k])[0];
      }
    if (best == m.size()) return;
    take(at(m[best], (*next)[best]++));
  }
}

// Point to point, counting bytes.
struct Link {
  MPI_Comm comm;
  std::int64_t sent = 0, received = 0;
  void Send(int to, Tag tag, const std::vector<double>& data) {
    MPI_Send(data.data(), static_cast<int>(data.size()), MPI_DOUBLE, to, tag, comm);
    sent += static_cast<std::int64_t>(data.size() * sizeof(double));
  }
  // The next message from `from`, of any tag.
  Tag Receive(int from, std::vector<double>* data) {
    MPI_Status status;
    MPI_Probe(from, MPI_ANY_TAG, comm, &status);
    int n = 0;
    MPI_Get_count(&status, MPI_DOUBLE, &n);
    data->resize(static_cast<std::size_t>(n));
    MPI_Recv(data->data(), n, MPI_DOUBLE, from, status.MPI_TAG, comm, MPI_STATUS_IGNORE);
    received += static_cast<std::int64_t>(n) * static_cast<std::int64_t>(sizeof(double));
    return static_cast<Tag>(status.MPI_TAG);
  }
  bool Pending(int from) {
    int flag = 0;
    MPI_Iprobe(from, MPI_ANY_TAG, comm, &flag, MPI_STATUS_IGNORE);
    return flag != 0;
  }
};

std::vector<double> Text(const std::string& s) { return std::vector<double>(s.begin(), s.end()); }
std::string TextOf(const std::vector<double>& d) {
  std::string s;
  for (const double c : d) s += static_cast<char>(c);
  return s;
}

// ---- process 0 ----

class SharedScan final : public DirectScanSource {
 public:
  SharedScan(MPI_Comm comm, int frame, const Scene& scene, const Camera& camera, const ExactScanOptions& options,
             int threads)
      : link_{comm}, frame_(frame), options_(options) {
    MPI_Comm_size(comm, &size_);
    const std::vector<ScanEntry> order = ScanOrder(scene.surfaces, camera);
    local_ = std::make_unique<PartitionedScan>(scene.surfaces, camera, options, threads, threads,
                                               PartitionSurfaces(order, camera, size_)[0]);
    encoder_ = std::make_unique<RowEncoder>(*local_);
    messages_.resize(static_cast<std::size_t>(size_));
    done_.assign(static_cast<std::size_t>(size_), 1);
    remote_.resize(static_cast<std::size_t>(size_));
  }

  ~SharedScan() override {
    // Whatever happened, every process's frame ends here: those not done are told to stop,
    // and their messages are drained to their kDone.
    for (int k = 1; k < size_; ++k)
      if (!done_[k]) link_.Send(k, kStop, {});
    for (int k = 1; k < size_; ++k) {
      std::vector<double> data;
      while (!done_[k])
        if (link_.Receive(k, &data) == kDone) done_[k] = 1;
    }
  }

  void BeginRows(const raster::SampleColumns& columns, double y0, double dy, int nRows) override {
    columns_ = columns;
    y0_ = y0;
    dy_ = dy;
    nRows_ = nRows;
    const std::vector<double> go = {static_cast<double>(frame_), options_.extrapolate ? 1.0 : 0.0,
                                    static_cast<double>(options_.thetaSteps), static_cast<double>(options_.slabRows),
                                    columns.x0, columns.dx, static_cast<double>(columns.n), y0, dy,
                                    static_cast<double>(nRows)};
    for (int k = 1; k < size_; ++k) {
      link_.Send(k, kGo, go);
      done_[k] = 0;
    }
  }

  bool ScanRow(double y, const raster::SampleColumns& columns, raster::FragmentRow& out) override {
    const int j = static_cast<int>(std::lround((y - y0_) / dy_));
    // Step 1: at a θ slab interval, every process votes.
    bool slab = true;
    const bool interval = local_->PrepareRow(y, columns, &slab);
    if (interval) {
      for (int k = 1; k < size_; ++k) slab = Expect(k, kVote, -1)[0] != 0.0 && slab;
      for (int k = 1; k < size_; ++k) link_.Send(k, kVerdict, {slab ? 1.0 : 0.0});
    }
    // Step 2: this process's row, then the others'.
    encoder_->Begin(j);
    const bool ok = local_->FinishRow(slab, y, columns, *encoder_);
    messages_[0].data = encoder_->Message(ok);
    messages_[0].Parse(j);
    for (int k = 1; k < size_; ++k) {
      messages_[k].data = Expect(k, kRow, j);
      if (!messages_[k].Parse(j)) throw std::runtime_error("process " + std::to_string(k) + " sent a malformed row");
    }
    // Step 3: merged in the scan order of all surfaces.
    const double t1 = Now();
    Merge(
        messages_, [](const RowMessage& m) { return m.nFragments; },
        [](const RowMessage& m, std::size_t i) { return m.Fragment(i); },
        [&](const double* d) {
          int column = 0;
          const raster::Fragment f = DecodeFragment(d, &column);
          out.Add(column, f);
        },
        &next_);
    Merge(
        messages_, [](const RowMessage& m) { return m.nTriangles; },
        [](const RowMessage& m, std::size_t i) { return m.Triangle(i); },
        [&](const double* d) {
          out.AddTriangle(DecodeVertex(d + 2), DecodeVertex(d + 2 + kVertex), DecodeVertex(d + 2 + 2 * kVertex),
                          static_cast<std::uint32_t>(d[1]));
        },
        &next_);
    compositeSeconds_ += Now() - t1;
    bool allOk = true;
    for (const RowMessage& m : messages_) allOk = allOk && m.ok;
    // Credit: the others may run kRowsInFlight rows ahead of what is merged.
    if ((j + 1) % (kRowsInFlight / 2) == 0)
      for (int k = 1; k < size_; ++k) link_.Send(k, kCredit, {static_cast<double>(j + 1)});
    // The frame's last row: the others' counts.
    if (j + 1 == nRows_)
      for (int k = 1; k < size_; ++k) {
        const std::vector<double> d = Expect(k, kDone, -1);
        done_[k] = 1;
        Counters c;
        std::size_t at = 0;
        for (const CounterInfo& info : kCounterTable) c[info.counter] = static_cast<std::int64_t>(d[at++]);
        remote_[k].counters = c;
        remote_[k].process = {k, d[at], static_cast<std::int64_t>(d[at + 1]), static_cast<std::int64_t>(d[at + 2]),
                              static_cast<long>(d[at + 3])};
      }
    return allOk;
  }

  Counters Stats() const override {
    Counters total = local_->Stats();
    for (int k = 1; k < size_; ++k) total.Merge(remote_[k].counters);
    return total;
  }
  Timing Times() const override {
    Timing t = local_->Times();
    for (int k = 1; k < size_; ++k) t.workerSeconds.push_back(remote_[k].process.seconds);
    t.compositeSeconds = compositeSeconds_;
    return t;
  }
  std::vector<Process> Processes() const override {
    std::vector<Process> p;
    double local = 0.0;
    for (const double t : local_->Times().workerSeconds) local += t;
    p.push_back({0, local, link_.sent, link_.received, PeakKiB()});
    for (int k = 1; k < size_; ++k) p.push_back(remote_[k].process);
    return p;
  }
  void SetTrace(TraceSink*) override {}

 private:
  // The next message from process k, which must have tag `want` (a row: that row). A
  // process that failed says so: its reason, then kDone.
  std::vector<double> Expect(int k, Tag want, int row) {
    std::vector<double> data;
    const Tag tag = link_.Receive(k, &data);
    if (tag == want) return data;
    std::string why = "stopped before the frame's end";
    if (tag == kError) {
      why = TextOf(data);
      std::vector<double> rest;
      while (link_.Receive(k, &rest) != kDone) {
      }
    }
    if (tag == kError || tag == kDone) done_[k] = 1;
    throw std::runtime_error("process " + std::to_string(k) + (row >= 0 ? " at row " + std::to_string(row) : "") +
                             ": " + why);
  }

  struct Remote {
    Counters counters;
    Process process;
  };
  Link link_;
  int size_ = 1, frame_ = -1;
  ExactScanOptions options_;
  std::unique_ptr<PartitionedScan> local_;
  std::unique_ptr<RowEncoder> encoder_;
  std::vector<RowMessage> messages_;
  std::vector<std::size_t> next_;
  std::vector<char> done_;
  std::vector<Remote> remote_;
  raster::SampleColumns columns_;
  double y0_ = 0.0, dy_ = 1.0;
  int nRows_ = 0;
  double compositeSeconds_ = 0.0;
};

// ---- the other processes ----

// Discards what is written to it: only process 0 speaks to the user.
class NullBuffer final : public std::streambuf {
 protected:
  int overflow(int c) override { return c; }
};

// One frame, as process 0 asked for it in `go`; false when process 0 stopped it.
void ServeFrame(Link& link, int rank, int size, const cli::RenderOptions& o, const std::vector<double>& go) {
  const double t0 = Now();
  Counters counts;
  double seconds = 0.0;
  try {
    if (go.size() != 10) throw std::runtime_error("a malformed frame request");
    cli::CameraOptions camera = o.camera;
    camera.frame = static_cast<int>(go[0]);
    NullBuffer none;
    std::ostream quiet(&none);
    auto loaded = cli::LoadSceneAndCamera(o.file, camera, quiet);
    if (std::holds_alternative<int>(loaded)) throw std::runtime_error("cannot read " + o.file);
    const Scene& scene = std::get<cli::LoadedScene>(loaded).scene;
    const Camera& cam = std::get<cli::LoadedScene>(loaded).view.camera;
    ExactScanOptions options;
    options.extrapolate = go[1] != 0.0;
    options.thetaSteps = static_cast<int>(go[2]);
    options.slabRows = static_cast<int>(go[3]);
    const raster::SampleColumns columns{go[4], go[5], static_cast<int>(go[6])};
    const double y0 = go[7], dy = go[8];
    const int nRows = static_cast<int>(go[9]);
    const int threads = o.threads > 0 ? o.threads : 1;
    const std::vector<ScanEntry> order = ScanOrder(scene.surfaces, cam);
    PartitionedScan scan(scene.surfaces, cam, options, threads, threads,
                         PartitionSurfaces(order, cam, size)[static_cast<std::size_t>(rank)]);
    RowEncoder encoder(scan);
    // A test's fault: this process fails at that row (PATCHSCAN_MPI_FAIL_AT_ROW).
    const char* failAt = std::getenv("PATCHSCAN_MPI_FAIL_AT_ROW");
    const int failRow = failAt ? std::atoi(failAt) : -1;
    int credited = 0;
    bool stopped = false;
    std::vector<double> in;
    // Handles one message from process 0 (a credit or a stop); the verdict it waits for
    // is returned through `verdict`.
    auto handle = [&](Tag tag, int* verdict) {
      if (tag == kCredit) credited = std::max(credited, static_cast<int>(in.at(0)));
      else if (tag == kStop) stopped = true;
      else if (tag == kVerdict && verdict) *verdict = in.at(0) != 0.0;
    };
    for (int j = 0; j < nRows && !stopped; ++j) {
      while (!stopped && link.Pending(0)) handle(link.Receive(0, &in), nullptr);
      while (!stopped && j - credited >= kRowsInFlight) handle(link.Receive(0, &in), nullptr);
      if (stopped) break;
      if (j == failRow) throw std::runtime_error("a fault injected at row " + std::to_string(j));
      const double y = y0 + j * dy;
      bool vote = true;
      if (scan.PrepareRow(y, columns, &vote)) {
        link.Send(0, kVote, {vote ? 1.0 : 0.0});
        int verdict = -1;
        while (!stopped && verdict < 0) handle(link.Receive(0, &in), &verdict);
        if (stopped) break;
        vote = verdict != 0;
      }
      encoder.Begin(j);
      const bool ok = scan.FinishRow(vote, y, columns, encoder);
      link.Send(0, kRow, encoder.Message(ok));
    }
    counts = scan.Stats();
    for (const double t : scan.Times().workerSeconds) seconds += t;
  } catch (const std::exception& e) {
    link.Send(0, kError, Text(e.what()));
    seconds = Now() - t0;
  }
  std::vector<double> done;
  for (const CounterInfo& info : kCounterTable) done.push_back(static_cast<double>(counts[info.counter]));
  done.insert(done.end(), {seconds, static_cast<double>(link.sent), static_cast<double>(link.received),
                           static_cast<double>(PeakKiB())});
  link.Send(0, kDone, done);
}

}  // namespace

std::unique_ptr<DirectScanSource> MakeSharedScan(MPI_Comm comm, int frame, const Scene& scene, const Camera& camera,
                                                 const ExactScanOptions& options, int threads) {
  return std::make_unique<SharedScan>(comm, frame, scene, camera, options, threads);
}

int ServeFrames(MPI_Comm comm, const cli::RenderOptions& options) {
  int rank = 0, size = 1;
  MPI_Comm_rank(comm, &rank);
  MPI_Comm_size(comm, &size);
  cli::CatchInterrupts();  // process 0 decides when to stop; an interrupt reaches it too
  Link link{comm};
  std::vector<double> in;
  for (;;) {
    const Tag tag = link.Receive(0, &in);
    if (tag == kFinish) return in.empty() ? 70 : static_cast<int>(in[0]);
    if (tag == kGo) ServeFrame(link, rank, size, options, in);
    // A late credit or stop of a frame already over: nothing to do.
  }
}

void FinishAll(MPI_Comm comm, int code) {
  int size = 1;
  MPI_Comm_size(comm, &size);
  const double c = code;
  for (int k = 1; k < size; ++k) MPI_Send(&c, 1, MPI_DOUBLE, k, kFinish, comm);
}

}  // namespace patchscan::mpi
