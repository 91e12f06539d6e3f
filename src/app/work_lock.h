// SPDX-License-Identifier: MIT
// One run at a time in a work folder: two full runs writing the same folders would swap in
// each other's half-written outputs.
#pragma once

#include <filesystem>

namespace citymesh::app {

/// A lock on <work>/run.lock, held for the object's life (flock: released by the kernel when
/// the process ends, however it ends). `exclusive`: a full run or a merge, which write the
/// outputs; otherwise shared, as the subsets of one run (`--subset i/N`) share a work folder
/// and write only their tiles. Throws OutputError naming the folder and the holder when
/// another process holds it in a conflicting way, or when the lock file cannot be made; a
/// file system that cannot lock (some network mounts) gets a warning, and no lock.
class WorkFolderLock {
 public:
  WorkFolderLock(const std::filesystem::path& work, bool exclusive);
  ~WorkFolderLock();
  WorkFolderLock(const WorkFolderLock&) = delete;
  WorkFolderLock& operator=(const WorkFolderLock&) = delete;

 private:
  int fd_ = -1;
};

}  // namespace citymesh::app
