// SPDX-License-Identifier: MIT
// PLY writing through a buffered AtomicFile.
#include "citymesh/io/ply_writer.h"

#include <fmt/format.h>

#include <algorithm>
#include <bit>
#include <cstring>

#include "citymesh/core/atomic_file.h"
#include "citymesh/core/error.h"

namespace citymesh {

static_assert(std::endian::native == std::endian::little, "the PLY writer assumes a little-endian host");
static_assert(sizeof(Vec3d) == 3 * sizeof(double) && sizeof(Triangle) == 3 * sizeof(std::uint32_t),
              "vertex positions and corner lists are written as they lie in memory");

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

/// A column's values as bytes: row r's value is the `size` bytes at data + r * size.
struct RawColumn {
  const char* data;
  std::size_t size;
};

RawColumn raw_column(const PlyColumn& c) {
  return std::visit([](const auto& s) { return RawColumn{reinterpret_cast<const char*>(s.data()), sizeof(s[0])}; },
                    c.values);
}

std::vector<RawColumn> raw_columns(const std::vector<PlyColumn>& columns) {
  std::vector<RawColumn> raw;
  for (const PlyColumn& c : columns) raw.push_back(raw_column(c));
  return raw;
}

/// Copies one value of `size` bytes (a fixed-size copy for the sizes PLY has).
inline char* put_value(char* at, const char* from, std::size_t size) {
  switch (size) {
    case 1: *at = *from; break;
    case 2: std::memcpy(at, from, 2); break;
    case 4: std::memcpy(at, from, 4); break;
    case 8: std::memcpy(at, from, 8); break;
    default: std::memcpy(at, from, size);
  }
  return at + size;
}

/// Fixed-size rows gathered in a buffer and handed to the file in large blocks: a value at a
/// time through a growing vector and a variant visit was a tenth of writing a labelled PLY.
class RowWriter {
 public:
  RowWriter(AtomicFile& file, std::span<const RawColumn> columns, std::size_t lead_bytes)
      : file_(file), columns_(columns), row_bytes_(lead_bytes) {
    for (const RawColumn& c : columns_) row_bytes_ += c.size;
    buffer_.resize(std::max(kBlock, row_bytes_));
  }
  RowWriter(const RowWriter&) = delete;
  RowWriter& operator=(const RowWriter&) = delete;

  /// Room for one row: the caller writes the `lead_bytes` first, finish_row() the columns.
  char* start_row() {
    if (used_ + row_bytes_ > buffer_.size()) flush();
    return buffer_.data() + used_;
  }
  void finish_row(char* after_lead, std::size_t row) {
    for (const RawColumn& c : columns_) after_lead = put_value(after_lead, c.data + row * c.size, c.size);
    used_ += row_bytes_;
  }
  void flush() {
    file_.write(buffer_.data(), used_);
    used_ = 0;
  }

 private:
  static constexpr std::size_t kBlock = 1u << 20;
  AtomicFile& file_;
  std::span<const RawColumn> columns_;
  std::size_t row_bytes_;
  std::vector<char> buffer_;
  std::size_t used_ = 0;
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
  const std::vector<RawColumn> vertex_columns = raw_columns(in.vertex_columns), face_columns = raw_columns(in.face_columns);
  {
    RowWriter out(file, vertex_columns, sizeof(Vec3d));
    for (std::size_t v = 0; v < in.positions.size(); ++v) {
      char* at = out.start_row();
      std::memcpy(at, &in.positions[v], sizeof(Vec3d));
      out.finish_row(at + sizeof(Vec3d), v);
    }
    out.flush();
  }
  RowWriter out(file, face_columns, 1 + sizeof(Triangle));
  for (std::size_t f = 0; f < in.triangles.size(); ++f) {
    char* at = out.start_row();
    *at = 3;  // the list's length
    std::memcpy(at + 1, &in.triangles[f], sizeof(Triangle));
    out.finish_row(at + 1 + sizeof(Triangle), f);
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
