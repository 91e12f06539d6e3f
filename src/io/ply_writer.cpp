// SPDX-License-Identifier: MIT
// PLY writing through a buffered AtomicFile.
#include "citymesh/io/ply_writer.h"

#include <fmt/format.h>

#include <algorithm>
#include <bit>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <functional>

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

/// Where rows go: the output file, or a spool file behind it.
using ByteSink = std::function<void(const char*, std::size_t)>;

ByteSink sink_of(AtomicFile& file) {
  return [&file](const char* data, std::size_t size) { file.write(data, size); };
}

/// Fixed-size rows gathered in a buffer and handed to the file in large blocks: a value at a
/// time through a growing vector and a variant visit was a tenth of writing a labelled PLY.
class RowWriter {
 public:
  RowWriter(ByteSink sink, std::span<const RawColumn> columns, std::size_t lead_bytes)
      : sink_(std::move(sink)), columns_(columns), row_bytes_(lead_bytes) {
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
    sink_(buffer_.data(), used_);
    used_ = 0;
  }

 private:
  static constexpr std::size_t kBlock = 1u << 20;
  ByteSink sink_;
  std::span<const RawColumn> columns_;
  std::size_t row_bytes_;
  std::vector<char> buffer_;
  std::size_t used_ = 0;
};

/// `chunk`'s vertex rows (x, y, z, then its vertex columns), as the header declares them.
void write_vertex_rows(const ByteSink& sink, const PlyWriteInput& chunk) {
  const std::vector<RawColumn> columns = raw_columns(chunk.vertex_columns);
  RowWriter out(sink, columns, sizeof(Vec3d));
  for (std::size_t v = 0; v < chunk.positions.size(); ++v) {
    char* at = out.start_row();
    std::memcpy(at, &chunk.positions[v], sizeof(Vec3d));
    out.finish_row(at + sizeof(Vec3d), v);
  }
  out.flush();
}

/// `chunk`'s face rows (the corner list, then its face columns), as the header declares them.
void write_face_rows(const ByteSink& sink, const PlyWriteInput& chunk) {
  const std::vector<RawColumn> columns = raw_columns(chunk.face_columns);
  RowWriter out(sink, columns, 1 + sizeof(Triangle));
  for (std::size_t f = 0; f < chunk.triangles.size(); ++f) {
    char* at = out.start_row();
    *at = 3;  // the list's length
    std::memcpy(at + 1, &chunk.triangles[f], sizeof(Triangle));
    out.finish_row(at + 1 + sizeof(Triangle), f);
  }
  out.flush();
}

std::string make_header(const PlyWriteInput& in, std::uint64_t vertices, std::uint64_t faces) {
  std::string h = "ply\nformat binary_little_endian 1.0\n";
  for (const std::string& c : in.comments) h += fmt::format("comment {}\n", c);
  h += fmt::format("element vertex {}\nproperty double x\nproperty double y\nproperty double z\n", vertices);
  auto declare = [&](const PlyColumn& c) {
    std::visit([&](const auto& s) {
      using T = std::remove_cv_t<typename std::decay_t<decltype(s)>::element_type>;
      h += fmt::format("property {} {}\n", type_name<T>(), c.name);
    }, c.values);
  };
  for (const PlyColumn& c : in.vertex_columns) declare(c);
  h += fmt::format("element face {}\nproperty list uchar uint vertex_indices\n", faces);
  for (const PlyColumn& c : in.face_columns) declare(c);
  return h + "end_header\n";
}

/// Whether `chunk`'s columns are `layout`'s: the same names and types, in order.
bool same_columns(const std::vector<PlyColumn>& layout, const std::vector<PlyColumn>& chunk) {
  if (layout.size() != chunk.size()) return false;
  for (std::size_t c = 0; c < layout.size(); ++c) {
    if (layout[c].name != chunk[c].name || layout[c].values.index() != chunk[c].values.index()) return false;
  }
  return true;
}

}  // namespace

struct PlyStreamWriter::Impl {
  AtomicFile file;
  PlyWriteInput layout;
  std::uint64_t vertices, faces, vertices_written = 0, faces_written = 0;
  Impl(const std::filesystem::path& path, PlyWriteInput l, std::uint64_t v, std::uint64_t f)
      : file(path), layout(std::move(l)), vertices(v), faces(f) {}
};

PlyStreamWriter::PlyStreamWriter(const std::filesystem::path& path, const PlyWriteInput& layout, std::uint64_t vertices,
                                 std::uint64_t faces)
    : impl_(std::make_unique<Impl>(path, PlyWriteInput{{}, {}, layout.vertex_columns, layout.face_columns, layout.comments},
                                   vertices, faces)) {
  impl_->file.write(make_header(impl_->layout, vertices, faces));
}

PlyStreamWriter::~PlyStreamWriter() = default;

