// SPDX-License-Identifier: MIT
// Builds without MPI: every run is one process.
#include "cluster.h"

namespace citymesh::app {

std::unique_ptr<Cluster> join_mpi() { return nullptr; }
bool built_with_mpi() { return false; }

}  // namespace citymesh::app
