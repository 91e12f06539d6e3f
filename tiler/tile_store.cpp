// SPDX-License-Identifier: MIT
#include "citymesh/tiler/tile_store.h"

#include <fcntl.h>
#include <fmt/format.h>
#include <sys/uio.h>
#include <unistd.h>

#include <cstdio>
#include <cstring>
#include <unordered_map>

#include "citymesh/core/checksum.h"
#include "citymesh/core/error.h"
#include "citymesh/core/read_file.h"

namespace citymesh {

namespace {

constexpr char kMagic[8] = {'C', 'M', 'T', 'I', 'L', 'E', '0', '1'};
// Version 2: the checksum is XXH3 (version 1: FNV-1a, a tenth of the tiler's time on a city).
constexpr std::uint32_t kVersion = 2;
constexpr std::uint32_t kHasIntensity = 1, kHasColor = 2;

struct BlockHeader {
  char magic[8];
  std::uint32_t version;
  std::uint32_t flags;
  std::uint64_t vertices;
  std::uint64_t triangles;
  std::uint64_t checksum;  ///< bulk_checksum (XXH3) of the payload
};
static_assert(sizeof(BlockHeader) == 40);

std::uint64_t vertex_bytes(std::uint32_t flags) {
  return 4 + 12 + 12 + ((flags & kHasIntensity) != 0 ? 4 : 0) + ((flags & kHasColor) != 0 ? 3 : 0);
}
constexpr std::uint64_t kTriangleBytes = 12 + 8 + 4 + 4 + 1;

std::uint32_t flags_of(const Mesh& m) {
  return (m.intensities.empty() ? 0 : kHasIntensity) | (m.colors.empty() ? 0 : kHasColor);
}

/// Reads consecutive arrays out of one block's payload.
class PayloadReader {
 public:
  explicit PayloadReader(const char* data) : data_(data) {}
  template <class T>
  void take(std::vector<T>& values, std::size_t count) {
    const std::size_t old = values.size();
    values.resize(old + count);
    std::memcpy(static_cast<void*>(values.data() + old), data_, count * sizeof(T));
    data_ += count * sizeof(T);
  }

 private:
  const char* data_;
};

}  // namespace

std::uint64_t TilePiece::byte_size() const {
  return sizeof(BlockHeader) + vertex_bytes(flags_of(mesh)) * mesh.vertex_count() + kTriangleBytes * triangle_count();
}

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

namespace {

template <class T>
std::string_view bytes_of(const std::vector<T>& values) {
  return {reinterpret_cast<const char*>(values.data()), values.size() * sizeof(T)};
}

/// One block as consecutive byte ranges: the header, then the payload arrays in file order.
struct BlockParts {
  BlockHeader header{};
  std::vector<std::uint64_t> faces;
  std::vector<std::uint32_t> fans;
  std::vector<std::string_view> parts;

