// SPDX-License-Identifier: MIT
// citymesh entry point.
#include "command.h"

int main(int argc, char** argv) { return citymesh::app::run_cli(argc, argv); }
