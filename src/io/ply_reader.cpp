// SPDX-License-Identifier: MIT
// Streaming PLY reader: per-element decoding plans, bounded chunks, errors that name the row.
#include "citymesh/io/ply_reader.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "byte_source.h"
#include "citymesh/core/error.h"
#include "citymesh/core/interrupt.h"
#include "citymesh/core/log.h"
#include "ply_values.h"

namespace citymesh {

using namespace ply_detail;

namespace {

/// Whether d is longer than kMaxReach (or not a number), by its squared length: the reader
/// checks every vertex and the tiler every face of a city, so no square root unless it fails.
bool beyond_reach(const Vec3d& d) { return !(dot(d, d) <= kMaxReach * kMaxReach); }

// Where a vertex property's value goes: a fixed attribute, or kSlots + e for extra property e.
using Slot = std::uint16_t;
enum : Slot { kSkip, kX, kY, kZ, kSX, kSY, kSZ, kTime, kIntensity, kRed, kGreen, kBlue, kSlots };

/// Longest polygon accepted; a longer list is malformed input, not a face.
constexpr std::int64_t kMaxPolygon = 65535;
/// Header bytes searched for end_header.
constexpr std::size_t kMaxHeader = 1u << 20;

struct FixedField {
  std::size_t offset;
  PlyScalar type;
  Slot slot;
};

std::string read_header_text(const std::filesystem::path& path, std::uint64_t file_size) {
  ByteSource src(path, 0, 64u << 10);
  const std::size_t n = static_cast<std::size_t>(std::min<std::uint64_t>(file_size, kMaxHeader));
  const char* p = src.peek(n);
  return p == nullptr ? std::string() : std::string(p, n);
}

std::uint64_t file_size_of(const std::filesystem::path& path) {
  std::error_code ec;
  const auto size = std::filesystem::file_size(path, ec);
  if (ec) throw InputError(fmt::format("{}: cannot open: {}", path.string(), ec.message()));
  return size;
}

}  // namespace

void PlyVertexChunk::clear() {
  positions.clear();
  sensor_positions.clear();
  times.clear();
  intensities.clear();
  colors.clear();
  for (auto& column : extras) column.clear();
}

void PlyFaceChunk::clear() {
  triangles.clear();
  faces.clear();
  fans.clear();
  for (auto& column : extras) column.clear();
}

struct PlyReader::Impl {
  std::filesystem::path path;
  PlyReadParams params;
  PlyHeader header;
  PlyVertexLayout layout;
  PlyReadStats stats;
  std::unique_ptr<ByteSource> src;
  bool swap = false;
  bool ascii = false;

  std::size_t element = 0;  // current element in file order
  std::uint64_t row = 0;    // next row of the current element
  std::uint64_t vertex_total = 0;
  std::uint64_t face_total = 0;
  std::vector<Slot> vertex_slots;  // one per vertex property
  std::vector<FixedField> vertex_fixed;
  std::optional<std::size_t> vertex_row_size;
  std::size_t face_list = 0;  // index of vertex_indices among the face properties
  std::vector<int> face_extra_slot;  // per face property: index into extra_face_properties, or -1
  std::vector<double> face_values;   // the current face's extra values
  std::vector<std::int64_t> polygon;

  Impl(std::filesystem::path p, PlyReadParams rp) : path(std::move(p)), params(std::move(rp)) {
    const std::uint64_t size = file_size_of(path);
    header = parse_ply_header(read_header_text(path, size), size, path);
    swap = header.format == PlyFormat::binary_big_endian;
    ascii = header.format == PlyFormat::ascii;
    plan_vertices();
    plan_faces();
    params.chunk_rows = std::max<std::size_t>(params.chunk_rows, 1);
    src = std::make_unique<ByteSource>(path, header.header_bytes);
  }

  [[noreturn]] void fail(std::string_view why) const {
    throw InputError(fmt::format("{}: {}", path.string(), why));
  }
  [[noreturn]] void fail_row(std::string_view element_name, std::uint64_t index, std::string_view why) const {
    throw InputError(fmt::format("{}: {} {}: {}", path.string(), element_name, index, why));
  }

