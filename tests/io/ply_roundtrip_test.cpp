// SPDX-License-Identifier: MIT
#include <gtest/gtest.h>

#include <cstring>
#include <random>

#include "citymesh/core/error.h"
#include "citymesh/io/mesh_io.h"
#include "citymesh/io/ply_writer.h"
#include "test_support.h"

namespace citymesh {
namespace {

Mesh random_mesh(std::uint32_t seed, std::size_t vertices, std::size_t triangles) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> coord(-50.f, 50.f);
  Mesh m;
  m.origin = {651000.0, 6860000.0, 35.0};
  for (std::size_t v = 0; v < vertices; ++v) {
    m.positions.push_back({coord(rng), coord(rng), coord(rng)});
    m.sensor_positions.push_back({coord(rng), coord(rng), 2.5f});
    m.times.push_back(54160.0 + 1e-6 * static_cast<double>(v));
    m.intensities.push_back(static_cast<float>(v % 100));
    m.colors.push_back({static_cast<std::uint8_t>(v), 7, 200});
  }
  std::uniform_int_distribution<std::uint32_t> index(0, static_cast<std::uint32_t>(vertices - 1));
  while (m.triangles.size() < triangles) {
    const Triangle t{index(rng), index(rng), index(rng)};
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) continue;
    m.triangle_ids.push_back({0, 0, m.triangles.size()});
    m.triangles.push_back(t);
  }
  return m;
}

TEST(PlyWriter, MeshRoundTripsBitExactlyWithProvenanceColumns) {
  const Mesh m = random_mesh(7, 500, 900);
  std::vector<std::int32_t> source_acq(m.triangle_count()), source_face(m.triangle_count());
  for (std::size_t t = 0; t < source_acq.size(); ++t) {
    source_acq[t] = static_cast<std::int32_t>(t % 3);
    source_face[t] = t % 5 == 0 ? -1 : static_cast<std::int32_t>(t * 11);
  }
  test::TempDir dir;
  write_mesh_ply(dir / "m.ply", m, {{"source_acq", std::span<const std::int32_t>(source_acq)},
                                    {"source_face", std::span<const std::int32_t>(source_face)}});

  MeshReadParams params;
  params.origin = m.origin;
  const MeshReadResult r = read_mesh(dir / "m.ply", params);
  EXPECT_EQ(r.mesh.positions, m.positions);
  EXPECT_EQ(r.mesh.sensor_positions, m.sensor_positions);
  EXPECT_EQ(r.mesh.times, m.times);
  EXPECT_EQ(r.mesh.intensities, m.intensities);
  EXPECT_EQ(r.mesh.colors, m.colors);
  EXPECT_EQ(r.mesh.triangles, m.triangles);

  // The provenance columns, decoded by hand from the documented layout.
  PlyReader reader(dir / "m.ply");
  const PlyElement* face = reader.header().find("face");
  ASSERT_NE(face, nullptr);
  ASSERT_EQ(face->properties.size(), 3u);
  EXPECT_EQ(face->properties[1].name, "source_acq");
  EXPECT_EQ(face->properties[2].type, PlyScalar::int32);
  const std::string bytes = test::read_text(dir / "m.ply");
  const std::size_t face_start = bytes.size() - m.triangle_count() * (1 + 12 + 8);
  for (std::size_t t = 0; t < m.triangle_count(); t += 97) {
    std::int32_t acq = 0, src = 0;
    std::memcpy(&acq, bytes.data() + face_start + t * 21 + 13, 4);
    std::memcpy(&src, bytes.data() + face_start + t * 21 + 17, 4);
    EXPECT_EQ(acq, source_acq[t]);
    EXPECT_EQ(src, source_face[t]);
  }
}

TEST(PlyWriter, HeaderDeclaresDoubleCoordinatesAndBinaryLittleEndian) {
  test::TempDir dir;
  write_mesh_ply(dir / "m.ply", random_mesh(1, 10, 5));
  PlyReader reader(dir / "m.ply");
  EXPECT_EQ(reader.header().format, PlyFormat::binary_little_endian);
  const PlyElement* v = reader.header().find("vertex");
  for (const char* name : {"x", "y", "z", "x_origin", "y_origin", "z_origin"}) {
    ASSERT_NE(v->find(name), nullptr) << name;
    EXPECT_EQ(v->find(name)->type, PlyScalar::float64) << name;
  }
}

