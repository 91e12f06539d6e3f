// SPDX-License-Identifier: MIT
// PLY writing through a buffered AtomicFile.
#include "citymesh/io/ply_writer.h"

#include <fmt/format.h>

#include <bit>
#include <cstring>

#include "citymesh/core/atomic_file.h"
#include "citymesh/core/error.h"

namespace citymesh {

static_assert(std::endian::native == std::endian::little, "the PLY writer assumes a little-endian host");

namespace {

template <class T>
constexpr std::string_view type_name() {
  if constexpr (std::is_same_v<T, std::int8_t>) return "char";
  if constexpr (std::is_same_v<T, std::uint8_t>) return "uchar";
  if constexpr (std::is_same_v<T, std::int16_t>) return "short";
  if constexpr (std::is_same_v<T, std::uint16_t>) return "ushort";
  if constexpr (std::is_same_v<T, std::int32_t>) return "int";
  if constexpr (std::is_same_v<T, std::uint32_t>) return "uint";
  if constexpr (std::is_same_v<T, float>) return "float";
  if constexpr (std::is_same_v<T, double>) return "double";
}

std::size_t column_size(const PlyColumn& c) {
  return std::visit([](const auto& s) { return s.size(); }, c.values);
}

void check_columns(const std::vector<PlyColumn>& columns, std::size_t rows, std::string_view element,
                   const std::filesystem::path& path) {
  for (const PlyColumn& c : columns) {
    if (column_size(c) != rows) {
      throw ProcessingError(fmt::format("{}: {} column '{}' has {} values for {} rows", path.string(),
                                        element, c.name, column_size(c), rows));
    }
  }
}

/// Collects bytes and hands them to the file in large blocks.
class BufferedOut {
 public:
  explicit BufferedOut(AtomicFile& file) : file_(file) { buffer_.reserve(kBlock); }
  template <class T>
  void put(const T& value) {
    const auto* p = reinterpret_cast<const char*>(&value);
    buffer_.insert(buffer_.end(), p, p + sizeof(T));
    if (buffer_.size() >= kBlock) flush();
  }
  void put_column_value(const PlyColumn& c, std::size_t row) {
    std::visit([&](const auto& s) { put(s[row]); }, c.values);
  }
  void flush() {
    file_.write(buffer_.data(), buffer_.size());
    buffer_.clear();
  }

 private:
  static constexpr std::size_t kBlock = 1u << 20;
  AtomicFile& file_;
  std::vector<char> buffer_;
};

std::string make_header(const PlyWriteInput& in) {
  std::string h = "ply\nformat binary_little_endian 1.0\n";
  for (const std::string& c : in.comments) h += fmt::format("comment {}\n", c);
  h += fmt::format("element vertex {}\nproperty double x\nproperty double y\nproperty double z\n",
                   in.positions.size());
  auto declare = [&](const PlyColumn& c) {
    std::visit([&](const auto& s) {
      using T = std::remove_cv_t<typename std::decay_t<decltype(s)>::element_type>;
      h += fmt::format("property {} {}\n", type_name<T>(), c.name);
    }, c.values);
  };
  for (const PlyColumn& c : in.vertex_columns) declare(c);
  h += fmt::format("element face {}\nproperty list uchar uint vertex_indices\n", in.triangles.size());
  for (const PlyColumn& c : in.face_columns) declare(c);
  return h + "end_header\n";
}

}  // namespace

void write_ply(const std::filesystem::path& path, const PlyWriteInput& in) {
  check_columns(in.vertex_columns, in.positions.size(), "vertex", path);
  check_columns(in.face_columns, in.triangles.size(), "face", path);
  AtomicFile file(path);
  file.write(make_header(in));
  BufferedOut out(file);
  for (std::size_t v = 0; v < in.positions.size(); ++v) {
    out.put(in.positions[v].x);
    out.put(in.positions[v].y);
    out.put(in.positions[v].z);
    for (const PlyColumn& c : in.vertex_columns) out.put_column_value(c, v);
  }
  for (std::size_t f = 0; f < in.triangles.size(); ++f) {
    out.put(std::uint8_t{3});
    for (std::uint32_t index : in.triangles[f]) out.put(index);
    for (const PlyColumn& c : in.face_columns) out.put_column_value(c, f);
  }
  out.flush();
  file.commit();
}

void write_mesh_ply(const std::filesystem::path& path, const Mesh& mesh, std::vector<PlyColumn> face_columns) {
  mesh.check_invariants();
  std::vector<Vec3d> positions(mesh.vertex_count());
  for (std::size_t v = 0; v < positions.size(); ++v) positions[v] = mesh.world_position(v);
  std::vector<double> sx, sy, sz;
  PlyWriteInput in{positions, mesh.triangles, {}, std::move(face_columns), {"written by citymesh"}};
  std::vector<std::uint8_t> red, green, blue;
  if (mesh.has_sensor_positions()) {
    for (std::size_t v = 0; v < positions.size(); ++v) {
      const Vec3d s = mesh.world_sensor_position(v);
      sx.push_back(s.x);
      sy.push_back(s.y);
      sz.push_back(s.z);
    }
    in.vertex_columns.push_back({"x_origin", std::span<const double>(sx)});
    in.vertex_columns.push_back({"y_origin", std::span<const double>(sy)});
    in.vertex_columns.push_back({"z_origin", std::span<const double>(sz)});
  }
  if (!mesh.times.empty()) in.vertex_columns.push_back({"gps_time", std::span<const double>(mesh.times)});
  if (!mesh.intensities.empty()) {
    in.vertex_columns.push_back({"intensity", std::span<const float>(mesh.intensities)});
  }
  if (!mesh.colors.empty()) {
    for (const Rgb8& c : mesh.colors) {
      red.push_back(c.r);
      green.push_back(c.g);
      blue.push_back(c.b);
    }
    in.vertex_columns.push_back({"red", std::span<const std::uint8_t>(red)});
    in.vertex_columns.push_back({"green", std::span<const std::uint8_t>(green)});
    in.vertex_columns.push_back({"blue", std::span<const std::uint8_t>(blue)});
  }
  write_ply(path, in);
}

}  // namespace citymesh