  explicit BlockParts(const TilePiece& piece) {
    const Mesh& m = piece.mesh;
    std::memcpy(header.magic, kMagic, sizeof kMagic);
    header.version = kVersion;
    header.flags = flags_of(m);
    header.vertices = m.vertex_count();
    header.triangles = m.triangle_count();
    faces.resize(m.triangle_count());
    fans.resize(m.triangle_count());
    for (std::size_t t = 0; t < faces.size(); ++t) {
      faces[t] = m.triangle_ids[t].face;
      fans[t] = m.triangle_ids[t].fan;
    }
    parts = {bytes_of(piece.vertex_ids), bytes_of(m.positions), bytes_of(m.sensor_positions)};
    if ((header.flags & kHasIntensity) != 0) parts.push_back(bytes_of(m.intensities));
    if ((header.flags & kHasColor) != 0) parts.push_back(bytes_of(m.colors));
    for (const std::string_view part : {bytes_of(m.triangles), bytes_of(faces), bytes_of(fans),
                                        bytes_of(piece.triangle_index), bytes_of(piece.roles)}) {
      parts.push_back(part);
    }
    BulkChecksum sum;
    for (const std::string_view part : parts) sum.add(part.data(), part.size());
    header.checksum = sum.value();
    parts.insert(parts.begin(), std::string_view(reinterpret_cast<const char*>(&header), sizeof header));
  }
  BlockParts(const BlockParts&) = delete;
  BlockParts& operator=(const BlockParts&) = delete;
};

}  // namespace

std::string encode_tile_block(const TilePiece& piece) {
  const BlockParts block(piece);
  std::string out;
  out.reserve(piece.byte_size());
  for (const std::string_view part : block.parts) out += part;
  return out;
}

void append_tile_block(const std::filesystem::path& file, const TilePiece& piece) {
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
  ok = ok && ::writev(fd, io.data(), static_cast<int>(io.size())) == static_cast<ssize_t>(total);
  const int err = errno;
  if (fd >= 0) ::close(fd);
  if (!ok) throw OutputError(fmt::format("{}: cannot append a tile block: {}", file.string(), std::strerror(err)));
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

TilePiece decode_tile_blocks(std::string_view bytes, const Vec3d& origin, std::uint32_t acquisition,
                             std::string_view source) {
  TilePiece piece;
  piece.mesh.origin = origin;
  std::vector<std::uint32_t> ids;
  std::vector<Vec3f> positions, sensors;
  std::vector<float> intensities;
  std::vector<Rgb8> colors;
  std::vector<Triangle> triangles;
  std::vector<std::uint64_t> faces;
  std::vector<std::uint32_t> fans;
  std::unordered_map<std::uint32_t, std::uint32_t> local;  // vertex id -> index in the piece
  std::size_t at = 0;
  for (std::size_t block = 0; at < bytes.size(); ++block) {
    const auto fail = [&](std::string_view what) {
      return InputError(fmt::format("{}: block {} at byte {}: {}", source, block, at, what));
    };
    BlockHeader h{};
    if (bytes.size() - at < sizeof h) throw fail("truncated header");
    std::memcpy(&h, bytes.data() + at, sizeof h);
    if (std::memcmp(h.magic, kMagic, sizeof kMagic) != 0) throw fail("not a citymesh tile block");
    if (h.version != kVersion) throw fail(fmt::format("version {} (this build reads {})", h.version, kVersion));
    const std::uint64_t room = bytes.size() - at - sizeof h;
    // Counts are checked against the bytes present before anything is allocated.
    if (h.vertices > room / vertex_bytes(h.flags) || h.triangles > room / kTriangleBytes ||
        h.vertices * vertex_bytes(h.flags) + h.triangles * kTriangleBytes > room) {
      throw fail("counts larger than the file (truncated?)");
    }
    const char* payload = bytes.data() + at + sizeof h;
    const std::uint64_t size = h.vertices * vertex_bytes(h.flags) + h.triangles * kTriangleBytes;
    if (bulk_checksum(payload, size) != h.checksum) throw fail("checksum mismatch");
    PayloadReader r(payload);
    const std::size_t v0 = ids.size(), t0 = triangles.size(), nv = h.vertices, nt = h.triangles;
    r.take(ids, nv);
    r.take(positions, nv);
    r.take(sensors, nv);
    if ((h.flags & kHasIntensity) != 0) r.take(intensities, nv);
    if ((h.flags & kHasColor) != 0) r.take(colors, nv);
    r.take(triangles, nt);
    r.take(faces, nt);
    r.take(fans, nt);
    r.take(piece.triangle_index, nt);
    r.take(piece.roles, nt);
    // Block-local corners -> piece vertices (a vertex seen in an earlier block is reused).
    std::vector<std::uint32_t> remap(nv);
    for (std::size_t v = 0; v < nv; ++v) {
      const auto [it, added] = local.try_emplace(ids[v0 + v], static_cast<std::uint32_t>(piece.vertex_ids.size()));
      remap[v] = it->second;
      if (!added) continue;
      piece.vertex_ids.push_back(ids[v0 + v]);
      piece.mesh.positions.push_back(positions[v0 + v]);
      piece.mesh.sensor_positions.push_back(sensors[v0 + v]);
      if ((h.flags & kHasIntensity) != 0) piece.mesh.intensities.push_back(intensities[v0 + v]);
      if ((h.flags & kHasColor) != 0) piece.mesh.colors.push_back(colors[v0 + v]);
    }
    for (std::size_t t = t0; t < t0 + nt; ++t) {
      Triangle tri = triangles[t];
      for (std::uint32_t& c : tri) {
        if (c >= nv) throw fail(fmt::format("triangle {} uses vertex {} of {}", t - t0, c, nv));
        c = remap[c];
      }
      if (static_cast<std::uint8_t>(piece.roles[t]) > 2) throw fail(fmt::format("triangle {}: bad role", t - t0));
      piece.mesh.triangles.push_back(tri);
      piece.mesh.triangle_ids.push_back({acquisition, fans[t], faces[t]});
    }
    at += sizeof h + size;
  }
  // Blocks of one acquisition come from one file and carry the same attributes; keep an
  // attribute only when every vertex has it.
  if (piece.mesh.intensities.size() != piece.mesh.vertex_count()) piece.mesh.intensities.clear();
  if (piece.mesh.colors.size() != piece.mesh.vertex_count()) piece.mesh.colors.clear();
  return piece;
}

}  // namespace citymesh
