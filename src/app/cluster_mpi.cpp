// SPDX-License-Identifier: MIT
// The ranks of an MPI job (OpenMPI's C API; the only source that includes mpi.h). Rank 0 runs
// a server thread that hands out the schedule's items; the other ranks' workers pull them one
// message at a time. Every wait polls and sleeps instead of spinning, so a waiting rank leaves
// its cores to the ranks that work.
#define OMPI_SKIP_MPICXX 1
#define MPICH_SKIP_MPICXX 1
#include <fmt/format.h>
#include <mpi.h>

#include <atomic>
#include <chrono>
#include <cstdint>
#include <cstdlib>
#include <mutex>
#include <thread>

#include "citymesh/core/error.h"
#include "citymesh/core/log.h"
#include "cluster.h"

namespace citymesh::app {

namespace {

enum Tag : int { kRequest = 11, kReply = 12, kRankDone = 13, kArrive = 21, kGo = 22 };
/// Reply payloads other than an item.
constexpr std::int64_t kWait = -1, kDone = -2;
/// A request that reports no finished item.
constexpr std::int64_t kNothing = -1;

void sleep_ms(int ms) { std::this_thread::sleep_for(std::chrono::milliseconds(ms)); }

/// True when a message from `source` with `tag` is waiting.
bool pending(int source, int tag) {
  int flag = 0;
  MPI_Iprobe(source, tag, MPI_COMM_WORLD, &flag, MPI_STATUS_IGNORE);
  return flag != 0;
}

/// Receives one int64 from `source` with `tag`, asleep until it comes.
std::int64_t receive(int source, int tag, int poll_ms) {
  while (!pending(source, tag)) sleep_ms(poll_ms);
  std::int64_t value = 0;
  MPI_Recv(&value, 1, MPI_INT64_T, source, tag, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
  return value;
}

void send(int dest, int tag, std::int64_t value) { MPI_Send(&value, 1, MPI_INT64_T, dest, tag, MPI_COMM_WORLD); }

/// Rank 0's workers use the schedule directly; a server thread answers the other ranks.
class RootChannel final : public WorkChannel {
 public:
  RootChannel(int ranks, WorkSchedule& schedule, std::function<void(std::size_t)> on_finish)
      : local_(schedule, std::move(on_finish)), remaining_(ranks - 1), server_([this] { serve(); }) {}
  ~RootChannel() override { server_.join(); }
  std::optional<std::size_t> next(std::optional<std::size_t> finished) override { return local_.next(finished); }
  void abort() override {
    stop_ = true;
    local_.abort();
  }

 private:
  void serve() {
    try {
      while (remaining_ > 0 && !stop_) {
        MPI_Status status;
        int flag = 0;
        MPI_Iprobe(MPI_ANY_SOURCE, kRequest, MPI_COMM_WORLD, &flag, &status);
        if (flag != 0) {
          std::int64_t finished = 0;
          MPI_Recv(&finished, 1, MPI_INT64_T, status.MPI_SOURCE, kRequest, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
          const WorkReply reply = local_.poll(
              finished >= 0 ? std::optional<std::size_t>(static_cast<std::size_t>(finished)) : std::nullopt);
          send(status.MPI_SOURCE, kReply,
               reply.kind == WorkReply::Kind::item   ? static_cast<std::int64_t>(reply.item)
               : reply.kind == WorkReply::Kind::wait ? kWait
                                                     : kDone);
          continue;
        }
        MPI_Iprobe(MPI_ANY_SOURCE, kRankDone, MPI_COMM_WORLD, &flag, &status);
        if (flag != 0) {
          std::int64_t ignored = 0;
          MPI_Recv(&ignored, 1, MPI_INT64_T, status.MPI_SOURCE, kRankDone, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
          --remaining_;
          continue;
        }
        sleep_ms(1);
      }
    } catch (const std::exception& e) {
      // The root's own workers fail the same way and end the job (MPI_Abort).
      log::error("rank 0: work server stopped: {}", e.what());
      local_.abort();
    }
  }

  LocalChannel local_;
  int remaining_;  ///< ranks whose workers have not all stopped
  std::atomic<bool> stop_ = false;
  std::thread server_;
};

/// Another rank's workers: one request at a time (the mutex keeps MPI calls serialized).
class RemoteChannel final : public WorkChannel {
 public:
  ~RemoteChannel() override {
    const std::lock_guard lock(mutex_);
    if (!aborted_) send(0, kRankDone, 0);  // after a failure the job is ended instead
  }
  std::optional<std::size_t> next(std::optional<std::size_t> finished) override {
    for (;;) {
      std::int64_t reply = 0;
      {
        const std::lock_guard lock(mutex_);
        if (aborted_) throw ProcessingError("stopped: another worker failed");
        send(0, kRequest, finished ? static_cast<std::int64_t>(*finished) : kNothing);
        reply = receive(0, kReply, 0);
      }
      finished.reset();
      if (reply >= 0) return static_cast<std::size_t>(reply);
      if (reply == kDone) return std::nullopt;
      sleep_ms(20);  // nothing ready yet: the tiles it needs are in flight elsewhere
    }
  }
  void abort() override {
    const std::lock_guard lock(mutex_);
    aborted_ = true;
  }

 private:
  std::mutex mutex_;
  bool aborted_ = false;
};

class MpiCluster final : public Cluster {
 public:
  MpiCluster() {
    int provided = 0;
    MPI_Init_thread(nullptr, nullptr, MPI_THREAD_SERIALIZED, &provided);
    MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
    MPI_Comm_size(MPI_COMM_WORLD, &size_);
    if (provided < MPI_THREAD_SERIALIZED) {
      MPI_Finalize();
      throw ConfigError("the MPI library does not allow calls from several threads (MPI_THREAD_SERIALIZED)");
    }
  }
  ~MpiCluster() override { MPI_Finalize(); }

  int rank() const override { return rank_; }
  int size() const override { return size_; }

  void barrier() override {
    if (rank_ != 0) {
      send(0, kArrive, 0);
      (void)receive(0, kGo, 5);
      return;
    }
    for (int r = 1; r < size_; ++r) (void)receive(r, kArrive, 5);
    for (int r = 1; r < size_; ++r) send(r, kGo, 0);
  }

  bool same_everywhere(std::uint64_t value) override {
    // A barrier whose messages carry the values: the root compares them and sends the answer.
    const auto sent = static_cast<std::int64_t>(value);
    if (rank_ != 0) {
      send(0, kArrive, sent);
      return receive(0, kGo, 5) == 1;
    }
    bool same = true;
    for (int r = 1; r < size_; ++r) same = receive(r, kArrive, 5) == sent && same;
    for (int r = 1; r < size_; ++r) send(r, kGo, same ? 1 : 0);
    return same;
  }

  std::unique_ptr<WorkChannel> share(WorkSchedule* schedule, std::function<void(std::size_t)> on_finish) override {
    // Every rank is past any earlier sharing before this one starts: messages never mix.
    barrier();
    if (rank_ == 0) return std::make_unique<RootChannel>(size_, *schedule, std::move(on_finish));
    return std::make_unique<RemoteChannel>();
  }

  void abort(int exit_code) override {
    if (size_ > 1) MPI_Abort(MPI_COMM_WORLD, exit_code);
  }

 private:
  int rank_ = 0, size_ = 1;
};

}  // namespace

std::unique_ptr<Cluster> join_mpi() { return std::make_unique<MpiCluster>(); }
bool built_with_mpi() { return true; }

}  // namespace citymesh::app
