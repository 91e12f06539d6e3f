// SPDX-License-Identifier: MIT
// The processes of one run: this process alone, or the ranks of an MPI job (mpirun, srun).
// MPI stays inside cluster_mpi.cpp; the same binary runs without it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>

#include "work_schedule.h"

namespace citymesh::app {

class Cluster {
 public:
  virtual ~Cluster() = default;
  [[nodiscard]] virtual int rank() const = 0;
  [[nodiscard]] virtual int size() const = 0;
  [[nodiscard]] bool root() const { return rank() == 0; }

  /// Returns once every rank has called it. Ranks wait asleep, so an idle rank leaves its
  /// cores to the others.
  virtual void barrier() = 0;

  /// True on every rank when every rank gave the same value, false on every rank otherwise.
  /// Collective.
  virtual bool same_everywhere(std::uint64_t value) = 0;

  /// Shares the root's `schedule` (the other ranks pass nullptr) with the worker threads of
  /// every rank: rank 0 hands out items, the others pull. Collective. `on_finish` runs on the
  /// root for every finished item. The channel's destructor returns once every rank's workers
  /// have stopped.
  virtual std::unique_ptr<WorkChannel> share(WorkSchedule* schedule, std::function<void(std::size_t)> on_finish) = 0;

  /// Ends every rank after an error on this one (this process alone: nothing).
  virtual void abort(int exit_code) = 0;
};

/// This process alone.
std::unique_ptr<Cluster> single_process();

/// The MPI job this process was started in, when an MPI launcher started it (OpenMPI's
/// mpirun or srun with PMIx); otherwise this process alone. Throws ConfigError when a launcher
/// started several ranks but this build has no MPI.
std::unique_ptr<Cluster> join_cluster();

/// Whether this build can join MPI jobs.
bool built_with_mpi();

}  // namespace citymesh::app
