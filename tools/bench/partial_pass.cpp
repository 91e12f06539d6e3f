// SPDX-License-Identifier: MIT
// Writes the part of an acquisition whose triangles have their centroid inside an x-y box (in
// the file's coordinates): a later pass over one district, for tools/bench/append.sh.
// Usage: partial_pass IN.ply OUT.ply XMIN YMIN XMAX YMAX
#include <fmt/format.h>

#include <exception>
#include <string>

#include "citymesh/io/mesh_io.h"
#include "citymesh/io/ply_writer.h"

using namespace citymesh;

int main(int argc, char** argv) {
  if (argc != 7) {
    fmt::print(stderr, "usage: partial_pass IN.ply OUT.ply XMIN YMIN XMAX YMAX\n");
    return 1;
  }
  try {
    const Mesh whole = read_mesh(argv[1]).mesh;
    const double x0 = std::stod(argv[3]), y0 = std::stod(argv[4]), x1 = std::stod(argv[5]), y1 = std::stod(argv[6]);
    Mesh part = whole;  // every vertex stays: the writer keeps unused ones, the tiler skips them
    part.triangles.clear();
    part.triangle_ids.clear();
    for (std::size_t t = 0; t < whole.triangle_count(); ++t) {
      const auto [a, b, c] = whole.corners(t);
      const Vec3d centroid = whole.origin + (a + b + c) / 3.0;
      if (centroid.x < x0 || centroid.x >= x1 || centroid.y < y0 || centroid.y >= y1) continue;
      part.triangles.push_back(whole.triangles[t]);
      part.triangle_ids.push_back(whole.triangle_ids[t]);
    }
    write_mesh_ply(argv[2], part);
    fmt::print("{}: {} of {} triangles\n", argv[2], part.triangle_count(), whole.triangle_count());
  } catch (const std::exception& e) {
    fmt::print(stderr, "partial_pass: {}\n", e.what());
    return 2;
  }
  return 0;
}
