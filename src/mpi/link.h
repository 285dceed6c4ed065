// Point to point between MPI processes, for patchscan-mpi (mpi/shared_scan.h).
#pragma once

#include <mpi.h>

#include <cstdint>
#include <deque>
#include <type_traits>
#include <vector>

#include "mpi/wire.h"

namespace patchscan::mpi {

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

}  // namespace patchscan::mpi
