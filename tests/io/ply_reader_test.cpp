// SPDX-License-Identifier: MIT
#include <fmt/format.h>
#include <gtest/gtest.h>

#include "citymesh/core/error.h"
#include "citymesh/io/mesh_io.h"
#include "citymesh/io/ply_inspect.h"
#include "citymesh/io/ply_reader.h"
#include "ply_builder.h"
#include "test_support.h"

namespace citymesh {
namespace {

using test::ElementSpec;
using test::PropSpec;

constexpr PlyFormat kFormats[] = {PlyFormat::ascii, PlyFormat::binary_little_endian, PlyFormat::binary_big_endian};

/// A strip of `n` quads (2n + 2 vertices) with sensor positions 2 m above, as one element set
/// using the given coordinate and index types.
std::vector<ElementSpec> quad_strip(int n, PlyScalar coord, PlyScalar index, PlyScalar count = PlyScalar::uint8) {
  ElementSpec v{"vertex", {{"x", coord}, {"y", coord}, {"z", coord}, {"x_origin", coord}, {"y_origin", coord},
                           {"z_origin", coord}, {"gps_time", PlyScalar::float64}}, {}};
  for (int i = 0; i <= n; ++i) {
    for (int j = 0; j < 2; ++j) {
      v.rows.push_back({{double(i)}, {double(j)}, {0.5}, {double(i)}, {0.5}, {2.5}, {1000.0 + i}});
    }
  }
  ElementSpec f{"face", {{"vertex_indices", index, true, count}}, {}};
  for (int i = 0; i < n; ++i) {
    f.rows.push_back({{double(2 * i), double(2 * i + 2), double(2 * i + 3), double(2 * i + 1)}});
  }
  return {v, f};
}

MeshReadResult read_text(const std::string& ply, MeshReadParams params = {}) {
  test::TempDir dir;
  test::write_text(dir / "m.ply", ply);
  return read_mesh(dir / "m.ply", params);
}

TEST(PlyReader, AllFormatsAndTypesGiveTheSameMesh) {
  const Mesh reference = read_text(test::build_ply(PlyFormat::ascii, quad_strip(5, PlyScalar::float64, PlyScalar::int32))).mesh;
  ASSERT_EQ(reference.vertex_count(), 12u);
  ASSERT_EQ(reference.triangle_count(), 10u);
  for (PlyFormat format : kFormats) {
    for (PlyScalar coord : {PlyScalar::float32, PlyScalar::float64, PlyScalar::int16, PlyScalar::uint8}) {
      for (PlyScalar index : {PlyScalar::uint8, PlyScalar::int16, PlyScalar::uint32}) {
        SCOPED_TRACE(fmt::format("{} {} {}", ply_format_name(format), ply_scalar_name(coord), ply_scalar_name(index)));
        auto strip = quad_strip(5, coord, index, PlyScalar::uint16);
        if (coord == PlyScalar::int16 || coord == PlyScalar::uint8) {
          for (auto& row : strip[0].rows) row[2] = row[5] = {1.0};  // integers only
        }
        const Mesh m = read_text(test::build_ply(format, strip)).mesh;
        EXPECT_EQ(m.triangles, reference.triangles);
        EXPECT_EQ(m.triangle_ids, reference.triangle_ids);
        EXPECT_EQ(m.times, reference.times);
        for (std::size_t v = 0; v < m.vertex_count(); ++v) {
          EXPECT_EQ(m.world_position(v).x, reference.world_position(v).x);
          EXPECT_EQ(m.world_position(v).y, reference.world_position(v).y);
        }
      }
    }
  }
}

TEST(PlyReader, PolygonsAreFanTriangulatedKeepingTheirFaceIndex) {
  auto elements = quad_strip(1, PlyScalar::float32, PlyScalar::int32);
  elements[1].rows.push_back({{0, 1, 3, 2, 0}});  // a pentagon repeating a vertex
  MeshReadParams params;
  params.acquisition = 4;
  const MeshReadResult r = read_text(test::build_ply(PlyFormat::binary_little_endian, elements), params);
  // quad 0,2,3,1 -> (0,2,3) (0,3,1); pentagon 0,1,3,2,0 -> (0,1,3) (0,3,2) and (0,2,0) dropped
  const std::vector<Triangle> expected{{0, 2, 3}, {0, 3, 1}, {0, 1, 3}, {0, 3, 2}};
  EXPECT_EQ(r.mesh.triangles, expected);
  const std::vector<TriangleId> ids{{4, 0, 0}, {4, 1, 0}, {4, 0, 1}, {4, 1, 1}};
  EXPECT_EQ(r.mesh.triangle_ids, ids);
  EXPECT_EQ(r.stats.polygons_split, 2u);
  EXPECT_EQ(r.stats.degenerate_dropped, 1u);
}

TEST(PlyReader, DegenerateFacesAreDroppedAndCounted) {
  auto elements = quad_strip(2, PlyScalar::float32, PlyScalar::int32);
  elements[1].rows = {{{0, 0, 1}}, {{0, 1}}, {{0, 2, 4}}, {{0, 2, 3}}};  // repeat, 2-gon, collinear, good
  const MeshReadResult r = read_text(test::build_ply(PlyFormat::ascii, elements));
  EXPECT_EQ(r.stats.degenerate_dropped, 2u);
  EXPECT_EQ(r.zero_area_dropped, 1u);
  ASSERT_EQ(r.mesh.triangle_count(), 1u);
  EXPECT_EQ(r.mesh.triangle_ids[0].face, 3u);
}

TEST(PlyReader, ChunkSizeDoesNotChangeTheResult) {
  const std::string ply = test::build_ply(PlyFormat::binary_big_endian, quad_strip(40, PlyScalar::float32, PlyScalar::int32));
  const Mesh whole = read_text(ply).mesh;
  for (std::size_t rows : {1u, 3u, 64u}) {
    MeshReadParams params;
    params.ply.chunk_rows = rows;
    const Mesh chunked = read_text(ply, params).mesh;
    EXPECT_EQ(chunked.positions, whole.positions);
    EXPECT_EQ(chunked.triangles, whole.triangles);
    EXPECT_EQ(chunked.triangle_ids, whole.triangle_ids);
  }
}

TEST(PlyReader, ChunksAreBoundedAndInFileOrder) {
  test::TempDir dir;
  test::write_text(dir / "m.ply", test::build_ply(PlyFormat::binary_little_endian, quad_strip(50, PlyScalar::float32, PlyScalar::int32)));
  PlyReadParams params;
  params.chunk_rows = 16;
  PlyReader reader(dir / "m.ply", params);
  PlyVertexChunk v;
  PlyFaceChunk f;
  std::uint64_t next_vertex = 0, next_face = 0;
  bool faces_started = false;
  for (auto kind = reader.next(v, f); kind != PlyReader::ChunkKind::end; kind = reader.next(v, f)) {
    if (kind == PlyReader::ChunkKind::vertices) {
      EXPECT_FALSE(faces_started);
      EXPECT_EQ(v.first, next_vertex);
      EXPECT_LE(v.positions.size(), 16u);
      next_vertex += v.positions.size();
    } else {
      faces_started = true;
      EXPECT_EQ(f.first_face, next_face);
      EXPECT_LE(f.triangles.size(), 32u);  // 16 quads at most
      next_face += 16;
    }
  }
  EXPECT_EQ(next_vertex, 102u);
  EXPECT_EQ(reader.stats().faces, 50u);
  EXPECT_EQ(reader.stats().triangles, 100u);
}

/// One triangle at (x, y) in the CRS, after an unused first vertex at (first_x, y): ASCII, with
/// sensor positions 2 m above each point.
std::string triangle_after_unused_vertex(double first_x, double x, double y) {
  std::string ply =
      "ply\nformat ascii 1.0\nelement vertex 4\nproperty double x\nproperty double y\nproperty double z\n"
      "property double x_origin\nproperty double y_origin\nproperty double z_origin\nelement face 1\n"
      "property list uchar int vertex_indices\nend_header\n";
  const auto row = [](double px, double py) { return fmt::format("{:.3f} {:.3f} 30 {:.3f} {:.3f} 32\n", px, py, px, py); };
  ply += row(first_x, y) + row(x, y) + row(x + 1, y) + row(x, y + 1);
  return ply + "3 1 2 3\n";
}

TEST(PlyReader, UsedVerticesFarFromTheFrameOriginAreAnError) {
  // A corrupt first vertex, unused, sets the frame origin a million kilometres away: the
  // triangle's floats would have no metres left, and it was read all the same.
  try {
    read_text(triangle_after_unused_vertex(1e9, 650000, 6860000));
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("m.ply: face 0: vertex 1 lies"), std::string::npos) << what;
    EXPECT_NE(what.find("frame origin"), std::string::npos) << what;
  }
  // An acquisition in another CRS than the frame it is read into (origin given, 1 400 km off).
  MeshReadParams other_frame;
  other_frame.origin = Vec3d{650000, 6860000, 0};
  EXPECT_THROW(read_text(triangle_after_unused_vertex(450000, 450000, 5400000), other_frame), InputError);
  // Within the limit (an unused vertex 90 km away still sets the origin): read, to the millimetre.
  const Mesh m = read_text(triangle_after_unused_vertex(560000, 650000, 6860000)).mesh;
  ASSERT_EQ(m.triangle_count(), 1u);
  EXPECT_NEAR(m.world_position(2).x, 650001.0, 0.01);
}

TEST(PlyReader, IgnOffsetCommentsMakeCoordinatesAbsolute) {
  for (const char* comment : {"offset Pos 649000.5 6840000 10", "IGN offset Pos 649000.5 6840000 10"}) {
    const Mesh m = read_text(test::build_ply(PlyFormat::ascii, quad_strip(1, PlyScalar::float32, PlyScalar::int32), {comment})).mesh;
    EXPECT_EQ(m.world_position(3), (Vec3d{649001.5, 6840001.0, 10.5}));
    EXPECT_EQ(m.world_sensor_position(3), (Vec3d{649001.5, 6840000.5, 12.5}));
  }
}

TEST(PlyReader, SkipsUnknownElementsAndPropertiesInAnyOrder) {
  auto elements = quad_strip(2, PlyScalar::float32, PlyScalar::int32);
  elements[1].props.insert(elements[1].props.begin(), PropSpec{"flags", PlyScalar::uint16});
  elements[1].props.push_back(PropSpec{"texcoord", PlyScalar::float32, true, PlyScalar::uint8});
  for (auto& row : elements[1].rows) {
    row.insert(row.begin(), std::vector<double>{7});
    row.push_back({0.1, 0.2, 0.3});
  }
  elements[0].props.push_back(PropSpec{"normals", PlyScalar::float32, true, PlyScalar::int32});
  for (auto& row : elements[0].rows) row.push_back({0, 0, 1});
  ElementSpec camera{"camera", {{"k", PlyScalar::float64}, {"ids", PlyScalar::int32, true, PlyScalar::uint8}}, {{{1.0}, {1, 2}}, {{2.0}, {}}}};
  const std::vector<ElementSpec> reordered{elements[1], camera, elements[0]};  // faces first
  const Mesh reference = read_text(test::build_ply(PlyFormat::ascii, quad_strip(2, PlyScalar::float32, PlyScalar::int32))).mesh;
  for (PlyFormat format : kFormats) {
    const Mesh m = read_text(test::build_ply(format, reordered)).mesh;
    EXPECT_EQ(m.triangles, reference.triangles) << ply_format_name(format);
    EXPECT_EQ(m.positions, reference.positions) << ply_format_name(format);
  }
}

TEST(PlyReader, OptionalAttributesAndConfigurableNames) {
  ElementSpec v{"vertex", {{"x", PlyScalar::float32}, {"y", PlyScalar::float32}, {"z", PlyScalar::float32},
                           {"sx", PlyScalar::float64}, {"sy", PlyScalar::float64}, {"sz", PlyScalar::float64},
                           {"GPS_time", PlyScalar::float64}, {"intensity", PlyScalar::uint16},
                           {"red", PlyScalar::uint8}, {"green", PlyScalar::uint8}, {"blue", PlyScalar::uint8}},
                {{{1}, {2}, {3}, {4}, {5}, {6}, {7.25}, {300}, {10}, {20}, {30}}}};
  MeshReadParams params;
  params.ply.sensor_origin_names = {"sx", "sy", "sz"};
  const Mesh m = read_text(test::build_ply(PlyFormat::binary_big_endian, {v}), params).mesh;
  EXPECT_EQ(m.world_sensor_position(0), (Vec3d{4, 5, 6}));
  EXPECT_EQ(m.times, std::vector<double>{7.25});
  EXPECT_EQ(m.intensities, std::vector<float>{300});
  EXPECT_EQ(m.colors, (std::vector<Rgb8>{{10, 20, 30}}));
  EXPECT_EQ(m.triangle_count(), 0u);
}

TEST(PlyReader, MissingSensorOriginIsAnErrorOnlyWhenRequired) {
  ElementSpec v{"vertex", {{"x", PlyScalar::float32}, {"y", PlyScalar::float32}, {"z", PlyScalar::float32}}, {{{1}, {2}, {3}}}};
  test::TempDir dir;
  test::write_text(dir / "m.ply", test::build_ply(PlyFormat::ascii, {v}));
  EXPECT_THROW(read_mesh(dir / "m.ply"), InputError);
  const PlyInspection info = inspect_ply(dir / "m.ply");
  EXPECT_FALSE(info.layout.has_sensor_origin);
  EXPECT_EQ(info.bounds.min, (Vec3d{1, 2, 3}));
}

}  // namespace
}  // namespace citymesh

