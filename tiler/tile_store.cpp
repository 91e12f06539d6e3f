// SPDX-License-Identifier: MIT
// Writing the tile store's blocks (version 6) and its files; reading is in
// tile_block_decode.cpp.
#include "citymesh/tiler/tile_store.h"

#include <fcntl.h>
#include <fmt/format.h>
#include <sys/uio.h>
#include <unistd.h>

#include <array>
#include <cstring>

#include "citymesh/core/checksum.h"
#include "citymesh/core/error.h"
#include "citymesh/core/read_file.h"
#include "tile_block_writer.h"

namespace citymesh {

using namespace tiler_detail;

namespace {

template <class T>
std::string_view bytes_of(const std::vector<T>& values) {
  return {reinterpret_cast<const char*>(values.data()), values.size() * sizeof(T)};
}

/// `piece` through the writer, whole.
std::vector<std::string_view> write_piece(const TilePiece& piece, TileBlockWriter& writer) {
  const Mesh& m = piece.mesh;
  const std::uint32_t flags = flags_of(m);
  writer.start(flags, m.vertex_count(), m.triangle_count());
  for (std::size_t v = 0; v < m.vertex_count(); ++v) {
    writer.add_vertex(piece.vertex_ids[v], m.positions[v], m.sensor_positions[v],
                      (flags & kHasIntensity) != 0 ? m.intensities[v] : 0.0f,
                      (flags & kHasColor) != 0 ? m.colors[v] : Rgb8{});
  }
  for (std::size_t t = 0; t < m.triangle_count(); ++t) {
    const TriangleId& id = m.triangle_ids[t];
    writer.add_triangle(m.triangles[t], id.face, piece.triangle_index[t], id.fan, piece.roles[t]);
  }
  return writer.finish();
}

}  // namespace

namespace tiler_detail {

void TileBlockWriter::start(std::uint32_t flags, std::size_t max_vertices, std::size_t max_triangles) {
  // Per vertex seven 32-bit deltas; per triangle fan << 3 | step | role with the corner codes
  // (44 bits), up to three corner distances and the face (64-bit deltas), and the index.
  constexpr std::size_t per_vertex = 7 * max_varint_bytes(32);
  constexpr std::size_t per_triangle = max_varint_bytes(44) + 4 * max_varint_bytes(64) + max_varint_bytes(32);
  flags_ = flags;
  vertices_ = 0;
  intensities_.clear();
  colors_.clear();
  vertex_varints_.reset(max_vertices * per_vertex);
  triangle_varints_.reset(max_triangles * per_triangle);
  id_ = index_ = 0;
  window_ = {};
  position_ = sensor_ = {};
  face_ = 0;
  triangles_ = 0;
}

std::vector<std::string_view> TileBlockWriter::finish() {
  header_ = {};
  std::memcpy(header_.start.magic, kMagic, sizeof kMagic);
  header_.start.version = kVersion;
  header_.start.flags = flags_;
  header_.vertices = vertices_;
  header_.triangles = triangles_;
  std::vector<std::string_view> parts;
  if ((flags_ & kHasIntensity) != 0) parts.push_back(bytes_of(intensities_));
  if ((flags_ & kHasColor) != 0) parts.push_back(bytes_of(colors_));
  parts.push_back(vertex_varints_.bytes());
  parts.push_back(triangle_varints_.bytes());
  BulkChecksum sum;
  for (const std::string_view part : parts) {
    sum.add(part.data(), part.size());
    header_.payload_bytes += part.size();
  }
  header_.checksum = sum.value();
  parts.insert(parts.begin(), std::string_view(reinterpret_cast<const char*>(&header_), sizeof header_));
  return parts;
}

BlockAppender::BlockAppender(std::filesystem::path file) : file_(std::move(file)) {
  fd_ = ::open(file_.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd_ < 0) throw OutputError(fmt::format("{}: cannot create the block file: {}", file_.string(), std::strerror(errno)));
}

BlockAppender::~BlockAppender() { ::close(fd_); }

ByteRange BlockAppender::append(const std::vector<std::string_view>& parts) {
  std::vector<iovec> io;
  std::uint64_t total = 0;
  for (const std::string_view part : parts) {
    io.push_back({const_cast<char*>(part.data()), part.size()});
    total += part.size();
  }
  const ByteRange range{size_, total};
  if (::pwritev(fd_, io.data(), static_cast<int>(io.size()), static_cast<off_t>(size_)) != static_cast<ssize_t>(total)) {
    const int err = errno;
    throw OutputError(fmt::format("{}: cannot append a tile block: {}", file_.string(), std::strerror(err)));
  }
  size_ += total;
  // Start writing the block back now, without waiting: the tiler goes on while the disk
  // works, and the fsync before the store is published then finds little left to wait for
  // (it was a fifth of the tiler's time). Only a hint: a failure here changes nothing.
  (void)::sync_file_range(fd_, static_cast<off_t>(range.offset), static_cast<off_t>(total), SYNC_FILE_RANGE_WRITE);
  return range;
}

}  // namespace tiler_detail

void TilePiece::clear() {
  mesh.positions.clear();
  mesh.sensor_positions.clear();
  mesh.intensities.clear();
  mesh.colors.clear();
  mesh.triangles.clear();
  mesh.triangle_ids.clear();
  vertex_ids.clear();
  triangle_index.clear();
  roles.clear();
}

std::string encode_tile_block(const TilePiece& piece) {
  TileBlockWriter writer;
  std::string out;
  for (const std::string_view part : write_piece(piece, writer)) out += part;
  return out;
}

void sync_tile_files(const std::filesystem::path& dir) {
  std::error_code ec;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(dir, ec)) {
    const int fd = ::open(entry.path().c_str(), O_RDONLY | O_CLOEXEC);
    const bool ok = fd >= 0 && ::fsync(fd) == 0;
    const int err = errno;
    if (fd >= 0) ::close(fd);
    if (!ok) throw OutputError(fmt::format("{}: cannot sync: {}", entry.path().string(), std::strerror(err)));
  }
  if (ec) throw OutputError(fmt::format("{}: cannot list the tile store: {}", dir.string(), ec.message()));
}

TilePiece read_tile_piece(const std::filesystem::path& file, std::span<const ByteRange> blocks, const Vec3d& origin,
                          std::uint32_t acquisition, std::string_view tile) {
  const std::string source = fmt::format("{} (tile {})", file.string(), tile);
  return decode_tile_blocks(read_file_ranges(file, blocks, source), origin, acquisition, source);
}

}  // namespace citymesh
