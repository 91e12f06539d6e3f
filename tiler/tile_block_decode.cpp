// SPDX-License-Identifier: MIT
// Reading the tile store's blocks: versions 6 to 3 (varints) and version 2 (fixed-size
// arrays), each checked against its own bytes before anything is allocated.
#include <fmt/format.h>

#include <array>
#include <bit>
#include <cstring>
#include <unordered_map>

#include "citymesh/core/checksum.h"
#include "citymesh/core/error.h"
#include "citymesh/core/varint.h"
#include "citymesh/tiler/tile_store.h"
#include "tile_block_format.h"

namespace citymesh {

using namespace tiler_detail;

namespace {

/// Reads consecutive arrays out of one block's payload.
class PayloadReader {
 public:
  explicit PayloadReader(const char* data) : data_(data) {}
  template <class T>
  void take(std::vector<T>& values, std::size_t count) {
    values.resize(count);
    std::memcpy(static_cast<void*>(values.data()), data_, count * sizeof(T));
    data_ += count * sizeof(T);
  }
  [[nodiscard]] const char* at() const { return data_; }

 private:
  const char* data_;
};

/// One block's arrays as stored: its corners index the block's own vertices.
struct BlockArrays {
  std::uint32_t flags = 0;
  std::vector<std::uint32_t> ids;
  std::vector<Vec3f> positions, sensors;
  std::vector<float> intensities;
  std::vector<Rgb8> colors;
  std::vector<Triangle> triangles;
  std::vector<std::uint64_t> faces;
  std::vector<std::uint32_t> fans, indices;
  std::vector<TileRole> roles;
};

/// Where a block lies, for its errors.
struct BlockPlace {
  std::string_view source;
  std::size_t block = 0, at = 0;
  [[nodiscard]] InputError fail(std::string_view what) const {
    return InputError(fmt::format("{}: block {} at byte {}: {}", source, block, at, what));
  }
};

/// Reads the version-2 block at the start of `bytes` into `b`; returns its size in bytes.
std::size_t read_fixed_block(std::string_view bytes, const BlockPlace& place, BlockArrays& b) {
  FixedBlockHeader h{};
  if (bytes.size() < sizeof h) throw place.fail("truncated header");
  std::memcpy(&h, bytes.data(), sizeof h);
  const std::uint64_t room = bytes.size() - sizeof h, vertex_bytes = fixed_vertex_bytes(h.start.flags);
  // Counts are checked against the bytes present before anything is allocated.
  if (h.vertices > room / vertex_bytes || h.triangles > room / kFixedTriangleBytes ||
      h.vertices * vertex_bytes + h.triangles * kFixedTriangleBytes > room) {
    throw place.fail("counts larger than the file (truncated?)");
  }
  const char* payload = bytes.data() + sizeof h;
  const std::uint64_t size = h.vertices * vertex_bytes + h.triangles * kFixedTriangleBytes;
  if (bulk_checksum(payload, size) != h.checksum) throw place.fail("checksum mismatch");
  b.flags = h.start.flags;
  const std::size_t nv = h.vertices, nt = h.triangles;
  PayloadReader r(payload);
  r.take(b.ids, nv);
  r.take(b.positions, nv);
  r.take(b.sensors, nv);
  if ((b.flags & kHasIntensity) != 0) r.take(b.intensities, nv);
  if ((b.flags & kHasColor) != 0) r.take(b.colors, nv);
  r.take(b.triangles, nt);
  r.take(b.faces, nt);
  r.take(b.fans, nt);
  r.take(b.indices, nt);
  r.take(b.roles, nt);
  return sizeof h + size;
}

/// The next value of the sequence `running` (see VarintReader::get_next), or an input error.
template <class Unsigned>
Unsigned next(VarintReader& in, Unsigned& running, const BlockPlace& place) {
  if (!in.get_next(running)) throw place.fail("a varint is truncated or out of range");
  return running;
}

/// Where a triangle's fan and role go, from the varint `fan_role` that holds them above
/// `low_bits` other bits.
void set_fan_role(std::uint64_t fan_role, unsigned low_bits, std::size_t t, const BlockPlace& place,
                  BlockArrays& b) {
  if (fan_role >> low_bits > UINT32_MAX) throw place.fail(fmt::format("triangle {}: fan out of range", t));
  b.fans[t] = static_cast<std::uint32_t>(fan_role >> low_bits);
  b.roles[t] = static_cast<TileRole>(fan_role & 3);
}

/// The next point of a sequence of points stored as varint deltas of their floats' bits.
Vec3f next_point(VarintReader& in, std::array<std::uint32_t, 3>& bits, const BlockPlace& place) {
  for (std::uint32_t& b : bits) next(in, b, place);
  return {std::bit_cast<float>(bits[0]), std::bit_cast<float>(bits[1]), std::bit_cast<float>(bits[2])};
}

/// A version-6 triangle's corners: the codes in the low bits of `shape` and the varints of the
/// corners coded kOther (see CornerWindow).
Triangle read_coded_corners(VarintReader& in, std::uint64_t shape, std::size_t t, const BlockPlace& place,
                            CornerWindow& window) {
  Triangle corners{};
  for (std::size_t k = 0; k < 3; ++k) {
    const std::uint64_t code_at = shape >> (CornerWindow::kCodeBits * (2 - k));
    const auto code = static_cast<std::uint32_t>(code_at & CornerWindow::kCodeMask);
    std::optional<std::uint64_t> corner;
    if (code == CornerWindow::kOther) {
      std::uint64_t distance = 0;
      if (!in.get(distance)) throw place.fail("a varint is truncated or out of range");
      corner = window.next_new() - unzigzag(distance);
    } else {
      corner = window.corner_of(code);
    }
    if (!corner || *corner > UINT32_MAX) {
      throw place.fail(fmt::format("triangle {}: corner {} stands for no vertex", t, k));
    }
    corners[k] = static_cast<std::uint32_t>(*corner);
    window.saw(*corner);
  }
  window.shift(corners);
  return corners;
}

/// The varint part of a version-6 to 3 payload (see TileBlockWriter).
void read_varints(VarintReader& in, std::uint32_t version, std::size_t nv, std::size_t nt, const BlockPlace& place,
                  BlockArrays& b) {
  b.ids.resize(nv);
  b.sensors.resize(nv);
  const bool has_positions = version >= kCornerDeltasVersion;  // versions 4 and 3 had them raw
  if (has_positions) b.positions.resize(nv);
  std::uint32_t id = 0;
  std::array<std::uint32_t, 3> position{}, sensor{};
  for (std::size_t v = 0; v < nv; ++v) {
    b.ids[v] = next(in, id, place);
    if (has_positions) b.positions[v] = next_point(in, position, place);
    b.sensors[v] = next_point(in, sensor, place);
  }
  b.triangles.resize(nt);
  b.faces.resize(nt);
  b.fans.resize(nt);
  b.indices.resize(nt);
  b.roles.resize(nt);
  std::uint32_t corner = 0, index = 0;
  std::uint64_t face = 0, fan_role = 0;
  CornerWindow window;
  const auto take_fan_role = [&] {
    if (!in.get(fan_role)) throw place.fail("a varint is truncated or out of range");
  };
  for (std::size_t t = 0; t < nt; ++t) {
    if (version >= kVersion) {
      take_fan_role();
      b.triangles[t] = read_coded_corners(in, fan_role, t, place, window);
      fan_role >>= CornerWindow::kTriangleCodeBits;
    } else {
      for (std::uint32_t& c : b.triangles[t]) c = next(in, corner, place);
      if (version >= kRawPositionsVersion) take_fan_role();
    }
    if (version >= kRawPositionsVersion) {
      set_fan_role(fan_role, 3, t, place, b);
      if ((fan_role & kSteps) != 0) {
        ++face;
        ++index;
      } else {
        next(in, face, place);
        next(in, index, place);
      }
    } else {
      next(in, face, place);
      next(in, index, place);
      take_fan_role();
      set_fan_role(fan_role, 2, t, place, b);
    }
    b.faces[t] = face;
    b.indices[t] = index;
  }
}

/// Reads the version-6 to 3 block at the start of `bytes` into `b`; returns its size in bytes.
std::size_t read_varint_block(std::string_view bytes, const BlockPlace& place, BlockArrays& b) {
  BlockHeader h{};
  if (bytes.size() < sizeof h) throw place.fail("truncated header");
  std::memcpy(&h, bytes.data(), sizeof h);
  if (h.payload_bytes > bytes.size() - sizeof h) throw place.fail("payload larger than the file (truncated?)");
  // Counts are checked against the payload before anything is allocated.
  const std::uint32_t version = h.start.version;
  const std::uint64_t size = h.payload_bytes;
  const std::uint64_t per_vertex = raw_vertex_bytes(h.start.flags, version) + min_varints_per_vertex(version);
  const std::uint64_t per_triangle = min_varints_per_triangle(version);
  if (h.vertices > size / per_vertex || h.triangles > size / per_triangle ||
      h.vertices * per_vertex + h.triangles * per_triangle > size) {
    throw place.fail("counts larger than the block");
  }
  const char* payload = bytes.data() + sizeof h;
  if (bulk_checksum(payload, size) != h.checksum) throw place.fail("checksum mismatch");
  b.flags = h.start.flags;
  const std::size_t nv = h.vertices, nt = h.triangles;
  PayloadReader r(payload);
  if (version < kCornerDeltasVersion) r.take(b.positions, nv);
  if ((b.flags & kHasIntensity) != 0) r.take(b.intensities, nv);
  if ((b.flags & kHasColor) != 0) r.take(b.colors, nv);
  VarintReader in(r.at(), payload + size);
  read_varints(in, version, nv, nt, place, b);
  if (!in.at_end()) throw place.fail("bytes left after the triangles");
  return sizeof h + size;
}

/// Appends block `b` to `piece`; a vertex whose id an earlier block had is that block's copy.
void merge_block(const BlockArrays& b, const BlockPlace& place, std::uint32_t acquisition,
                 std::unordered_map<std::uint32_t, std::uint32_t>& local, TilePiece& piece) {
  const std::size_t nv = b.ids.size(), nt = b.triangles.size();
  // The first block gets exact room (a piece is mostly one block): growth by doubling would
  // leave up to twice the memory in every piece the assembly holds for the whole city. Later
  // blocks grow the arrays geometrically, as usual.
  Mesh& m = piece.mesh;
  if (piece.vertex_ids.empty() && m.triangles.empty()) {
    piece.vertex_ids.reserve(nv);
    m.positions.reserve(nv);
    m.sensor_positions.reserve(nv);
    if ((b.flags & kHasIntensity) != 0) m.intensities.reserve(nv);
    if ((b.flags & kHasColor) != 0) m.colors.reserve(nv);
    m.triangles.reserve(nt);
    m.triangle_ids.reserve(nt);
    piece.triangle_index.reserve(nt);
    piece.roles.reserve(nt);
  }
  std::vector<std::uint32_t> remap(nv);
  for (std::size_t v = 0; v < nv; ++v) {
    const auto [it, added] = local.try_emplace(b.ids[v], static_cast<std::uint32_t>(piece.vertex_ids.size()));
    remap[v] = it->second;
    if (!added) continue;
    piece.vertex_ids.push_back(b.ids[v]);
    m.positions.push_back(b.positions[v]);
    m.sensor_positions.push_back(b.sensors[v]);
    if ((b.flags & kHasIntensity) != 0) m.intensities.push_back(b.intensities[v]);
    if ((b.flags & kHasColor) != 0) m.colors.push_back(b.colors[v]);
  }
  for (std::size_t t = 0; t < nt; ++t) {
    Triangle tri = b.triangles[t];
    for (std::uint32_t& c : tri) {
      if (c >= nv) throw place.fail(fmt::format("triangle {} uses vertex {} of {}", t, c, nv));
      c = remap[c];
    }
    if (static_cast<std::uint8_t>(b.roles[t]) > 2) throw place.fail(fmt::format("triangle {}: bad role", t));
    m.triangles.push_back(tri);
    m.triangle_ids.push_back({acquisition, b.fans[t], b.faces[t]});
    piece.triangle_index.push_back(b.indices[t]);
    piece.roles.push_back(b.roles[t]);
  }
}

}  // namespace

TilePiece decode_tile_blocks(std::string_view bytes, const Vec3d& origin, std::uint32_t acquisition,
                             std::string_view source) {
  TilePiece piece;
  piece.mesh.origin = origin;
  std::unordered_map<std::uint32_t, std::uint32_t> local;  // vertex id -> index in the piece
  BlockPlace place{source, 0, 0};
  BlockArrays block;  // reused: each block's arrays take the place of the last one's
  for (; place.at < bytes.size(); ++place.block) {
    const std::string_view rest = bytes.substr(place.at);
    BlockStart start{};
    if (rest.size() < sizeof start) throw place.fail("truncated header");
    std::memcpy(&start, rest.data(), sizeof start);
    if (std::memcmp(start.magic, kMagic, sizeof kMagic) != 0) throw place.fail("not a citymesh tile block");
    if (start.version >= kFullIdsVersion && start.version <= kVersion) {
      place.at += read_varint_block(rest, place, block);
    } else if (start.version == kFixedVersion) {
      place.at += read_fixed_block(rest, place, block);
    } else {
      throw place.fail(fmt::format("version {} (this build reads {} to {})", start.version, kFixedVersion, kVersion));
    }
    merge_block(block, place, acquisition, local, piece);
  }
  // Blocks of one acquisition come from one file and carry the same attributes; keep an
  // attribute only when every vertex has it.
  if (piece.mesh.intensities.size() != piece.mesh.vertex_count()) piece.mesh.intensities.clear();
  if (piece.mesh.colors.size() != piece.mesh.vertex_count()) piece.mesh.colors.clear();
  return piece;
}

}  // namespace citymesh