  void plan_vertices() {
    const PlyElement* v = header.find("vertex");
    if (v == nullptr) fail("no 'vertex' element in the header");
    vertex_total = v->count;
    if (vertex_total > UINT32_MAX) {
      fail(fmt::format("{} vertices in one file is more than the supported 4294967295; split the file",
                       vertex_total));
    }
    vertex_slots.assign(v->properties.size(), kSkip);
    auto assign = [&](std::string_view name, Slot slot) {
      for (std::size_t i = 0; i < v->properties.size(); ++i) {
        if (v->properties[i].name != name) continue;
        if (v->properties[i].is_list) fail(fmt::format("vertex property '{}' is a list, expected a number", name));
        vertex_slots[i] = slot;
        return true;
      }
      return false;
    };
    const bool xyz = assign("x", kX) & assign("y", kY) & assign("z", kZ);
    if (!xyz) fail("vertex element lacks one of the properties x, y, z");
    const auto& o = params.sensor_origin_names;
    const int origins = int(assign(o[0], kSX)) + int(assign(o[1], kSY)) + int(assign(o[2], kSZ));
    layout.has_sensor_origin = origins == 3;
    if (origins != 3 && (params.require_sensor_origin || origins != 0)) {
      fail(fmt::format("no sensor position: vertex properties {}, {}, {} not all found (set [input] "
                       "sensor_origin to the names your file uses)",
                       o[0], o[1], o[2]));
    }
    for (const std::string& name : params.time_names) {
      if (assign(name, kTime)) {
        layout.has_time = true;
        layout.time_name = name;
        break;
      }
    }
    layout.has_intensity = assign(params.intensity_name, kIntensity);
    for (std::size_t e = 0; e < params.extra_vertex_properties.size(); ++e) {
      const std::string& name = params.extra_vertex_properties[e];
      if (!assign(name, static_cast<Slot>(kSlots + e))) fail(fmt::format("vertex property '{}' not found", name));
    }
    layout.has_color = assign("red", kRed) & assign("green", kGreen) & assign("blue", kBlue);
    if (!layout.has_color) {
      std::replace_if(vertex_slots.begin(), vertex_slots.end(),
                      [](Slot s) { return s == kRed || s == kGreen || s == kBlue; }, kSkip);
    }
    vertex_row_size = v->fixed_row_size();
    std::size_t offset = 0;
    for (std::size_t i = 0; i < v->properties.size(); ++i) {
      if (vertex_slots[i] != kSkip) vertex_fixed.push_back({offset, v->properties[i].type, vertex_slots[i]});
      offset += ply_scalar_size(v->properties[i].type);
    }
  }

  void plan_faces() {
    const PlyElement* f = header.find("face");
    if (f == nullptr) return;
    face_total = f->count;
    for (std::size_t i = 0; i < f->properties.size(); ++i) {
      const PlyProperty& p = f->properties[i];
      if (p.name != "vertex_indices" && p.name != "vertex_index") continue;
      if (!p.is_list) fail(fmt::format("face property '{}' must be a list", p.name));
      if (p.type == PlyScalar::float32 || p.type == PlyScalar::float64) {
        fail(fmt::format("face property '{}' must hold integers, not {}", p.name, ply_scalar_name(p.type)));
      }
      face_list = i;
      plan_face_extras(*f);
      return;
    }
    fail("face element has no 'vertex_indices' (or 'vertex_index') list");
  }

  void plan_face_extras(const PlyElement& f) {
    face_extra_slot.assign(f.properties.size(), -1);
    face_values.assign(params.extra_face_properties.size(), 0.0);
    for (std::size_t e = 0; e < params.extra_face_properties.size(); ++e) {
      const std::string& name = params.extra_face_properties[e];
      const auto it = std::find_if(f.properties.begin(), f.properties.end(),
                                   [&](const PlyProperty& p) { return p.name == name && !p.is_list; });
      if (it == f.properties.end()) fail(fmt::format("face property '{}' not found", name));
      face_extra_slot[static_cast<std::size_t>(it - f.properties.begin())] = static_cast<int>(e);
    }
  }

  // ---- vertices -------------------------------------------------------------------------

  void emit_vertex(PlyVertexChunk& out, const std::vector<double>& v, std::uint64_t index) const {
    for (std::size_t e = 0; e < params.extra_vertex_properties.size(); ++e) out.extras[e].push_back(v[kSlots + e]);
    const Vec3d p{v[kX], v[kY], v[kZ]};
    if (!is_finite(p)) {
      fail_row("vertex", index, fmt::format("position is not finite ({}, {}, {})", p.x, p.y, p.z));
    }
    out.positions.push_back(p + header.offset);
    if (layout.has_sensor_origin) {
      const Vec3d s{v[kSX], v[kSY], v[kSZ]};
      if (!is_finite(s)) {
        fail_row("vertex", index, fmt::format("sensor position is not finite ({}, {}, {})", s.x, s.y, s.z));
      }
      if (beyond_reach(p - s)) {
        fail_row("vertex", index,
                 fmt::format("lies {:.0f} m from its sensor position (more than {:.0f} m: corrupt coordinates?)",
                             norm(p - s), kMaxReach));
      }
      out.sensor_positions.push_back(s + header.offset);
    }
    if (layout.has_time) {
      if (!std::isfinite(v[kTime])) fail_row("vertex", index, "time is not finite");
      out.times.push_back(v[kTime]);
    }
    if (layout.has_intensity) out.intensities.push_back(static_cast<float>(v[kIntensity]));
    if (layout.has_color) {
      auto channel = [](double c) { return static_cast<std::uint8_t>(std::clamp(c, 0.0, 255.0)); };
      out.colors.push_back({channel(v[kRed]), channel(v[kGreen]), channel(v[kBlue])});
    }
  }

