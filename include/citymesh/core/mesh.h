// SPDX-License-Identifier: MIT
// The data model shared by every stage: acquisitions, triangle ids and in-memory meshes.
#pragma once

#include <array>
#include <cmath>
#include <compare>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "citymesh/core/time.h"
#include "citymesh/core/vec.h"

namespace citymesh {

/// One mobile-mapping pass: its position in the config (the index every output refers to),
/// its date and the file it was read from.
struct Acquisition {
  std::uint32_t index = 0;
  TimePoint date{};
  std::filesystem::path path;
  bool withdrawn = false;  ///< read as an empty mesh (its file is not opened)
};

/// Global identity of a triangle, kept by every stage and written to every output.
/// `face` is the face index in the acquisition's file; `fan` numbers the triangles that
/// fan triangulation made from one polygon (0 for a face that already was a triangle).
struct TriangleId {
  std::uint32_t acquisition = 0;
  std::uint32_t fan = 0;
  std::uint64_t face = 0;

  friend constexpr auto operator<=>(const TriangleId& a, const TriangleId& b) {
    if (auto c = a.acquisition <=> b.acquisition; c != 0) return c;
    if (auto c = a.face <=> b.face; c != 0) return c;
    return a.fan <=> b.fan;
  }
  friend constexpr bool operator==(const TriangleId&, const TriangleId&) = default;
};

struct Rgb8 {
  std::uint8_t r = 0, g = 0, b = 0;
  friend constexpr bool operator==(const Rgb8&, const Rgb8&) = default;
};

using Triangle = std::array<std::uint32_t, 3>;

/// A triangle mesh in a local frame. Positions are floats relative to `origin` (a point in the
/// project CRS, in metres): city coordinates are ~10^6 m, far beyond float precision, while
/// offsets within a tile or street stay well under a millimetre of float error.
/// Optional attributes are either empty or have one value per vertex.
struct Mesh {
  Vec3d origin;
  std::vector<Vec3f> positions;
  std::vector<Vec3f> sensor_positions;  ///< where the sensor stood when it measured the vertex
  std::vector<double> times;            ///< per-vertex time (seconds, the file's time base)
  std::vector<float> intensities;
  std::vector<Rgb8> colors;
  std::vector<Triangle> triangles;
  std::vector<TriangleId> triangle_ids;  ///< one per triangle

  [[nodiscard]] std::size_t vertex_count() const { return positions.size(); }
  [[nodiscard]] std::size_t triangle_count() const { return triangles.size(); }
  [[nodiscard]] bool has_sensor_positions() const { return !sensor_positions.empty(); }
  /// Absolute position in the project CRS.
  [[nodiscard]] Vec3d world_position(std::size_t v) const { return origin + Vec3d(positions[v]); }
  /// The corners of triangle t in the local frame, as doubles for exact-in-intent geometry.
  [[nodiscard]] std::array<Vec3d, 3> corners(std::size_t t) const {
    const Triangle& tri = triangles[t];
    return {Vec3d(positions[tri[0]]), Vec3d(positions[tri[1]]), Vec3d(positions[tri[2]])};
  }
  /// Triangle t's viewpoint in the local frame: the barycentre of its corners' sensor
  /// positions (its empty space is the tetrahedron between it and this point).
  [[nodiscard]] Vec3d viewpoint(std::size_t t) const {
    const Triangle& tri = triangles[t];
    return (Vec3d(sensor_positions[tri[0]]) + Vec3d(sensor_positions[tri[1]]) + Vec3d(sensor_positions[tri[2]])) / 3.0;
  }
  [[nodiscard]] Vec3d world_sensor_position(std::size_t v) const {
    return origin + Vec3d(sensor_positions[v]);
  }
  /// Throws ProcessingError when attribute sizes disagree or an index is out of range.
  void check_invariants() const;
  /// Hands back the room every array grew beyond its size (meshes built by appending hold up
  /// to twice what they need).
  void shrink_to_fit();
};

/// Appends vertex v of `from` to `to` with every per-vertex attribute `from` carries; both
/// meshes share one origin.
void append_vertex(const Mesh& from, std::uint32_t v, Mesh& to);

/// Appends every vertex and triangle of `from` to `to`, whose origin may differ: positions and
/// sensor positions are moved into `to`'s frame, the other per-vertex attributes `from`
/// carries are copied, and each triangle keeps its acquisition and takes its index in `to` as
/// its face. Throws ProcessingError when the two carry different attributes.
void append_mesh(const Mesh& from, Mesh& to);

/// Converts an absolute position to floats relative to `origin`.
inline Vec3f to_local(const Vec3d& p, const Vec3d& origin) { return Vec3f(p - origin); }

/// The default local origin for data starting at `first`: that point rounded down to whole
/// metres, so origins are exact and readable in any CRS.
inline Vec3d whole_metre_origin(const Vec3d& first) {
  return {std::floor(first.x), std::floor(first.y), std::floor(first.z)};
}

/// Twice the area of the triangle (a, b, c); 0 for degenerate triangles.
double doubled_area(const Vec3d& a, const Vec3d& b, const Vec3d& c);

/// Below this doubled area (m^2) a triangle of the input is degenerate: its normal is noise.
/// Every reader of acquisitions drops such triangles (whole-mesh reading and the tiler alike,
/// from the file's double coordinates) so that both number the remaining triangles the same.
inline constexpr double kMinDoubledArea = 1e-12;

/// Whether the input triangle (a, b, c), in the file's coordinates, is dropped as degenerate.
inline bool degenerate_input_triangle(const Vec3d& a, const Vec3d& b, const Vec3d& c,
                                      double min_doubled_area = kMinDoubledArea) {
  const Vec3d n = cross(b - a, c - a);  // squared, without the root: asked of every input triangle
  return !(dot(n, n) >= min_doubled_area * min_doubled_area);
}

}  // namespace citymesh
