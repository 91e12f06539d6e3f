// SPDX-License-Identifier: MIT
// Writing the tile store's blocks (version 3) and its files; reading is in
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
#include "citymesh/core/varint.h"
#include "tile_block_format.h"

namespace citymesh {

using namespace tiler_detail;

namespace {

template <class T>
std::string_view bytes_of(const std::vector<T>& values) {
  return {reinterpret_cast<const char*>(values.data()), values.size() * sizeof(T)};
}

/// The varint part of a version-3 payload: per vertex its id and sensor position (float bits),
/// each against the previous vertex's; per triangle its corners against the previous corner,
/// its face and index against the previous triangle's, and fan << 2 | role.
VarintWriter encode_varints(const TilePiece& piece) {
  const Mesh& m = piece.mesh;
  // Per vertex four 32-bit deltas; per triangle four 32-bit deltas, a 64-bit one and fan << 2
  // | role (34 bits).
  const std::size_t per_vertex = 4 * max_varint_bytes(32);
  const std::size_t per_triangle = 4 * max_varint_bytes(32) + max_varint_bytes(64) + max_varint_bytes(34);
  VarintWriter w(piece.vertex_ids.size() * per_vertex + m.triangle_count() * per_triangle);
  std::uint32_t id = 0;
  std::array<std::uint32_t, 3> sensor{};
  for (std::size_t v = 0; v < piece.vertex_ids.size(); ++v) {
    w.put_next(piece.vertex_ids[v], id);
    const Vec3f& p = m.sensor_positions[v];
    w.put_next(float_bits(p.x), sensor[0]);
    w.put_next(float_bits(p.y), sensor[1]);
    w.put_next(float_bits(p.z), sensor[2]);
  }
  std::uint32_t corner = 0, index = 0;
  std::uint64_t face = 0;
  for (std::size_t t = 0; t < m.triangle_count(); ++t) {
    for (const std::uint32_t c : m.triangles[t]) w.put_next(c, corner);
    w.put_next(m.triangle_ids[t].face, face);
    w.put_next(piece.triangle_index[t], index);
    w.put(std::uint64_t{m.triangle_ids[t].fan} << 2 | static_cast<std::uint8_t>(piece.roles[t]));
  }
  return w;
}

/// One block as consecutive byte ranges: the header, then the payload in file order.
struct BlockParts {
  BlockHeader header{};
  VarintWriter varints;
  std::vector<std::string_view> parts;

  explicit BlockParts(const TilePiece& piece) : varints(encode_varints(piece)) {
    const Mesh& m = piece.mesh;
    std::memcpy(header.start.magic, kMagic, sizeof kMagic);
    header.start.version = kVersion;
    header.start.flags = flags_of(m);
    header.vertices = m.vertex_count();
    header.triangles = m.triangle_count();
    parts = {bytes_of(m.positions)};
    if ((header.start.flags & kHasIntensity) != 0) parts.push_back(bytes_of(m.intensities));
    if ((header.start.flags & kHasColor) != 0) parts.push_back(bytes_of(m.colors));
    parts.push_back(varints.bytes());
    BulkChecksum sum;
    for (const std::string_view part : parts) {
      sum.add(part.data(), part.size());
      header.payload_bytes += part.size();
    }
    header.checksum = sum.value();
    parts.insert(parts.begin(), std::string_view(reinterpret_cast<const char*>(&header), sizeof header));
  }
  BlockParts(const BlockParts&) = delete;
  BlockParts& operator=(const BlockParts&) = delete;
};

}  // namespace

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
  const BlockParts block(piece);
  std::string out;
  out.reserve(sizeof(BlockHeader) + block.header.payload_bytes);
  for (const std::string_view part : block.parts) out += part;
  return out;
}

std::uint64_t append_tile_block(const std::filesystem::path& file, const TilePiece& piece) {
  const BlockParts block(piece);
  std::vector<iovec> io;
  std::size_t total = 0;
  for (const std::string_view part : block.parts) {
    io.push_back({const_cast<char*>(part.data()), part.size()});
    total += part.size();
  }
  // No fsync here: sync_tile_files() makes the store durable once, before the manifest names it.
  const int fd = ::open(file.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0644);
  bool ok = fd >= 0;
  const off_t at = ok ? ::lseek(fd, 0, SEEK_END) : 0;
  ok = ok && ::writev(fd, io.data(), static_cast<int>(io.size())) == static_cast<ssize_t>(total);
  const int err = errno;
  // Start writing the block back now, without waiting: the tiler goes on while the disk
  // works, and the fsync before the store is published then finds little left to wait for
  // (it was a fifth of the tiler's time). Only a hint: a failure here changes nothing.
  if (ok) (void)::sync_file_range(fd, at, static_cast<off_t>(total), SYNC_FILE_RANGE_WRITE);
  if (fd >= 0) ::close(fd);
  if (!ok) throw OutputError(fmt::format("{}: cannot append a tile block: {}", file.string(), std::strerror(err)));
  return total;
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

TilePiece read_tile_piece(const std::filesystem::path& file, const Vec3d& origin, std::uint32_t acquisition) {
  const std::optional<std::string> bytes = read_file_bytes(file);
  if (!bytes) throw InputError(fmt::format("{}: cannot open the tile chunk", file.string()));
  return decode_tile_blocks(*bytes, origin, acquisition, file.string());
}

}  // namespace citymesh