  void read_vertex_binary_fixed(std::vector<double>& v, std::uint64_t index) {
    const std::size_t size = *vertex_row_size;
    const char* p = src->peek(size);
    if (p == nullptr) fail_row("vertex", index, "unexpected end of file");
    for (const FixedField& f : vertex_fixed) v[f.slot] = load_double(p + f.offset, f.type, swap);
    src->skip(size);
  }

  void read_vertex_binary_walk(const PlyElement& e, std::vector<double>& v, std::uint64_t index) {
    for (std::size_t i = 0; i < e.properties.size(); ++i) {
      const PlyProperty& p = e.properties[i];
      if (p.is_list) {
        skip_binary_list(p, "vertex", index);
        continue;
      }
      const char* b = src->peek(ply_scalar_size(p.type));
      if (b == nullptr) fail_row("vertex", index, "unexpected end of file");
      v[vertex_slots[i]] = load_double(b, p.type, swap);
      src->skip(ply_scalar_size(p.type));
    }
  }

  void read_vertex_ascii(const PlyElement& e, std::vector<double>& v, std::uint64_t index) {
    std::string_view line;
    if (!src->next_line(line)) fail_row("vertex", index, "unexpected end of file");
    AsciiTokens tokens(line);
    std::string_view token;
    for (std::size_t i = 0; i < e.properties.size(); ++i) {
      const PlyProperty& p = e.properties[i];
      if (p.is_list) {
        skip_ascii_list(tokens, p, "vertex", index);
        continue;
      }
      if (!tokens.next(token)) fail_row("vertex", index, fmt::format("missing value for '{}'", p.name));
      auto value = parse_double(token);
      if (!value) fail_row("vertex", index, fmt::format("'{}' is not a number (property '{}')", token, p.name));
      v[vertex_slots[i]] = *value;
    }
    if (tokens.next(token)) fail_row("vertex", index, fmt::format("unexpected extra value '{}'", token));
  }

  void read_vertices(PlyVertexChunk& out, const PlyElement& e, std::uint64_t n) {
    std::vector<double> v(kSlots + params.extra_vertex_properties.size(), 0.0);
    out.positions.reserve(n);
    out.extras.resize(params.extra_vertex_properties.size());
    for (std::uint64_t i = 0; i < n; ++i) {
      const std::uint64_t index = row + i;
      if (ascii) {
        read_vertex_ascii(e, v, index);
      } else if (vertex_row_size) {
        read_vertex_binary_fixed(v, index);
      } else {
        read_vertex_binary_walk(e, v, index);
      }
      emit_vertex(out, v, index);
    }
  }

  // ---- faces ----------------------------------------------------------------------------

  std::int64_t checked_count(std::int64_t count, std::string_view element_name, std::uint64_t index) const {
    if (count < 0 || count > kMaxPolygon) {
      fail_row(element_name, index, fmt::format("list length {} is out of range (0..{})", count, kMaxPolygon));
    }
    return count;
  }

  void skip_binary_list(const PlyProperty& p, std::string_view element_name, std::uint64_t index) {
    const char* b = src->peek(ply_scalar_size(p.count_type));
    if (b == nullptr) fail_row(element_name, index, "unexpected end of file");
    const std::int64_t count = checked_count(load_int(b, p.count_type, swap), element_name, index);
    src->skip(ply_scalar_size(p.count_type));
    const std::size_t bytes = static_cast<std::size_t>(count) * ply_scalar_size(p.type);
    if (src->peek(bytes) == nullptr) fail_row(element_name, index, "unexpected end of file");
    src->skip(bytes);
  }

  void skip_ascii_list(AsciiTokens& tokens, const PlyProperty& p, std::string_view element_name,
                       std::uint64_t index) const {
    std::string_view token;
    auto count = tokens.next(token) ? parse_int(token) : std::nullopt;
    if (!count) fail_row(element_name, index, fmt::format("list '{}': missing or bad length", p.name));
    for (std::int64_t k = checked_count(*count, element_name, index); k > 0; --k) {
      if (!tokens.next(token)) fail_row(element_name, index, fmt::format("list '{}' is shorter than its length", p.name));
    }
  }

