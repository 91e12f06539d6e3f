// SPDX-License-Identifier: MIT
// citymesh entry point.
#include <cstdio>

#include "citymesh/core/process_memory.h"
#include "command.h"

int main(int argc, char** argv) {
  // Each stage's result line shows when the stage ends, also in a file or a pipe (a cluster
  // job's log), where stdout would otherwise hold every line until the process exits.
  std::setvbuf(stdout, nullptr, _IOLBF, BUFSIZ);
  citymesh::keep_freed_memory_for_reuse();
  return citymesh::app::run_cli(argc, argv);
}
