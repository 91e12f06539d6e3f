// SPDX-License-Identifier: MIT
// `citymesh mesh`: real scan-ordered points -> a mesh by sensor topology.
#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include <iostream>

#include "citymesh/core/error.h"
#include "citymesh/io/ply_reader.h"
#include "citymesh/io/ply_writer.h"
#include "citymesh/scan/real_scans.h"
#include "command.h"

namespace citymesh::app {

namespace {

class MeshCommand final : public Command {
 public:
  std::string_view name() const override { return "mesh"; }
  std::string_view summary() const override { return "mesh real scan-ordered points (profiler lines or spinning frames)"; }

  void declare(CLI::App& app) override {
    app.add_option("files", files_,
                   "PLY point files in acquisition order (profiler: consecutive chunks of one drive; spinning: frames "
                   "of one drive, each meshed on its own, all in one mesh)")
        ->required()
        ->check(CLI::ExistingFile);
    app.add_option("--out", out_, "mesh PLY to write")->required();
    app.add_option("--layout", layout_, "auto (from the properties), profiler (angle wraps per line), spinning (ring x column)")
        ->check(CLI::IsMember({"auto", "profiler", "spinning"}));
    app.add_option("--echo", echo_, "profiler: which echo of a multi-echo pulse to mesh")->check(CLI::IsMember({"first", "last"}));
    app.add_option("--band-lines", band_lines_,
                   "profiler: scan lines meshed at a time, at least 2 (memory: ~40 bytes per cell of a band; 0: "
                   "about a million cells; the output does not depend on it)")
        ->check(CLI::Range(std::size_t{0}, std::size_t{1} << 24));
    app.add_option("--max-edge-base", meshing_.max_edge_base, "metres")->check(CLI::Range(0.0, 100.0));
    app.add_option("--max-edge-per-metre", meshing_.max_edge_per_metre, "extra edge length per metre of range")
        ->check(CLI::Range(0.0, 10.0));
    app.add_option("--max-depth-jump", meshing_.max_depth_jump, "largest relative range difference in a triangle")
        ->check(CLI::Range(0.0, 10.0));
    app.add_option("--max-incidence", meshing_.max_incidence_deg, "degrees between normal and line of sight")
        ->check(CLI::Range(1.0, 90.0));
    app.footer(
        "Examples:\n  citymesh mesh sample_riegl_18_0{1,2,3,4,5}.ply --out riegl_mesh.ply\n"
        "  citymesh mesh ouster_os1_128_frame1795.ply --out frame1795_mesh.ply\n"
        "  citymesh mesh ouster_os1_128_frame179{5,6,7}.ply --out drive.ply   # one pass of three frames");
  }

  void run() override {
    std::vector<std::filesystem::path> paths(files_.begin(), files_.end());
    const std::string layout = layout_ == "auto" ? detect(paths.front()) : layout_;
    if (layout == "profiler") {
      mesh_profiler_drive(paths);
      return;
    }
    mesh_spinning_frames(paths);
  }

 private:
  /// A profiler drive's grid, meshed and written a band of scan lines at a time: its memory
  /// does not grow with the drive's length. The same bytes as meshing the whole grid at once.
  void mesh_profiler_drive(const std::vector<std::filesystem::path>& paths) const {
    ProfilerGridParams p;
    p.echo = echo_ == "last" ? ProfilerGridParams::Echo::last : ProfilerGridParams::Echo::first;
    std::unique_ptr<PlySpoolWriter> out;
    SensorBand where;
    SensorMeshStats stats;
    std::int64_t cells = 0;
    std::uint64_t triangles = 0;
    // Bands of about a million cells by default (some 40 bytes each with the mesher's arrays).
    const ProfilerBandSize size{band_lines_};
    const ProfilerGridShape shape = for_each_profiler_band(paths, p, size, [&](const SensorGrid& band) {
      // Row 0 repeats the band before's last row: its cells were counted there.
      const auto from = static_cast<std::ptrdiff_t>(where.carried.empty() ? 0 : band.cols);
      cells +=
          std::count(band.valid.begin() + std::min<std::ptrdiff_t>(from, std::ssize(band.valid)), band.valid.end(), 1);
      const SensorMeshResult r = mesh_sensor_band(band, meshing_, 0, where);
      stats += r.stats;
      triangles += r.mesh.triangle_count();
      if (r.mesh.vertex_count() == 0) return;  // then no triangle either: each has a corner in a new row
      append(out, r.mesh, {});
    });
    if (out == nullptr) {
      Mesh empty;
      empty.origin = shape.origin;
      write_mesh_ply(out_, empty);
    } else {
      out->commit();
    }
    std::cout << fmt::format("{}: profiler layout, grid {} x {}, {} points, {} triangles\n", out_, shape.rows,
                             shape.cols, cells, triangles);
    print_rejected(stats);
  }

