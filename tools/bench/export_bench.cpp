// SPDX-License-Identifier: MIT
// 3D Tiles export throughput and size: the simulated street of the change benchmark (all
// epochs together stand in for a ~300 k-triangle output, one source acquisition per epoch)
// written as Draco-compressed and as plain glb tiles.
//   export_bench [--length 30] [--epochs 7] [--tile 10]
#include <fmt/format.h>

#include <cstring>
#include <string>

#include "bench_scene.h"
#include "citymesh/core/process_memory.h"
#include "citymesh/core/stopwatch.h"
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