void PlyStreamWriter::add_vertices(const PlyWriteInput& chunk) {
  const std::filesystem::path& path = impl_->file.path();
  if (!same_columns(impl_->layout.vertex_columns, chunk.vertex_columns) || impl_->faces_written > 0 ||
      impl_->vertices_written + chunk.positions.size() > impl_->vertices) {
    throw ProcessingError(fmt::format("{}: vertex rows that do not fit the header", path.string()));
  }
  check_columns(chunk.vertex_columns, chunk.positions.size(), "vertex", path);
  write_vertex_rows(sink_of(impl_->file), chunk);
  impl_->vertices_written += chunk.positions.size();
}

void PlyStreamWriter::add_faces(const PlyWriteInput& chunk) {
  const std::filesystem::path& path = impl_->file.path();
  if (!same_columns(impl_->layout.face_columns, chunk.face_columns) || impl_->vertices_written != impl_->vertices ||
      impl_->faces_written + chunk.triangles.size() > impl_->faces) {
    throw ProcessingError(fmt::format("{}: face rows that do not fit the header", path.string()));
  }
  check_columns(chunk.face_columns, chunk.triangles.size(), "face", path);
  write_face_rows(sink_of(impl_->file), chunk);
  impl_->faces_written += chunk.triangles.size();
}

void PlyStreamWriter::commit() {
  if (impl_->vertices_written != impl_->vertices || impl_->faces_written != impl_->faces) {
    throw ProcessingError(fmt::format("{}: {} of {} vertices and {} of {} faces written", impl_->file.path().string(),
                                      impl_->vertices_written, impl_->vertices, impl_->faces_written, impl_->faces));
  }
  impl_->file.commit();
}

namespace {

/// A scratch file beside `output`, unlinked as soon as it is open: nothing is left behind,
/// even by a killed process, and the disk of the output (not /tmp) holds it.
class SpoolFile {
 public:
  SpoolFile(const std::filesystem::path& output, std::string_view part) : output_(output) {
    std::filesystem::path name = output;
    name += fmt::format(".{}{}{}", part, kTemporaryInfix, process_tag());
    file_ = std::fopen(name.c_str(), "w+b");
    if (file_ == nullptr) {
      const int err = errno;
      throw OutputError(
          fmt::format("{}: cannot open a scratch file beside it: {}", output.string(), std::strerror(err)));
    }
    std::error_code ignored;  // a name that cannot be removed only leaves an empty file behind
    std::filesystem::remove(name, ignored);
  }
  SpoolFile(const SpoolFile&) = delete;
  SpoolFile& operator=(const SpoolFile&) = delete;
  ~SpoolFile() { std::fclose(file_); }

  void write(const char* data, std::size_t size) {
    if (size > 0 && std::fwrite(data, 1, size, file_) != size) {
      const int err = errno;
      throw OutputError(fmt::format("{}: cannot write its scratch file: {}", output_.string(), std::strerror(err)));
    }
  }
  /// Everything written so far, appended to `out`.
  void copy_to(AtomicFile& out) {
    if (std::fflush(file_) != 0 || std::fseek(file_, 0, SEEK_SET) != 0) {
      throw OutputError(fmt::format("{}: cannot read back its scratch file", output_.string()));
    }
    std::vector<char> block(1u << 20);
    while (const std::size_t got = std::fread(block.data(), 1, block.size(), file_)) out.write(block.data(), got);
    if (std::ferror(file_) != 0)
      throw OutputError(fmt::format("{}: cannot read back its scratch file", output_.string()));
  }

 private:
  std::filesystem::path output_;
  std::FILE* file_ = nullptr;
};

}  // namespace

struct PlySpoolWriter::Impl {
  std::filesystem::path path;
  PlyWriteInput layout;
  SpoolFile vertex_rows, face_rows;
  std::uint64_t vertices = 0, faces = 0;
  std::uint32_t largest_corner = 0;
  Impl(const std::filesystem::path& p, PlyWriteInput l)
      : path(p), layout(std::move(l)), vertex_rows(p, "vertices"), face_rows(p, "faces") {}
};

PlySpoolWriter::PlySpoolWriter(const std::filesystem::path& path, const PlyWriteInput& layout)
    : impl_(std::make_unique<Impl>(
          path, PlyWriteInput{{}, {}, layout.vertex_columns, layout.face_columns, layout.comments})) {}

PlySpoolWriter::~PlySpoolWriter() = default;

void PlySpoolWriter::add_vertices(const PlyWriteInput& chunk) {
  if (!same_columns(impl_->layout.vertex_columns, chunk.vertex_columns)) {
    throw ProcessingError(fmt::format("{}: vertex rows with other properties than the first", impl_->path.string()));
  }
  check_columns(chunk.vertex_columns, chunk.positions.size(), "vertex", impl_->path);
  if (impl_->vertices + chunk.positions.size() > std::uint64_t{UINT32_MAX} + 1) {
    throw ProcessingError(
        fmt::format("{}: more than 2^32 vertices, past what a face's uint index names", impl_->path.string()));
  }
  write_vertex_rows([&](const char* data, std::size_t size) { impl_->vertex_rows.write(data, size); }, chunk);
  impl_->vertices += chunk.positions.size();
}

