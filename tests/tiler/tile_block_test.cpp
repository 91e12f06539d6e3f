// SPDX-License-Identifier: MIT
// The tile store's block codec: version 6 (varint deltas, positions among them, corners coded
// against the two previous triangles, faces and indices that step by one left out)
// round-trips any values, is under half the size of version 2 on scan-ordered data, takes
// two bytes a triangle there where version 5 took four, still reads version-5 to 2 blocks
// (written here by an independent oracle), and turns damage that a checksum cannot see
// (re-checksummed garbage) into input errors.
#include <gtest/gtest.h>

#include <array>
#include <bit>
#include <cstring>
#include <random>

#include "citymesh/core/checksum.h"
#include "citymesh/core/error.h"
#include "citymesh/core/varint.h"
#include "citymesh/tiler/tile_store.h"

namespace citymesh {
namespace {

constexpr std::uint32_t kAcquisition = 7;
const Vec3d kOrigin{651000, 6860000, 0};

/// A piece of `nv` vertices and `nt` triangles. `scan_order`: ids, faces and indices grow by
/// one, points along a scan line a few millimetres apart and sensors move a little, as the
/// tiler writes them; otherwise every value is random over its whole range (ids and indices
/// going backwards, faces near 2^64, any fan).
TilePiece make_piece(std::uint32_t seed, std::size_t nv, std::size_t nt, bool scan_order) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<float> coordinate(-60, 60);
  TilePiece p;
  p.mesh.origin = kOrigin;
  Vec3f sensor{-5, 12, 2.5f}, point{20, 30, 4};
  for (std::size_t v = 0; v < nv; ++v) {
    // Distinct ids: decoding merges equal ids into one vertex.
    p.vertex_ids.push_back(scan_order ? static_cast<std::uint32_t>(1000 + v)
                                      : static_cast<std::uint32_t>((rng() & 0xffff0000u) | v));
    point = scan_order ? point + Vec3f{2e-3f, -1e-3f, 3e-3f} : Vec3f{coordinate(rng), coordinate(rng), coordinate(rng)};
    p.mesh.positions.push_back(point);
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

/// `p` with breaks in its steps: some faces repeat (a polygon's fan), some jump, some indices
/// jump (a halo copy after a gap), at random places, and the last face and index wrap around.
TilePiece with_broken_steps(TilePiece p, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uint64_t face_shift = 0;
  std::uint32_t index_shift = 0;
  for (std::size_t t = 0; t < p.triangle_count(); ++t) {
    TriangleId& id = p.mesh.triangle_ids[t];
    const unsigned kind = rng() % 8;
    if (kind == 0 && t > 0) {
      id.fan = p.mesh.triangle_ids[t - 1].fan + 1;
      face_shift -= 1;
    }
    if (kind == 1) face_shift += rng() % 1000;
    if (kind == 2) index_shift += static_cast<std::uint32_t>(rng() % 1000);
    id.face += face_shift;
    p.triangle_index[t] += index_shift;
  }
  p.mesh.triangle_ids.back().face = UINT64_MAX;
  p.triangle_index.back() = UINT32_MAX;
  p.mesh.triangle_ids.push_back({kAcquisition, 0, 0});  // both wrap to 0 from their maximum
  p.triangle_index.push_back(0);
  p.mesh.triangles.push_back(p.mesh.triangles.back());
  p.roles.push_back(TileRole::halo);
  return p;
}

TEST(TileBlock, AnyValuesRoundTrip) {
  for (const bool scan_order : {false, true}) {
    const TilePiece piece = make_piece(3, 500, 900, scan_order);
    expect_same(piece, decode_tile_blocks(encode_tile_block(piece), kOrigin, kAcquisition, "test"));
  }
  const TilePiece broken = with_broken_steps(make_piece(3, 500, 900, true), 11);
  expect_same(broken, decode_tile_blocks(encode_tile_block(broken), kOrigin, kAcquisition, "test"));
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

/// `p` in the layout of version 3, 4 or 5, as builds before version 6 wrote it: version 6's
/// header; in versions 3 and 4 the raw positions; intensities, colours; per vertex the varint
/// deltas of id (version 5: then position bits) and sensor bits; per triangle those of the
/// corners, then in version 3 the face, the index and fan << 2 | role, from version 4 on fan
/// << 3 | steps << 2 | role and the face and index unless they step by one.
std::string varint_block(const TilePiece& p, std::uint32_t version) {
  std::string payload;
  const auto add = [&](const auto& values) {
    payload.append(reinterpret_cast<const char*>(values.data()), values.size() * sizeof(values[0]));
  };
  if (version < 5) add(p.mesh.positions);
  add(p.mesh.intensities);
  add(p.mesh.colors);
  VarintWriter vertices(p.vertex_ids.size() * 7 * max_varint_bytes(32));
  std::uint32_t id = 0;
  std::array<std::uint32_t, 3> position{}, sensor{};
  const auto put_point = [&](const Vec3f& x, std::array<std::uint32_t, 3>& running) {
    vertices.put_next(std::bit_cast<std::uint32_t>(x.x), running[0]);
    vertices.put_next(std::bit_cast<std::uint32_t>(x.y), running[1]);
    vertices.put_next(std::bit_cast<std::uint32_t>(x.z), running[2]);
  };
  for (std::size_t v = 0; v < p.vertex_ids.size(); ++v) {
    vertices.put_next(p.vertex_ids[v], id);
    if (version == 5) put_point(p.mesh.positions[v], position);
    put_point(p.mesh.sensor_positions[v], sensor);
  }
  VarintWriter triangles(p.triangle_count() * 6 * max_varint_bytes(64));
  std::uint32_t corner = 0, index = 0;
  std::uint64_t face = 0;
  for (std::size_t t = 0; t < p.triangle_count(); ++t) {
    for (const std::uint32_t c : p.mesh.triangles[t]) triangles.put_next(c, corner);
    const std::uint64_t fan = p.mesh.triangle_ids[t].fan, role = static_cast<std::uint8_t>(p.roles[t]);
    const std::uint64_t next_face = p.mesh.triangle_ids[t].face;
    const std::uint32_t next_index = p.triangle_index[t];
    const bool steps = version >= 4 && next_face == face + 1 && next_index == index + 1;
    if (version >= 4) triangles.put(fan << 3 | (steps ? 4 : 0) | role);
    if (steps) {
      face = next_face;
      index = next_index;
    } else {
      triangles.put_next(next_face, face);
      triangles.put_next(next_index, index);
    }
    if (version == 3) triangles.put(fan << 2 | role);
  }
  payload += vertices.bytes();
  payload += triangles.bytes();
  std::string block("CMTILE01");
  const std::uint32_t flags = 3;
  const std::uint64_t header[4] = {p.vertex_ids.size(), p.triangle_index.size(), payload.size(),
                                   bulk_checksum(payload.data(), payload.size())};
  block.append(reinterpret_cast<const char*>(&version), 4);
  block.append(reinterpret_cast<const char*>(&flags), 4);
  block.append(reinterpret_cast<const char*>(header), sizeof header);
  return block + payload;
}

TEST(TileBlock, VersionFourTakesTwoBytesATriangleLessThanVersionThreeOnScanOrderedData) {
  const TilePiece piece = make_piece(4, 4000, 8000, true);
  // Every triangle but the first (whose face and index start from 0) steps.
  EXPECT_EQ(varint_block(piece, 3).size() - varint_block(piece, 4).size(), 2 * (8000 - 1));
}

TEST(TileBlock, VersionFiveStoresScanOrderedPositionsInUnderTwoThirdsOfTheirRawBytes) {
  const TilePiece piece = make_piece(4, 4000, 8000, true);
  // Version 4 stored 12 raw bytes per position; steps of a few millimetres at some ten metres
  // are a few thousand steps of the floats' bits, two bytes a coordinate. Everything else is
  // stored as in version 4.
  const std::size_t saved = varint_block(piece, 4).size() - varint_block(piece, 5).size();
  EXPECT_GE(saved, 4000 * (12 - 7));
  EXPECT_LE(saved, 4000 * (12 - 3));
}

TEST(TileBlock, VersionSixTakesTwoBytesForATriangleOfAStrip) {
  // A strip that stops before it wraps back to vertex 0: each triangle shares two corners with
  // the one before and brings the next new vertex, so version 6 stores only the varint of fan,
  // steps, role and corner codes (two bytes) where version 5 stored three corner deltas and
  // that of fan, steps and role (four).
  const TilePiece piece = make_piece(4, 4000, 3998, true);
  EXPECT_EQ(varint_block(piece, 5).size() - encode_tile_block(piece).size(), 2 * 3998);
}

/// Triangles of a grid of `columns` x `rows` vertices, two per cell, cell after cell along
/// each row, as a scan-line mesh is; vertices are numbered in order of first use, as the
/// tiler numbers a block's.
TilePiece grid_piece(std::uint32_t columns, std::uint32_t rows) {
  TilePiece p;
  p.mesh.origin = kOrigin;
  std::vector<std::uint32_t> local(std::size_t{columns} * rows, UINT32_MAX);
  const auto vertex = [&](std::uint32_t c, std::uint32_t r) {
    std::uint32_t& v = local[std::size_t{r} * columns + c];
    if (v == UINT32_MAX) {
      v = static_cast<std::uint32_t>(p.vertex_ids.size());
      p.vertex_ids.push_back(r * columns + c);
      p.mesh.positions.push_back({0.05f * static_cast<float>(c), 0.05f * static_cast<float>(r), 3});
      p.mesh.sensor_positions.push_back({0, 0, 2});
    }
    return v;
  };
  for (std::uint32_t r = 0; r + 1 < rows; ++r) {
    for (std::uint32_t c = 0; c + 1 < columns; ++c) {
      const auto add = [&](Triangle t) {
        p.mesh.triangles.push_back(t);
        p.mesh.triangle_ids.push_back({kAcquisition, 0, p.triangle_index.size()});
        p.triangle_index.push_back(static_cast<std::uint32_t>(p.triangle_index.size()));
        p.roles.push_back(TileRole::owned);
      };
      add({vertex(c, r), vertex(c + 1, r), vertex(c, r + 1)});
      add({vertex(c + 1, r), vertex(c + 1, r + 1), vertex(c, r + 1)});
    }
  }
  return p;
}

TEST(TileBlock, GridMeshesRoundTripInThreeBytesATriangle) {
  const TilePiece piece = grid_piece(300, 40);
  const std::string block = encode_tile_block(piece);
  expect_same(piece, decode_tile_blocks(block, kOrigin, kAcquisition, "grid"));
  // Beyond the first row of cells, a cell's first triangle names one corner (the vertex a row
  // back, two bytes of distance) and its second none: six bytes a cell with the two codes'
  // varints. Version 5 took eight (two corner deltas a row long).
  TilePiece vertices_only = piece;
  vertices_only.mesh.triangles.clear();
  vertices_only.mesh.triangle_ids.clear();
  vertices_only.triangle_index.clear();
  vertices_only.roles.clear();
  const std::size_t vertex_bytes = encode_tile_block(vertices_only).size();
  const std::size_t triangles = piece.triangle_count();
  EXPECT_LE(block.size() - vertex_bytes, 3 * triangles);
  EXPECT_GE(varint_block(piece, 5).size() - block.size(), triangles / 2);
}

/// Checks that `back` is `a`'s triangles, then `b`'s, with their vertices (ids are distinct
/// between the two).
void expect_concatenation(const TilePiece& back, const TilePiece& a, const TilePiece& b) {
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

TEST(TileBlock, OlderVersionsStillRead) {
  const TilePiece a = make_piece(5, 300, 400, false), b = make_piece(6, 200, 100, true);
  // A chunk of old blocks followed by a new one (a resumed run appending): both read.
  SCOPED_TRACE("version 2");
  expect_concatenation(decode_tile_blocks(fixed_layout_block(a) + encode_tile_block(b), kOrigin, kAcquisition, "2"),
                       a, b);
  TilePiece c = with_broken_steps(make_piece(7, 200, 300, true), 12);
  for (std::uint32_t& id : c.vertex_ids) id += 100000;  // apart from b's
  for (const std::uint32_t version : {3u, 4u, 5u}) {
    SCOPED_TRACE(version);
    expect_concatenation(decode_tile_blocks(varint_block(a, version) + encode_tile_block(b), kOrigin, kAcquisition, ""),
                         a, b);
    expect_concatenation(decode_tile_blocks(varint_block(c, version) + encode_tile_block(b), kOrigin, kAcquisition, ""),
                         c, b);
  }
}

/// Re-checksums a block of version 3 or later after its payload was changed, so that only the decoder's
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
    // Bytes of the payload (raw intensities and colours first, varints after), or a count in
    // the header.
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
  // A changed intensity or colour still decodes (nothing can tell); most other damage cannot.
  EXPECT_GT(errors, 500);
}

}  // namespace
}  // namespace citymesh
