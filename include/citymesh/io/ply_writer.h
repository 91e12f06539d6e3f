// SPDX-License-Identifier: MIT
// Binary little-endian PLY output with double coordinates and any extra per-vertex or per-face
// columns (the provenance properties source_acq/source_face use them). Written atomically.
#pragma once

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <variant>
#include <vector>

#include "citymesh/core/mesh.h"

namespace citymesh {

/// One named column of values, one per vertex or per face; its element type picks the PLY type.
struct PlyColumn {
  using Values = std::variant<std::span<const std::int8_t>, std::span<const std::uint8_t>,
                              std::span<const std::int16_t>, std::span<const std::uint16_t>,
                              std::span<const std::int32_t>, std::span<const std::uint32_t>,
                              std::span<const float>, std::span<const double>>;
  std::string name;
  Values values;
};

struct PlyWriteInput {
  std::span<const Vec3d> positions;  ///< absolute, written as double x, y, z
  std::span<const Triangle> triangles;
  std::vector<PlyColumn> vertex_columns;
  std::vector<PlyColumn> face_columns;
  std::vector<std::string> comments;
};

/// Writes `input` to `path` (temporary name, fsync, rename). Throws ProcessingError when a
/// column's size disagrees with its element, OutputError when the file cannot be written.
void write_ply(const std::filesystem::path& path, const PlyWriteInput& input);

/// Writes a mesh in the input format of citymesh (DESIGN §3): x, y, z and x_origin, y_origin,
/// z_origin as double, gps_time, intensity and colour when present, plus `face_columns`.
void write_mesh_ply(const std::filesystem::path& path, const Mesh& mesh,
                    std::vector<PlyColumn> face_columns = {});

}  // namespace citymesh
