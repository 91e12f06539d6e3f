// SPDX-License-Identifier: MIT
#include "cluster.h"

#include <fmt/format.h>

#include <algorithm>
#include <cstdlib>
#include <string>

#include "citymesh/core/error.h"

namespace citymesh::app {

/// Defined in cluster_mpi.cpp, or as nothing in cluster_no_mpi.cpp.
std::unique_ptr<Cluster> join_mpi();

namespace {

class SingleProcess final : public Cluster {
 public:
  int rank() const override { return 0; }
  int size() const override { return 1; }
  void barrier() override {}
  bool same_everywhere(std::uint64_t) override { return true; }
  std::unique_ptr<WorkChannel> share(WorkSchedule* schedule, std::function<void(std::size_t)> on_finish) override {
    return std::make_unique<LocalChannel>(*schedule, std::move(on_finish));
  }
  void abort(int) override {}
};

/// The rank count an MPI launcher announced in the environment, or 0 when none started us.
int launcher_ranks() {
  for (const char* name : {"OMPI_COMM_WORLD_SIZE", "PMIX_SIZE", "PMI_SIZE"}) {
    if (const char* value = std::getenv(name)) return std::max(1, std::atoi(value));
  }
  // srun with PMIx sets the rank only.
  return std::getenv("PMIX_RANK") != nullptr ? 1 : 0;
}

}  // namespace

std::unique_ptr<Cluster> single_process() { return std::make_unique<SingleProcess>(); }

std::unique_ptr<Cluster> join_cluster() {
  const int ranks = launcher_ranks();
  if (ranks == 0) return single_process();
  if (std::unique_ptr<Cluster> mpi = join_mpi()) return mpi;
  if (ranks > 1) {
    throw ConfigError(
        fmt::format("started as one of {} MPI ranks, but this citymesh was built without MPI "
                    "(install libopenmpi-dev and rebuild), or use --subset i/N",
                    ranks));
  }
  return single_process();
}

}  // namespace citymesh::app