TEST(PlyWriter, MismatchedColumnIsRefusedAndNothingIsWritten) {
  test::TempDir dir;
  const Mesh m = random_mesh(3, 10, 5);
  std::vector<std::int32_t> short_column(2);
  EXPECT_THROW(write_mesh_ply(dir / "m.ply", m, {{"source_acq", std::span<const std::int32_t>(short_column)}}),
               ProcessingError);
  EXPECT_FALSE(std::filesystem::exists(dir / "m.ply"));
}

}  // namespace
}  // namespace citymesh

namespace citymesh {
namespace {

/// `m`'s vertices [first, last) as rows with its attributes.
MeshVertexRows rows_of(const Mesh& m, std::size_t first, std::size_t last) {
  MeshVertexRows rows({.sensors = true, .times = true, .intensities = true, .colors = true});
  for (std::size_t v = first; v < last; ++v) {
    rows.add(m.world_position(v), m.world_sensor_position(v), m.times[v], m.intensities[v], m.colors[v]);
  }
  return rows;
}

/// A random mesh with a source_acq column, written whole by write_mesh_ply to `file`: the
/// bytes a writer in parts must give, from the layout it is given.
struct WholeWrite {
  Mesh mesh;
  std::vector<std::int32_t> source;
  MeshVertexRows rows;
  WholeWrite(const std::filesystem::path& file, std::uint32_t seed, int sources)
      : mesh(random_mesh(seed, 300, 500)), source(mesh.triangle_count()), rows(rows_of(mesh, 0, mesh.vertex_count())) {
    for (std::size_t t = 0; t < source.size(); ++t) source[t] = static_cast<std::int32_t>(t % sources) - 1;
    write_mesh_ply(file, mesh, {{"source_acq", std::span<const std::int32_t>(source)}});
  }
  [[nodiscard]] PlyWriteInput layout() const {
    return {
        {}, {}, rows.columns(), {{"source_acq", std::span<const std::int32_t>(source)}}, {std::string(kPlyComment)}};
  }
};

TEST(PlyStreamWriter, ChunksGiveTheBytesOfTheWholeWrite) {
  test::TempDir dir;
  const WholeWrite whole(dir / "whole.ply", 11, 5);
  const Mesh& m = whole.mesh;
  const std::vector<std::int32_t>& source = whole.source;
  PlyStreamWriter out(dir / "chunks.ply", whole.layout(), m.vertex_count(), m.triangle_count());
  for (std::size_t first = 0; first < m.vertex_count(); first += 70) {
    const MeshVertexRows rows = rows_of(m, first, std::min(first + 70, m.vertex_count()));
    out.add_vertices({rows.positions, {}, rows.columns(), {}, {}});
  }
  for (std::size_t first = 0; first < m.triangle_count(); first += 130) {
    const std::size_t n = std::min<std::size_t>(130, m.triangle_count() - first);
    out.add_faces({{}, std::span(m.triangles).subspan(first, n), {},
                   {{"source_acq", std::span<const std::int32_t>(source).subspan(first, n)}}, {}});
  }
  EXPECT_FALSE(std::filesystem::exists(dir / "chunks.ply")) << "nothing before commit";
  out.commit();
  EXPECT_EQ(test::read_text(dir / "chunks.ply"), test::read_text(dir / "whole.ply"));
}

TEST(PlyStreamWriter, RowsThatDoNotFitTheHeaderAreRefusedAndNothingIsWritten) {
  test::TempDir dir;
  const Mesh m = random_mesh(12, 20, 10);
  const MeshVertexRows rows = rows_of(m, 0, m.vertex_count());
  const PlyWriteInput layout{{}, {}, rows.columns(), {}, {}};
  {
    PlyStreamWriter out(dir / "short.ply", layout, m.vertex_count() + 1, m.triangle_count());
    out.add_vertices({rows.positions, {}, rows.columns(), {}, {}});
    EXPECT_THROW(out.add_faces({{}, m.triangles, {}, {}, {}}), ProcessingError);  // a vertex is missing
    EXPECT_THROW(out.commit(), ProcessingError);
  }
  {
    PlyStreamWriter out(dir / "other.ply", layout, m.vertex_count(), m.triangle_count());
    const MeshVertexRows bare({});
    EXPECT_THROW(out.add_vertices({rows.positions, {}, bare.columns(), {}, {}}), ProcessingError);  // other columns
    EXPECT_THROW(out.add_vertices({std::vector<Vec3d>(m.vertex_count() + 1), {}, {}, {}, {}}), ProcessingError);
  }
  EXPECT_FALSE(std::filesystem::exists(dir / "short.ply"));
  EXPECT_FALSE(std::filesystem::exists(dir / "other.ply"));
}

TEST(PlySpoolWriter, InterleavedChunksGiveTheBytesOfTheWholeWriteAndLeaveNoScratchFile) {
  test::TempDir dir;
  const WholeWrite whole(dir / "whole.ply", 13, 7);
  const Mesh& m = whole.mesh;
  const std::vector<std::int32_t>& source = whole.source;
  const PlyWriteInput layout = whole.layout();
  {
    PlySpoolWriter out(dir / "spooled.ply", layout);
    // Faces before the vertices they use, as a drive's frames come: rows of both kinds in turn.
    std::size_t next_vertex = 0, next_face = 0;
    while (next_vertex < m.vertex_count() || next_face < m.triangle_count()) {
      const std::size_t n = std::min<std::size_t>(110, m.triangle_count() - next_face);
      out.add_faces({{},
                     std::span(m.triangles).subspan(next_face, n),
                     {},
                     {{"source_acq", std::span<const std::int32_t>(source).subspan(next_face, n)}},
                     {}});
      next_face += n;
      const MeshVertexRows rows = rows_of(m, next_vertex, std::min(next_vertex + 70, m.vertex_count()));
      out.add_vertices({rows.positions, {}, rows.columns(), {}, {}});
      next_vertex += rows.positions.size();
      EXPECT_EQ(out.vertices(), next_vertex);
    }
    EXPECT_FALSE(std::filesystem::exists(dir / "spooled.ply")) << "nothing before commit";
    EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir.path()), {}), 1) << "scratch files are unlinked";
    out.commit();
  }
  EXPECT_EQ(test::read_text(dir / "spooled.ply"), test::read_text(dir / "whole.ply"));
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir.path()), {}), 2) << "nothing but the two outputs";
}

