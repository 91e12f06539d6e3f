// SPDX-License-Identifier: MIT
// citymesh entry point.
#include "citymesh/core/process_memory.h"
#include "command.h"

int main(int argc, char** argv) {
  citymesh::keep_freed_memory_for_reuse();
  return citymesh::app::run_cli(argc, argv);
}