  /// Appends a mesh whose triangles name vertices by their ids in the whole output (those
  /// before it included) to `out`, made at the first mesh with that mesh's columns.
  void append(std::unique_ptr<PlySpoolWriter>& out, const Mesh& mesh, const std::filesystem::path& source) const {
    const MeshVertexRows rows = mesh_vertex_rows(mesh, 0, mesh.vertex_count());
    const PlyWriteInput part{rows.positions, {}, rows.columns(), {}, {std::string(kPlyComment)}};
    if (out == nullptr) out = std::make_unique<PlySpoolWriter>(out_, part);
    try {
      out->add_vertices(part);
    } catch (const ProcessingError& e) {
      if (source.empty()) throw;
      throw InputError(fmt::format("{}: its points carry other properties than the frames before it ({})",
                                   source.string(), e.what()));
    }
    out->add_faces({{}, mesh.triangles, {}, {}, {}});
  }

  /// Each frame meshed on its own grid, the frames of one drive in one mesh (as the simulator
  /// writes a spinning pass: its turns overlap, and the mosaic keeps one layer of them). The
  /// frames go to the file one by one: a drive of thousands of frames never is in memory.
  void mesh_spinning_frames(const std::vector<std::filesystem::path>& paths) const {
    std::unique_ptr<PlySpoolWriter> out;
    SensorMeshStats stats;
    std::int64_t cells = 0;
    std::uint64_t triangles = 0;
    for (const std::filesystem::path& path : paths) {
      const SensorGrid grid = spinning_grid(path);
      SensorMeshResult r = mesh_sensor_grid(grid, meshing_);
      const auto first = static_cast<std::uint32_t>(out == nullptr ? 0 : out->vertices());
      for (Triangle& t : r.mesh.triangles) t = {t[0] + first, t[1] + first, t[2] + first};
      append(out, r.mesh, path);
      cells += std::count(grid.valid.begin(), grid.valid.end(), 1);
      triangles += r.mesh.triangle_count();
      stats += r.stats;
    }
    out->commit();
    std::cout << fmt::format("{}: spinning layout, {} frame(s), {} points, {} triangles\n", out_, paths.size(), cells,
                             triangles);
    print_rejected(stats);
  }

  static void print_rejected(const SensorMeshStats& s) {
    std::cout << fmt::format("  rejected: {} long edges, {} depth jumps, {} grazing (of {} candidates)\n",
                             s.rejected_long_edge, s.rejected_depth_jump, s.rejected_grazing, s.candidates);
  }

  static std::string detect(const std::filesystem::path& file) {
    PlyReadParams read;
    read.require_sensor_origin = false;
    const PlyElement* v = PlyReader(file, read).header().find("vertex");
    if (v->find("ring") != nullptr && v->find("column") != nullptr) return "spinning";
    if (v->find("theta") != nullptr) return "profiler";
    throw InputError(fmt::format("{}: cannot tell the scan layout (no theta, nor ring and column); use --layout",
                                 file.string()));
  }

  std::vector<std::string> files_;
  std::string out_;
  std::string layout_ = "auto";
  std::string echo_ = "first";
  std::size_t band_lines_ = 0;  ///< 0: about a million cells
  SensorMeshingParams meshing_;
};

}  // namespace

std::unique_ptr<Command> make_mesh_command() { return std::make_unique<MeshCommand>(); }

}  // namespace citymesh::app
