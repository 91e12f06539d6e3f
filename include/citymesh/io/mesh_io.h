// SPDX-License-Identifier: MIT
// Reading a whole PLY acquisition into a Mesh (tests, tiles, small inputs; the tiler streams).
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>

#include "citymesh/core/mesh.h"
#include "citymesh/io/ply_reader.h"

namespace citymesh {

/// How far from the frame origin a used vertex may lie, in metres. Floats keep about a
/// centimetre there; farther, the coordinates are corrupt or from another CRS than the
/// frame's (read_mesh refuses them).
constexpr double kMaxFrameReach = 100'000.0;

struct MeshReadParams {
  PlyReadParams ply;
  std::uint32_t acquisition = 0;  ///< written into every TriangleId
  /// Local frame origin; by default the first vertex rounded down to whole metres.
  std::optional<Vec3d> origin;
  /// Triangles with less than this doubled area (m^2), measured on the file's double
  /// coordinates, are degenerate: dropped and counted.
  double min_doubled_area = kMinDoubledArea;
  /// A file with no face element (a point cloud) is an InputError (check_has_faces).
  bool require_faces = false;
};

struct MeshReadResult {
  Mesh mesh;
  PlyReadStats stats;
  std::uint64_t zero_area_dropped = 0;
};

/// Appends `chunk`'s vertices to `mesh`, moved into its frame (mesh.origin).
void append_vertex_chunk(Mesh& mesh, const PlyVertexChunk& chunk);

/// Throws InputError naming `file`, `face` and vertex `v` when `local`, its position in the
/// frame whose origin is `origin`, lies beyond kMaxFrameReach (its float position has lost its
/// millimetres, or is infinite: a corrupt first vertex, which sets the origin, or an
/// acquisition in another CRS than the first).
void check_frame_reach(const std::filesystem::path& file, std::uint64_t face, std::uint64_t v, const Vec3f& local,
                       const Vec3d& origin);

/// Reads every vertex and triangle of `path`. Throws InputError naming the file and row, also
/// when a vertex a face uses lies beyond kMaxFrameReach of the origin.
MeshReadResult read_mesh(const std::filesystem::path& path, const MeshReadParams& params = {});

}  // namespace citymesh