namespace citymesh {
namespace {

TEST(PlyReader, ExtraFacePropertiesInEveryFormatFollowTheirTriangles) {
  for (PlyFormat format : kFormats) {
    auto elements = quad_strip(2, PlyScalar::float32, PlyScalar::int32);
    elements[1].props.insert(elements[1].props.begin(), {"flag", PlyScalar::uint8});
    elements[1].props.push_back({"score", PlyScalar::float64});
    elements[1].props.push_back({"ignored", PlyScalar::int16});
    elements[1].rows[0].insert(elements[1].rows[0].begin(), {7.0});
    elements[1].rows[0].push_back({0.25});
    elements[1].rows[0].push_back({1});
    elements[1].rows[1].insert(elements[1].rows[1].begin(), {9.0});
    elements[1].rows[1].push_back({-1.5});
    elements[1].rows[1].push_back({2});
    test::TempDir dir;
    test::write_text(dir / "m.ply", test::build_ply(format, elements));
    PlyReadParams params;
    params.extra_face_properties = {"score", "flag"};
    PlyReader reader(dir / "m.ply", params);
    PlyVertexChunk vertices;
    PlyFaceChunk faces, all;
    all.extras.resize(2);
    while (reader.next(vertices, faces) != PlyReader::ChunkKind::end) {
      for (std::size_t e = 0; e < faces.extras.size(); ++e) {
        all.extras[e].insert(all.extras[e].end(), faces.extras[e].begin(), faces.extras[e].end());
      }
    }
    // Two quads, each split into two triangles that repeat the quad's values.
    EXPECT_EQ(all.extras[0], (std::vector<double>{0.25, 0.25, -1.5, -1.5})) << ply_format_name(format);
    EXPECT_EQ(all.extras[1], (std::vector<double>{7, 7, 9, 9})) << ply_format_name(format);
    params.extra_face_properties = {"missing"};
    EXPECT_THROW(PlyReader(dir / "m.ply", params), InputError);
  }
}

}  // namespace
}  // namespace citymesh
