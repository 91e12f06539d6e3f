// SPDX-License-Identifier: MIT
// 3D Tiles export throughput and size: the simulated street of the change benchmark (all
// epochs together stand in for a ~300 k-triangle output, one source acquisition per epoch)
// written as Draco-compressed and as plain glb tiles; and the mapping of its vertices to the
// tiles' local frame, exact against interpolated (map_to_local_frame).
//   export_bench [--length 30] [--epochs 7] [--tile 10]
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>

#include "bench_scene.h"
#include "citymesh/core/process_memory.h"
#include "citymesh/core/stopwatch.h"
#include "citymesh/geo/local_frame_map.h"
#include "citymesh/tiles3d/export.h"

using namespace citymesh;

namespace {

struct Output {
  Mesh mesh;
  std::vector<std::int32_t> source;
};

Output concatenate(const bench::BenchScene& scene) {
  Output out;
  out.mesh.origin = scene.meshes.front().origin;
  for (std::size_t k = 0; k < scene.meshes.size(); ++k) {
    const Mesh& m = scene.meshes[k];
    const auto base = static_cast<std::uint32_t>(out.mesh.positions.size());
    out.mesh.positions.insert(out.mesh.positions.end(), m.positions.begin(), m.positions.end());
    out.mesh.intensities.insert(out.mesh.intensities.end(), m.intensities.begin(), m.intensities.end());
    for (const Triangle& t : m.triangles) out.mesh.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
    out.source.insert(out.source.end(), m.triangle_count(), static_cast<std::int32_t>(k));
  }
  if (out.mesh.intensities.size() != out.mesh.positions.size()) out.mesh.intensities.clear();
  out.mesh.triangle_ids.resize(out.mesh.triangles.size());
  return out;
}

/// The output's vertices mapped to the local frame on one thread, exactly and by
/// map_to_local_frame: the seconds of each and how many coordinates round otherwise.
void print_mapping_speed(const Mesh& mesh, const Crs& crs) {
  std::vector<Vec3d> world;
  Box3d box;
  for (std::size_t v = 0; v < mesh.vertex_count(); ++v) {
    world.push_back(mesh.world_position(v));
    box.extend(world.back());
  }
  const EnuFrame frame(crs.to_geodetic((box.min + box.max) * 0.5));
  Stopwatch exact_clock;
  std::vector<Vec3f> exact;
  for (const Vec3d& p : world) exact.push_back(exact_local_position(crs, frame, p));
  const double exact_seconds = exact_clock.seconds();
  Stopwatch fast_clock;
  const std::vector<Vec3f> fast = map_to_local_frame(world, crs, frame);
  const double fast_seconds = fast_clock.seconds();
  std::size_t differing = 0;
  float largest = 0;
  for (std::size_t v = 0; v < world.size(); ++v) {
    for (int axis = 0; axis < 3; ++axis) {
      differing += fast[v][axis] != exact[v][axis];
      largest = std::max(largest, std::abs(fast[v][axis] - exact[v][axis]));
    }
  }
  fmt::print(
      "local frame: {} vertices on one thread, exact {:.3f} s ({:.0f} ns each), interpolated {:.3f} s ({:.0f} ns "
      "each, {:.1f}x); {} of {} coordinates round otherwise, by {:.1e} m at most\n",
      world.size(), exact_seconds, exact_seconds / double(world.size()) * 1e9, fast_seconds,
      fast_seconds / double(world.size()) * 1e9, exact_seconds / fast_seconds, differing, 3 * world.size(),
      double(largest));
}

double arg(int argc, char** argv, const char* name, double fallback) {
  for (int i = 1; i + 1 < argc; ++i)
    if (std::strcmp(argv[i], name) == 0) return std::stod(argv[i + 1]);
  return fallback;
}

}  // namespace

int main(int argc, char** argv) {
  keep_freed_memory_for_reuse();  // as the citymesh binary does
  const auto length = static_cast<float>(arg(argc, argv, "--length", 30));
  const int epochs = static_cast<int>(arg(argc, argv, "--epochs", 7));
  const double tile = arg(argc, argv, "--tile", 10);
  const Output output = concatenate(bench::simulated_street(length, epochs));
  const Crs crs = Crs::parse("EPSG:2154", {VerticalDatum::Kind::ellipsoidal, 0.0});
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "citymesh_export_bench";
  fmt::print("export of {} triangles ({} vertices, {} acquisitions), leaves of {} m\n", output.mesh.triangle_count(),
             output.mesh.vertex_count(), epochs, tile);
  print_mapping_speed(output.mesh, crs);
  std::uint64_t bytes[2] = {0, 0};
  for (const bool draco : {true, false}) {
    TilesetExportParams params;
    params.dir = dir / (draco ? "draco" : "plain");
    params.grid = {.tile_size = tile, .halo = 0.0, .origin = {0.0, 0.0}};
    params.draco = draco;
    for (int k = 0; k < epochs; ++k) params.acquisitions.push_back({fmt::format("epoch {}", k), "2026-01-01T00:00:00Z"});
    const TilesetExportStats s = export_tileset({output.mesh, output.source, crs}, params);
    const double per_leaf = static_cast<double>(s.glb_bytes) / static_cast<double>(s.leaf_triangles);
    const double per_content = static_cast<double>(s.glb_bytes) / static_cast<double>(s.all_triangles);
    fmt::print("{:<6} {:7.3f} s, {:6.2f} M input triangles/s | {} tiles ({} leaves, {} levels), {} triangles in all "
               "contents | {:.1f} MiB: {:.2f} bytes per content triangle, {:.2f} per input triangle{}\n",
               draco ? "draco" : "plain", s.seconds, static_cast<double>(s.leaf_triangles) / s.seconds / 1e6, s.tiles,
               s.leaves, s.levels, s.all_triangles, static_cast<double>(s.glb_bytes) / (1 << 20), per_content, per_leaf,
               draco ? fmt::format(" | {}-bit positions, {:.2f} mm step", s.position_bits, s.quantization_step * 1e3)
                     : std::string());
    bytes[draco ? 0 : 1] = s.glb_bytes;
  }
  fmt::print("Draco tiles are {:.1f}x smaller than plain glb\n", static_cast<double>(bytes[1]) / static_cast<double>(bytes[0]));
  fmt::print("peak memory {:.0f} MiB\n", static_cast<double>(peak_resident_bytes()) / (1 << 20));
  std::filesystem::remove_all(dir);
  return 0;
}
