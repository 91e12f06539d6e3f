// SPDX-License-Identifier: MIT
// Process tags of this machine for tests of what ended runs leave behind.
#pragma once

#include <sys/wait.h>
#include <unistd.h>

#include <string>

#include "citymesh/core/atomic_file.h"

namespace citymesh::test {

/// This machine's name, as process_tag() writes it ("<host>.<pid>").
inline std::string host_name() {
  const std::string tag = process_tag();
  return tag.substr(0, tag.rfind('.'));
}

/// The pid of a process that has ended: a child that exits at once, waited for (its pid is
/// free again; the system reuses pids only after going round their whole range).
inline pid_t ended_process() {
  const pid_t child = ::fork();
  if (child == 0) ::_exit(0);
  ::waitpid(child, nullptr, 0);
  return child;
}

}  // namespace citymesh::test
