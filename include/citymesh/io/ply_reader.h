// SPDX-License-Identifier: MIT
// Streaming PLY reader: bounded chunks of vertices and triangulated faces in file order, so
// that an acquisition far larger than memory can be read once, front to back.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "citymesh/core/mesh.h"
#include "citymesh/io/ply.h"

namespace citymesh {

struct PlyReadParams {
  /// Property names of the per-vertex sensor position.
  std::array<std::string, 3> sensor_origin_names{"x_origin", "y_origin", "z_origin"};
  /// Names tried in order for the per-vertex time.
  std::vector<std::string> time_names{"gps_time", "GPS_time", "time"};
  std::string intensity_name = "intensity";
  /// Further vertex properties to return, as doubles, in PlyVertexChunk::extras (in this
  /// order); a missing one is an input error.
  std::vector<std::string> extra_vertex_properties;
  /// Scalar face properties to return, as doubles, in PlyFaceChunk::extras (one value per
  /// triangle, repeated for the triangles of a split polygon); a missing one is an input error.
  std::vector<std::string> extra_face_properties;
  /// When true, a file without the sensor-origin properties is an input error.
  bool require_sensor_origin = true;
  /// Rows per chunk; bounds the reader's memory whatever the file size.
  std::size_t chunk_rows = 1 << 16;
};

/// Which optional vertex attributes the file provides.
struct PlyVertexLayout {
  bool has_sensor_origin = false;
  bool has_time = false;
  bool has_intensity = false;
  bool has_color = false;
  std::string time_name;  ///< the property actually used for time
};

/// Consecutive vertices [first, first + size). Positions are absolute (header offset applied).
/// Optional attributes are empty when the file lacks them.
struct PlyVertexChunk {
  std::uint64_t first = 0;
  std::vector<Vec3d> positions;
  std::vector<Vec3d> sensor_positions;
  std::vector<double> times;
  std::vector<float> intensities;
  std::vector<Rgb8> colors;
  std::vector<std::vector<double>> extras;  ///< one column per PlyReadParams::extra_vertex_properties
  void clear();
};

/// The farthest a point may lie from its sensor position, and the longest edge a face may
/// have, in metres. No mobile-mapping lidar reaches this far, so beyond it the coordinates are
/// corrupt; and a face or a line of sight that long would have the tiler and the empty-space
/// grids visit every cell between its ends (a run that never ends).
constexpr double kMaxReach = 1000.0;

/// Throws InputError naming `file` and `face` when an edge of the triangle (a, b, c) is longer
/// than kMaxReach (checked where the faces meet their vertices: the tiler and read_mesh).
void check_face_extent(const std::filesystem::path& file, std::uint64_t face, const Vec3d& a, const Vec3d& b,
                       const Vec3d& c);

/// The same check for a caller that already has `corners`, the box of a, b and c: no edge is
/// longer than the box's diagonal, so the edges are measured only when the diagonal passes
/// kMaxReach (the tiler builds the box anyway to place the face).
inline void check_face_extent(const std::filesystem::path& file, std::uint64_t face, const Box3d& corners,
                              const Vec3d& a, const Vec3d& b, const Vec3d& c) {
  const Vec3d diagonal = corners.max - corners.min;
  if (!(dot(diagonal, diagonal) <= kMaxReach * kMaxReach)) check_face_extent(file, face, a, b, c);
}

/// Throws InputError naming `file` and `face` when `triangle` uses a vertex beyond the first
/// `read` (a reader that streams faces as they come needs the vertex element first).
void check_vertices_read(const std::filesystem::path& file, std::uint64_t face, const Triangle& triangle,
                         std::uint64_t read);

/// Throws InputError naming `file` when `header` has no face element: a point cloud given
/// where a mesh is needed (an acquisition), which would otherwise run through as a pass of no
/// triangle and fail at the end on an empty output.
void check_has_faces(const std::filesystem::path& file, const PlyHeader& header);

/// Triangles from consecutive faces; polygons are fan-triangulated, faces that repeat a vertex
/// are dropped (and counted). Each triangle keeps its face index and fan number.
struct PlyFaceChunk {
  std::uint64_t first_face = 0;
  std::vector<Triangle> triangles;
  std::vector<std::uint64_t> faces;
  std::vector<std::uint32_t> fans;
  std::vector<std::vector<double>> extras;  ///< one column per PlyReadParams::extra_face_properties
  void clear();
};

struct PlyReadStats {
  std::uint64_t vertices = 0;
  std::uint64_t faces = 0;
  std::uint64_t triangles = 0;
  std::uint64_t polygons_split = 0;    ///< faces with more than three vertices
  std::uint64_t degenerate_dropped = 0;  ///< faces or fan triangles with < 3 distinct vertices
  std::uint64_t bytes = 0;
};

class PlyReader {
 public:
  /// Opens the file and parses its header. Throws InputError naming the file.
  PlyReader(std::filesystem::path path, PlyReadParams params = {});
  ~PlyReader();
  PlyReader(const PlyReader&) = delete;
  PlyReader& operator=(const PlyReader&) = delete;

  [[nodiscard]] const PlyHeader& header() const;
  [[nodiscard]] const PlyVertexLayout& vertex_layout() const;
  [[nodiscard]] const std::filesystem::path& path() const;
  [[nodiscard]] std::uint64_t vertex_count() const;
  [[nodiscard]] std::uint64_t face_count() const;

  enum class ChunkKind { vertices, faces, end };
  /// Reads the next chunk in file order into `vertices` or `faces` (the other is left alone).
  /// Elements other than vertex and face are skipped. Returns ChunkKind::end after the last
  /// element. Throws InputError naming the file, element and row on malformed data.
  ChunkKind next(PlyVertexChunk& vertices, PlyFaceChunk& faces);

  [[nodiscard]] const PlyReadStats& stats() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace citymesh