TEST(PlySpoolWriter, RowsOfOtherColumnsOrFacesOnMissingVerticesAreRefusedAndNothingIsWritten) {
  test::TempDir dir;
  const Mesh m = random_mesh(14, 20, 10);
  const MeshVertexRows rows = rows_of(m, 0, m.vertex_count());
  const PlyWriteInput layout{{}, {}, rows.columns(), {}, {}};
  {
    PlySpoolWriter out(dir / "short.ply", layout);
    out.add_vertices({std::span(rows.positions).first(m.vertex_count() - 1),
                      {},
                      rows_of(m, 0, m.vertex_count() - 1).columns(),
                      {},
                      {}});
    const std::vector<Triangle> uses_the_missing{{0, 1, static_cast<std::uint32_t>(m.vertex_count() - 1)}};
    out.add_faces({{}, uses_the_missing, {}, {}, {}});
    EXPECT_THROW(out.commit(), ProcessingError);  // the face's last corner never came
  }
  {
    PlySpoolWriter out(dir / "other.ply", layout);
    const MeshVertexRows bare({});
    EXPECT_THROW(out.add_vertices({rows.positions, {}, bare.columns(), {}, {}}), ProcessingError);  // other columns
    const std::vector<std::int32_t> extra(m.triangle_count(), 1);
    EXPECT_THROW(out.add_faces({{}, m.triangles, {}, {{"source_acq", std::span<const std::int32_t>(extra)}}, {}}),
                 ProcessingError);
  }
  EXPECT_FALSE(std::filesystem::exists(dir / "short.ply"));
  EXPECT_FALSE(std::filesystem::exists(dir / "other.ply"));
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir.path()), {}), 0) << "no scratch file left";
}

}  // namespace
}  // namespace citymesh