void PlySpoolWriter::add_faces(const PlyWriteInput& chunk) {
  if (!same_columns(impl_->layout.face_columns, chunk.face_columns)) {
    throw ProcessingError(fmt::format("{}: face rows with other properties than the first", impl_->path.string()));
  }
  check_columns(chunk.face_columns, chunk.triangles.size(), "face", impl_->path);
  for (const Triangle& t : chunk.triangles) impl_->largest_corner = std::max({impl_->largest_corner, t[0], t[1], t[2]});
  write_face_rows([&](const char* data, std::size_t size) { impl_->face_rows.write(data, size); }, chunk);
  impl_->faces += chunk.triangles.size();
}

std::uint64_t PlySpoolWriter::vertices() const { return impl_->vertices; }

void PlySpoolWriter::commit() {
  if (impl_->faces > 0 && impl_->largest_corner >= impl_->vertices) {
    throw ProcessingError(fmt::format("{}: a face uses vertex {}, of {} vertices", impl_->path.string(),
                                      impl_->largest_corner, impl_->vertices));
  }
  AtomicFile out(impl_->path);
  out.write(make_header(impl_->layout, impl_->vertices, impl_->faces));
  impl_->vertex_rows.copy_to(out);
  impl_->face_rows.copy_to(out);
  out.commit();
}

void write_ply(const std::filesystem::path& path, const PlyWriteInput& in) {
  check_columns(in.vertex_columns, in.positions.size(), "vertex", path);
  check_columns(in.face_columns, in.triangles.size(), "face", path);
  PlyStreamWriter out(path, in, in.positions.size(), in.triangles.size());
  out.add_vertices(in);
  out.add_faces(in);
  out.commit();
}

MeshVertexRows::MeshVertexRows(const MeshVertexAttributes& has) : has_(has) {}

void MeshVertexRows::add(const Vec3d& position, const Vec3d& sensor, double time, float intensity, Rgb8 color) {
  positions.push_back(position);
  if (has_.sensors) {
    sx_.push_back(sensor.x);
    sy_.push_back(sensor.y);
    sz_.push_back(sensor.z);
  }
  if (has_.times) times_.push_back(time);
  if (has_.intensities) intensities_.push_back(intensity);
  if (has_.colors) {
    red_.push_back(color.r);
    green_.push_back(color.g);
    blue_.push_back(color.b);
  }
}

std::vector<PlyColumn> MeshVertexRows::columns() const {
  std::vector<PlyColumn> c;
  if (has_.sensors) {
    c.push_back({"x_origin", std::span<const double>(sx_)});
    c.push_back({"y_origin", std::span<const double>(sy_)});
    c.push_back({"z_origin", std::span<const double>(sz_)});
  }
  if (has_.times) c.push_back({"gps_time", std::span<const double>(times_)});
  if (has_.intensities) c.push_back({"intensity", std::span<const float>(intensities_)});
  if (has_.colors) {
    c.push_back({"red", std::span<const std::uint8_t>(red_)});
    c.push_back({"green", std::span<const std::uint8_t>(green_)});
    c.push_back({"blue", std::span<const std::uint8_t>(blue_)});
  }
  return c;
}

MeshVertexAttributes vertex_attributes(const Mesh& mesh) {
  return {.sensors = mesh.has_sensor_positions(), .times = !mesh.times.empty(),
          .intensities = !mesh.intensities.empty(), .colors = !mesh.colors.empty()};
}

MeshVertexRows mesh_vertex_rows(const Mesh& mesh, std::size_t begin, std::size_t end) {
  const MeshVertexAttributes has = vertex_attributes(mesh);
  MeshVertexRows rows(has);
  for (std::size_t v = begin; v < end; ++v) {
    rows.add(mesh.world_position(v), has.sensors ? mesh.world_sensor_position(v) : Vec3d{},
             has.times ? mesh.times[v] : 0.0, has.intensities ? mesh.intensities[v] : 0.0f,
             has.colors ? mesh.colors[v] : Rgb8{});
  }
  return rows;
}

void write_mesh_ply(const std::filesystem::path& path, const Mesh& mesh, std::vector<PlyColumn> face_columns) {
  mesh.check_invariants();
  // The rows (absolute doubles: 56 bytes a vertex with sensors and times) are made a block
  // at a time, not for the whole mesh at once: a copy that was the peak of writing a large
  // mesh. The bytes are the same (PlyStreamWriter writes chunks as one write would).
  constexpr std::size_t kBlock = 1u << 18;
  const std::size_t n = mesh.vertex_count();
  const MeshVertexRows no_rows(vertex_attributes(mesh));  // its columns name the properties
  const PlyWriteInput header{{}, {}, no_rows.columns(), face_columns, {std::string(kPlyComment)}};
  check_columns(face_columns, mesh.triangle_count(), "face", path);
  PlyStreamWriter out(path, header, n, mesh.triangle_count());
  for (std::size_t first = 0; first < n; first += kBlock) {
    const MeshVertexRows rows = mesh_vertex_rows(mesh, first, std::min(n, first + kBlock));
    out.add_vertices({rows.positions, {}, rows.columns(), {}, {}});
  }
  out.add_faces({{}, mesh.triangles, {}, std::move(face_columns), {}});
  out.commit();
}

}  // namespace citymesh
