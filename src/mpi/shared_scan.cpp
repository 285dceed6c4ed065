#include "mpi/shared_scan.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <ostream>
#include <stdexcept>
#include <streambuf>
#include <thread>
#include <vector>

#include "mpi/link.h"
#include "mpi/wire.h"
#include "render/back_end.h"
#include "render/interrupt.h"
#include "render/load.h"
#include "render/report.h"
#include "raster/triangle_setup.h"
#include "xscan/polygon_feed.h"

namespace patchscan::mpi {
namespace {

using Process = render::ProcessReport;

double Now() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }

// ---- one frame on one process ----

// A process's part of a frame: it scans its share of the surfaces on every sample row,
// sends each owner what lands on the owner's rows, and hands its own back end its rows
// merged from every process. It goes on with the frame's messages after a failure
// (Fail), sending empty rows, so that the others finish.
class Band final : public DirectScanSource, public render::SharedRows {
 public:
  Band(MPI_Comm comm, const Scene& scene, const Camera& camera, const ExactScanOptions& options, int threads,
       const FrameRequest* go)
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
      raster::TriangleMesh triangles = render::PolygonTriangles(scene, camera);
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
    FrameRequest go;
    go.frame = frame_;
    go.extrapolate = options_.extrapolate;
    go.thetaSteps = options_.thetaSteps;
    go.slabRows = options_.slabRows;
    go.columns = columns;
    go.y0 = y0;
    go.dy = dy;
    go.nRows = nRows;
    go.aa = aa_;
    go.channels = layout_.channels;
    for (int k = 1; k < link_.Size(); ++k) link_.Send(k, kGo, go.Encode());
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
  DirectScanSource& Source() override { return *this; }
  std::unique_ptr<raster::RowSink> AssembleRows(raster::RowSink& next) override;

  // This process's figures, and (process 0) the others' from their kDone.
  Process Own() const {
    double seconds = 0.0;
    for (const double t : local_->Times().workerSeconds) seconds += t;
    return {link_.Rank(), seconds, link_.sent, link_.received, render::PeakResidentKiB()};
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
  void Start(const FrameRequest& go) {
    layout_.y0 = go.y0;
    layout_.dy = go.dy;
    layout_.nRows = go.nRows;
    layout_.aa = go.aa;
    layout_.channels = go.channels;
    columns_ = go.columns;
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
    return render::gInterrupted == 0;
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
void ServeFrame(MPI_Comm comm, const render::RenderOptions& o, const FrameRequest& go) {
  NullBuffer none;
  std::ostream quiet(&none);
  render::CameraOptions cameraOptions = o.camera;
  cameraOptions.frame = go.frame;
  ExactScanOptions options;
  options.extrapolate = go.extrapolate;
  options.thetaSteps = go.thetaSteps;
  options.slabRows = go.slabRows;
  const int aa = go.aa;
  const int threads = render::ThreadsFor(o.threads);
  auto loaded = render::LoadSceneAndCamera(o.file, cameraOptions, quiet);
  // A scene this process cannot read: it still takes its part in the frame's messages.
  Scene empty;
  const Scene& scene = std::holds_alternative<render::LoadedScene>(loaded) ? std::get<render::LoadedScene>(loaded).scene : empty;
  Camera camera;
  if (std::holds_alternative<render::LoadedScene>(loaded)) camera = std::get<render::LoadedScene>(loaded).view.camera;
  Band band(comm, scene, camera, options, threads, &go);
  band.SetFrame(go.frame, aa, go.channels);
  SendRows sink(band.Channel(), band.Rows());
  Counters counted;
  if (!std::holds_alternative<render::LoadedScene>(loaded)) band.Fail("cannot read " + o.file);
  if (band.Why().empty()) {
    try {
      auto setup = render::SetUpBackEnd(o, scene, camera, aa);
      if (std::holds_alternative<render::Failure>(setup)) throw std::runtime_error("cannot set up the back end");
      raster::RenderSettings& settings = std::get<std::unique_ptr<render::BackEndSetup>>(setup)->settings;
      settings.threads = threads;
      settings.ownsRow = band.OwnedRows();
      if (auto c = raster::RenderFragments(band, settings, sink)) counted = *c;
      else band.Fail(render::gInterrupted ? "interrupted" : "its render stopped");
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

std::unique_ptr<render::SharedRows> MakeSharedScan(MPI_Comm comm, const render::RenderOptions& o, const Scene& scene,
                                                 const Camera& camera, const ExactScanOptions& options, int aa,
                                                 int threads) {
  auto band = std::make_unique<Band>(comm, scene, camera, options, threads, nullptr);
  // The AOVs travel only when the image keeps them: an EXR with --aov, or a depth map
  // (a "zfile" or "shadow" Display, as render writes it when no -o is given).
  band->SetFrame(o.camera.frame, aa, o.aov || render::WritesDepthMap(o, scene) ? raster::kChannels : 4);
  return band;
}

int ServeFrames(MPI_Comm comm, const render::RenderOptions& options) {
  render::CatchInterrupts();  // process 0 decides when to stop; an interrupt reaches it too
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
    if (status.MPI_TAG != kGo) continue;
    const std::optional<FrameRequest> request = FrameRequest::Decode(in);
    if (!request) throw std::runtime_error("a malformed frame request");
    ServeFrame(comm, options, *request);
  }
}

void FinishAll(MPI_Comm comm, int code) {
  int size = 1;
  MPI_Comm_size(comm, &size);
  const double c = code;
  for (int k = 1; k < size; ++k) MPI_Send(&c, 1, MPI_DOUBLE, k, kFinish, comm);
}

}  // namespace patchscan::mpi
