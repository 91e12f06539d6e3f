// SPDX-License-Identifier: MIT
// Binary little-endian PLY output with double coordinates and any extra per-vertex or per-face
// columns (the provenance properties source_acq/source_face use them). Written atomically.
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
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

/// A PLY written in parts, for an output too large to hold at once: the counts first (the
/// header needs them), then the vertices chunk by chunk, then the faces. Written as
/// write_ply writes: nothing appears under the path unless commit() is reached.
class PlyStreamWriter {
 public:
  /// `layout`'s columns name the vertex and face properties and their types (its rows are not
  /// read); `vertices` and `faces` rows are to come. Throws OutputError naming the file.
  PlyStreamWriter(const std::filesystem::path& path, const PlyWriteInput& layout, std::uint64_t vertices,
                  std::uint64_t faces);
  ~PlyStreamWriter();
  PlyStreamWriter(const PlyStreamWriter&) = delete;
  PlyStreamWriter& operator=(const PlyStreamWriter&) = delete;
  /// Appends `chunk`'s vertex rows: its positions and vertex columns (laid out as the
  /// layout's). Throws ProcessingError when they do not fit the header.
  void add_vertices(const PlyWriteInput& chunk);
  /// Appends `chunk`'s face rows (its triangles and face columns), once every vertex is in.
  void add_faces(const PlyWriteInput& chunk);
  /// Throws ProcessingError when fewer rows came than the header announced.
  void commit();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// A PLY written in parts whose counts are known only at the end (a drive meshed frame by
/// frame): vertex and face rows may come in any order, faces naming vertices by their index
/// in the whole file. Both are spooled to scratch files beside the output (unlinked at once:
/// a killed process leaves nothing) and copied behind the header by commit(), which writes as
/// write_ply writes. Memory: one chunk at a time.
class PlySpoolWriter {
 public:
  /// `layout`'s columns name the vertex and face properties and their types (its rows are not
  /// read). Throws OutputError naming the file when no scratch file can be made beside it.
  PlySpoolWriter(const std::filesystem::path& path, const PlyWriteInput& layout);
  ~PlySpoolWriter();
  PlySpoolWriter(const PlySpoolWriter&) = delete;
  PlySpoolWriter& operator=(const PlySpoolWriter&) = delete;
  /// Appends `chunk`'s vertex rows. Throws ProcessingError when its columns are not the layout's.
  void add_vertices(const PlyWriteInput& chunk);
  /// Appends `chunk`'s face rows. Throws ProcessingError when its columns are not the layout's.
  void add_faces(const PlyWriteInput& chunk);
  /// The vertex rows added so far: the index the next chunk's first vertex takes.
  [[nodiscard]] std::uint64_t vertices() const;
  /// Writes the file. Throws ProcessingError when a face uses a vertex that never came.
  void commit();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Writes `input` to `path` (temporary name, fsync, rename). Throws ProcessingError when a
/// column's size disagrees with its element, OutputError when the file cannot be written.
void write_ply(const std::filesystem::path& path, const PlyWriteInput& input);

/// The comment every PLY citymesh writes carries.
inline constexpr std::string_view kPlyComment = "written by citymesh";

/// Which optional vertex attributes rows carry.
struct MeshVertexAttributes {
  bool sensors = false, times = false, intensities = false, colors = false;
};

/// Vertex rows in the input format of citymesh (DESIGN §3): x, y, z and x_origin, y_origin,
/// z_origin as double, gps_time, intensity and colour, those `has` names.
class MeshVertexRows {
 public:
  explicit MeshVertexRows(const MeshVertexAttributes& has);
  /// Appends a row; the attributes the rows do not carry are ignored.
  void add(const Vec3d& position, const Vec3d& sensor, double time, float intensity, Rgb8 color);
  /// The columns other than x, y, z over the rows added so far (every carried one, even empty).
  [[nodiscard]] std::vector<PlyColumn> columns() const;

  std::vector<Vec3d> positions;  ///< absolute: the x, y, z of each row

 private:
  MeshVertexAttributes has_;
  std::vector<double> sx_, sy_, sz_, times_;
  std::vector<float> intensities_;
  std::vector<std::uint8_t> red_, green_, blue_;
};

/// The optional vertex attributes `mesh` carries.
MeshVertexAttributes vertex_attributes(const Mesh& mesh);

/// Rows of `mesh`'s vertices [begin, end), absolute, with the attributes it carries.
MeshVertexRows mesh_vertex_rows(const Mesh& mesh, std::size_t begin, std::size_t end);

/// Writes a mesh in the input format of citymesh (DESIGN §3): x, y, z and x_origin, y_origin,
/// z_origin as double, gps_time, intensity and colour when present, plus `face_columns`.
void write_mesh_ply(const std::filesystem::path& path, const Mesh& mesh,
                    std::vector<PlyColumn> face_columns = {});

}  // namespace citymesh