  void read_polygon_binary(const PlyElement& e, std::uint64_t index) {
    for (std::size_t i = 0; i < e.properties.size(); ++i) {
      const PlyProperty& p = e.properties[i];
      if (i != face_list) {
        if (p.is_list) {
          skip_binary_list(p, "face", index);
        } else if (const char* b = src->peek(ply_scalar_size(p.type)); b == nullptr) {
          fail_row("face", index, "unexpected end of file");
        } else {
          if (face_extra_slot[i] >= 0) face_values[static_cast<std::size_t>(face_extra_slot[i])] = load_double(b, p.type, swap);
          src->skip(ply_scalar_size(p.type));
        }
        continue;
      }
      const std::size_t count_size = ply_scalar_size(p.count_type), item = ply_scalar_size(p.type);
      const char* b = src->peek(count_size);
      if (b == nullptr) fail_row("face", index, "unexpected end of file");
      const auto count = static_cast<std::size_t>(checked_count(load_int(b, p.count_type, swap), "face", index));
      src->skip(count_size);
      b = src->peek(count * item);
      if (b == nullptr) fail_row("face", index, "unexpected end of file");
      polygon.resize(count);
      for (std::size_t k = 0; k < count; ++k) polygon[k] = load_int(b + k * item, p.type, swap);
      src->skip(count * item);
    }
  }

  void read_polygon_ascii(const PlyElement& e, std::uint64_t index) {
    std::string_view line, token;
    if (!src->next_line(line)) fail_row("face", index, "unexpected end of file");
    AsciiTokens tokens(line);
    for (std::size_t i = 0; i < e.properties.size(); ++i) {
      const PlyProperty& p = e.properties[i];
      if (i != face_list) {
        if (p.is_list) {
          skip_ascii_list(tokens, p, "face", index);
        } else if (!tokens.next(token)) {
          fail_row("face", index, fmt::format("missing value for '{}'", p.name));
        } else if (face_extra_slot[i] >= 0) {
          const auto value = parse_double(token);
          if (!value) fail_row("face", index, fmt::format("'{}' is not a number", p.name));
          face_values[static_cast<std::size_t>(face_extra_slot[i])] = *value;
        }
        continue;
      }
      auto count = tokens.next(token) ? parse_int(token) : std::nullopt;
      if (!count) fail_row("face", index, "missing or bad vertex count");
      polygon.resize(static_cast<std::size_t>(checked_count(*count, "face", index)));
      for (auto& vertex : polygon) {
        auto value = tokens.next(token) ? parse_int(token) : std::nullopt;
        if (!value) fail_row("face", index, "fewer vertex indices than its count, or one is not an integer");
        vertex = *value;
      }
    }
    if (tokens.next(token)) fail_row("face", index, fmt::format("unexpected extra value '{}'", token));
  }

  /// Checks indices, fan-triangulates and drops triangles that repeat a vertex.
  void emit_polygon(PlyFaceChunk& out, std::uint64_t index) {
    if (polygon.empty()) fail_row("face", index, "empty vertex list");
    for (std::int64_t v : polygon) {
      if (v < 0 || static_cast<std::uint64_t>(v) >= vertex_total) {
        fail_row("face", index, fmt::format("vertex index {} is out of range (the file has {} vertices)", v,
                                            vertex_total));
      }
    }
    if (polygon.size() < 3) {
      ++stats.degenerate_dropped;
      return;
    }
    if (polygon.size() > 3) ++stats.polygons_split;
    for (std::size_t k = 1; k + 1 < polygon.size(); ++k) {
      const Triangle t{static_cast<std::uint32_t>(polygon[0]), static_cast<std::uint32_t>(polygon[k]),
                       static_cast<std::uint32_t>(polygon[k + 1])};
      if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) {
        ++stats.degenerate_dropped;
        continue;
      }
      out.triangles.push_back(t);
      out.faces.push_back(index);
      out.fans.push_back(static_cast<std::uint32_t>(k - 1));
      for (std::size_t e = 0; e < face_values.size(); ++e) out.extras[e].push_back(face_values[e]);
    }
  }

  void read_faces(PlyFaceChunk& out, const PlyElement& e, std::uint64_t n) {
    out.extras.resize(params.extra_face_properties.size());
    for (std::uint64_t i = 0; i < n; ++i) {
      if (ascii) {
        read_polygon_ascii(e, row + i);
      } else {
        read_polygon_binary(e, row + i);
      }
      emit_polygon(out, row + i);
    }
    stats.triangles += out.triangles.size();
  }

