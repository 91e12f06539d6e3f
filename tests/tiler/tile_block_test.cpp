// SPDX-License-Identifier: MIT
// The tile store's block codec: version 3 (varint deltas) round-trips any values, is under
// half the size of version 2 on scan-ordered data, still reads version-2 blocks, and turns
// damage that a checksum cannot see (re-checksummed garbage) into input errors.
#include <gtest/gtest.h>

#include <cstring>
#include <random>

#include "citymesh/core/checksum.h"
#include "citymesh/core/error.h"
#include "citymesh/tiler/tile_store.h"

namespace citymesh {
namespace {

constexpr std::uint32_t kAcquisition = 7;
const Vec3d kOrigin{651000, 6860000, 0};

/// A piece of `nv` vertices and `nt` triangles. `scan_order`: ids, faces and indices grow by
/// one and sensors move a little, as the tiler writes them; otherwise every value is random
/// over its whole range (ids and indices going backwards, faces near 2^64, any fan).
TilePiece make_piece(std::uint32_t seed, std::size_t nv, std::size_t nt, bool scan_order) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<float> coordinate(-60, 60);
  TilePiece p;
  p.mesh.origin = kOrigin;
  Vec3f sensor{-5, 12, 2.5f};
  for (std::size_t v = 0; v < nv; ++v) {
    // Distinct ids: decoding merges equal ids into one vertex.
    p.vertex_ids.push_back(scan_order ? static_cast<std::uint32_t>(1000 + v)
                                      : static_cast<std::uint32_t>((rng() & 0xffff0000u) | v));
    p.mesh.positions.push_back({coordinate(rng), coordinate(rng), coordinate(rng)});
    sensor = scan_order ? sensor + Vec3f{1e-4f, 0, 0} : Vec3f{coordinate(rng), coordinate(rng), coordinate(rng)};
    p.mesh.sensor_positions.push_back(sensor);
    p.mesh.intensities.push_back(coordinate(rng));
    p.mesh.colors.push_back({static_cast<std::uint8_t>(rng()), static_cast<std::uint8_t>(rng()), 3});
  }
  for (std::size_t t = 0; t < nt; ++t) {
    const auto corner = [&] { return static_cast<std::uint32_t>(rng() % nv); };
    p.mesh.triangles.push_back(scan_order ? Triangle{static_cast<std::uint32_t>(t % nv),
                                                     static_cast<std::uint32_t>((t + 1) % nv),
                                                     static_cast<std::uint32_t>((t + 2) % nv)}
                                          : Triangle{corner(), corner(), corner()});
    const std::uint64_t face = scan_order ? 5000 + t : rng();
    const auto fan = scan_order ? 0u : static_cast<std::uint32_t>(rng());
    p.mesh.triangle_ids.push_back({kAcquisition, fan, face});
    p.triangle_index.push_back(scan_order ? static_cast<std::uint32_t>(t) : static_cast<std::uint32_t>(rng()));
    p.roles.push_back(static_cast<TileRole>(rng() % 3));
  }
  return p;
}

void expect_same(const TilePiece& a, const TilePiece& b) {
  EXPECT_EQ(a.vertex_ids, b.vertex_ids);
  EXPECT_EQ(a.mesh.positions, b.mesh.positions);
  EXPECT_EQ(a.mesh.sensor_positions, b.mesh.sensor_positions);
  EXPECT_EQ(a.mesh.intensities, b.mesh.intensities);
  EXPECT_EQ(a.mesh.colors, b.mesh.colors);
  EXPECT_EQ(a.mesh.triangles, b.mesh.triangles);
  EXPECT_EQ(a.mesh.triangle_ids, b.mesh.triangle_ids);
  EXPECT_EQ(a.triangle_index, b.triangle_index);
  EXPECT_EQ(a.roles, b.roles);
}

TEST(TileBlock, AnyValuesRoundTrip) {
  for (const bool scan_order : {false, true}) {
    const TilePiece piece = make_piece(3, 500, 900, scan_order);
    expect_same(piece, decode_tile_blocks(encode_tile_block(piece), kOrigin, kAcquisition, "test"));
  }
}

TEST(TileBlock, ScanOrderedBlocksTakeUnderHalfOfTheFixedLayout) {
  const TilePiece piece = make_piece(4, 4000, 8000, true);
  // Version 2: 40-byte header, 4 + 12 + 12 + 4 + 3 bytes per vertex, 29 per triangle.
  const std::size_t fixed = 40 + 35 * 4000 + 29 * 8000;
  EXPECT_LT(encode_tile_block(piece).size(), fixed / 2);
}

/// `piece` in version 2's layout (header: magic, version, flags, vertices, triangles, XXH3;
/// then vertex ids, positions, sensors, intensities, colours, triangles, faces, fans, triangle
/// indices, roles), as builds before version 3 wrote it.
std::string fixed_layout_block(const TilePiece& p) {
  std::string payload;
  const auto add = [&](const auto& values) {
    payload.append(reinterpret_cast<const char*>(values.data()), values.size() * sizeof(values[0]));
  };
  std::vector<std::uint64_t> faces;
  std::vector<std::uint32_t> fans;
  for (const TriangleId& id : p.mesh.triangle_ids) {
    faces.push_back(id.face);
    fans.push_back(id.fan);
  }
  add(p.vertex_ids);
  add(p.mesh.positions);
  add(p.mesh.sensor_positions);
  add(p.mesh.intensities);
  add(p.mesh.colors);
  add(p.mesh.triangles);
  add(faces);
  add(fans);
  add(p.triangle_index);
  add(p.roles);
  std::string block("CMTILE01");
  const std::uint32_t version = 2, flags = 3;
  const std::uint64_t counts[3] = {p.vertex_ids.size(), p.triangle_index.size(),
                                   bulk_checksum(payload.data(), payload.size())};
  block.append(reinterpret_cast<const char*>(&version), 4);
  block.append(reinterpret_cast<const char*>(&flags), 4);
  block.append(reinterpret_cast<const char*>(counts), sizeof counts);
  return block + payload;
}

TEST(TileBlock, VersionTwoBlocksStillRead) {
  const TilePiece a = make_piece(5, 300, 400, false), b = make_piece(6, 200, 100, true);
  // A chunk of old blocks followed by a new one (a resumed run appending): both read.
  const TilePiece back =
      decode_tile_blocks(fixed_layout_block(a) + encode_tile_block(b), kOrigin, kAcquisition, "test");
  ASSERT_EQ(back.triangle_count(), a.triangle_count() + b.triangle_count());
  ASSERT_EQ(back.vertex_ids.size(), a.vertex_ids.size() + b.vertex_ids.size());
  for (std::size_t t = 0; t < back.triangle_count(); ++t) {
    const bool first = t < a.triangle_count();
    const TilePiece& src = first ? a : b;
    const std::size_t s = first ? t : t - a.triangle_count();
    ASSERT_EQ(back.mesh.triangle_ids[t], src.mesh.triangle_ids[s]);
    ASSERT_EQ(back.triangle_index[t], src.triangle_index[s]);
    for (std::size_t k = 0; k < 3; ++k) {
      const std::uint32_t v = back.mesh.triangles[t][k], w = src.mesh.triangles[s][k];
      ASSERT_EQ(back.vertex_ids[v], src.vertex_ids[w]);
      ASSERT_EQ(back.mesh.sensor_positions[v], src.mesh.sensor_positions[w]);
    }
  }
}

/// Re-checksums a version-3 block after its payload was changed, so that only the decoder's
/// own checks stand between the damage and the piece.
void recompute_checksum(std::string& block) {
  std::uint64_t payload = 0;
  std::memcpy(&payload, block.data() + 32, 8);
  const std::uint64_t sum = bulk_checksum(block.data() + 48, std::min<std::uint64_t>(payload, block.size() - 48));
  std::memcpy(block.data() + 40, &sum, 8);
}

TEST(TileBlock, DamageUnderAValidChecksumIsAnInputErrorNeverACrash) {
  const std::string good = encode_tile_block(make_piece(8, 60, 90, true));
  std::mt19937 rng(9);
  int errors = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    std::string block = good;
    // Bytes of the payload (raw floats first, varints after), or a count in the header.
    const std::size_t at = trial % 10 == 0 ? 16 + rng() % 24 : 48 + rng() % (good.size() - 48);
    block[at] = static_cast<char>(rng());
    if (trial % 3 == 0) block.resize(block.size() - 1 - rng() % 8);
    recompute_checksum(block);
    try {
      (void)decode_tile_blocks(block, kOrigin, kAcquisition, "damaged.bin");
    } catch (const InputError& e) {
      ++errors;
      EXPECT_NE(std::string(e.what()).find("damaged.bin: block 0"), std::string::npos) << e.what();
    }
  }
  // A changed float still decodes (nothing can tell); most other damage cannot.
  EXPECT_GT(errors, 500);
}

}  // namespace
}  // namespace citymesh