  // ---- other elements -------------------------------------------------------------------

  void skip_element(const PlyElement& e) {
    for (std::uint64_t i = 0; i < e.count; ++i) {
      if (ascii) {
        std::string_view line;
        if (!src->next_line(line)) fail_row(e.name, i, "unexpected end of file");
        continue;
      }
      for (const PlyProperty& p : e.properties) {
        if (p.is_list) {
          skip_binary_list(p, e.name, i);
        } else if (src->peek(ply_scalar_size(p.type)) == nullptr) {
          fail_row(e.name, i, "unexpected end of file");
        } else {
          src->skip(ply_scalar_size(p.type));
        }
      }
      if ((i & 0xFFFF) == 0) throw_if_interrupted(path.string());
    }
  }

  void finish() {
    if (ascii) {
      std::string_view line;
      while (src->next_line(line)) {
        if (line.find_first_not_of(" \t") != std::string_view::npos) {
          log::warn("{}: text after the last element ignored", path.string());
          break;
        }
      }
    } else if (const std::uint64_t extra = src->remaining(); extra > 0) {
      log::warn("{}: {} bytes after the last element ignored", path.string(), extra);
    }
    if (stats.degenerate_dropped > 0) {
      log::info("{}: dropped {} degenerate faces (fewer than three distinct vertices)", path.string(),
                stats.degenerate_dropped);
    }
  }
};

PlyReader::PlyReader(std::filesystem::path path, PlyReadParams params)
    : impl_(std::make_unique<Impl>(std::move(path), std::move(params))) {}
PlyReader::~PlyReader() = default;

const PlyHeader& PlyReader::header() const { return impl_->header; }
const PlyVertexLayout& PlyReader::vertex_layout() const { return impl_->layout; }
const std::filesystem::path& PlyReader::path() const { return impl_->path; }
std::uint64_t PlyReader::vertex_count() const { return impl_->vertex_total; }
std::uint64_t PlyReader::face_count() const { return impl_->face_total; }
const PlyReadStats& PlyReader::stats() const { return impl_->stats; }

PlyReader::ChunkKind PlyReader::next(PlyVertexChunk& vertices, PlyFaceChunk& faces) {
  Impl& m = *impl_;
  while (m.element < m.header.elements.size()) {
    const PlyElement& e = m.header.elements[m.element];
    if (m.row >= e.count) {
      ++m.element;
      m.row = 0;
      continue;
    }
    throw_if_interrupted(m.path.string());
    const std::uint64_t n = std::min<std::uint64_t>(m.params.chunk_rows, e.count - m.row);
    if (e.name == "vertex") {
      vertices.clear();
      vertices.first = m.row;
      m.read_vertices(vertices, e, n);
      m.row += n;
      m.stats.vertices += n;
      return ChunkKind::vertices;
    }
    if (e.name == "face") {
      faces.clear();
      faces.first_face = m.row;
      m.read_faces(faces, e, n);
      m.row += n;
      m.stats.faces += n;
      return ChunkKind::faces;
    }
    m.skip_element(e);
    m.row = e.count;
  }
  if (m.element == m.header.elements.size()) {
    m.finish();
    ++m.element;  // finish only once
    m.stats.bytes = std::filesystem::file_size(m.path);
  }
  return ChunkKind::end;
}

void check_face_extent(const std::filesystem::path& file, std::uint64_t face, const Vec3d& a, const Vec3d& b,
                       const Vec3d& c) {
  if (beyond_reach(b - a) || beyond_reach(c - b) || beyond_reach(a - c)) {
    const double longest = std::max({norm(b - a), norm(c - b), norm(a - c)});
    throw InputError(fmt::format("{}: face {}: an edge of {:.0f} m (longer than {:.0f} m: corrupt coordinates?)",
                                 file.string(), face, longest, kMaxReach));
  }
}

void check_has_faces(const std::filesystem::path& file, const PlyHeader& header) {
  if (header.find("face") != nullptr) return;
  throw InputError(fmt::format(
      "{}: no face element: a point cloud, not a mesh (an acquisition is a triangle mesh; `citymesh mesh` meshes "
      "scan-ordered points)",
      file.string()));
}

void check_vertices_read(const std::filesystem::path& file, std::uint64_t face, const Triangle& triangle,
                         std::uint64_t read) {
  for (const std::uint32_t v : triangle) {
    if (v >= read) {
      throw InputError(fmt::format("{}: face {} uses vertex {} before the vertices are read (put the vertex element "
                                   "first)",
                                   file.string(), face, v));
    }
  }
}

}  // namespace citymesh
