// SPDX-License-Identifier: MIT
// The labelled PLY and picture written chunk by chunk are those of the whole mesh.
#include <gtest/gtest.h>

#include <random>

#include "citymesh/core/error.h"
#include "citymesh/io/ply_writer.h"
#include "citymesh/render/render.h"
#include "detect_output.h"
#include "labelled_output.h"
#include "test_support.h"

namespace citymesh::app {
namespace {

/// Small random triangles over a grid of jittered vertices (rows of 100, 30 cm apart) at city
/// coordinates, many overlapping, with every vertex attribute.
Mesh random_mesh(std::uint32_t seed, std::size_t vertices) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0, 30), z(0, 3), jitter(-0.1f, 0.1f);
  Mesh m;
  m.origin = {651000, 6860000, 30};
  for (std::size_t v = 0; v < vertices; ++v) {
    m.positions.push_back({0.3f * static_cast<float>(v % 100) + jitter(rng),
                           0.3f * static_cast<float>(v / 100) + jitter(rng), z(rng)});
    m.sensor_positions.push_back({u(rng), u(rng), 2.5f});
    m.times.push_back(1000.0 + static_cast<double>(v) / 7);
    m.intensities.push_back(static_cast<float>(v % 251));
    m.colors.push_back({static_cast<std::uint8_t>(v), static_cast<std::uint8_t>(v / 3), 7});
  }
  std::uniform_int_distribution<std::uint32_t> pick(0, static_cast<std::uint32_t>(vertices - 1));
  for (std::size_t t = 0; t < 2 * vertices; ++t) {
    const std::uint32_t a = pick(rng);
    m.triangles.push_back({a, (a + 1 + pick(rng) % 3) % static_cast<std::uint32_t>(vertices),
                           (a + 100 + pick(rng) % 3) % static_cast<std::uint32_t>(vertices)});
    m.triangle_ids.push_back({0, 0, 3 * t});
  }
  return m;
}

/// Random labels for `n` triangles.
ChangeResult random_labels(std::uint32_t seed, std::size_t n) {
  std::mt19937 rng(seed);
  ChangeResult r;
  r.index.offsets = {0, n};
  for (std::size_t t = 0; t < n; ++t) {
    r.state.push_back(static_cast<TriangleState>(rng() % 3));
    r.first_seen.push_back(TimePoint(Duration(static_cast<std::int64_t>(rng() % 100000))));
    r.last_seen.push_back(TimePoint(Duration(static_cast<std::int64_t>(100000 + rng() % 100000))));
    r.sustainable.push_back(static_cast<std::uint8_t>(rng() % 2));
    r.kept.push_back(static_cast<std::uint8_t>(rng() % 2));
    r.refutes.push_back(static_cast<std::uint8_t>(rng() % 2));
  }
  return r;
}

LabelledOutputParams params_for(const Mesh& m, const std::filesystem::path& dir) {
  return {.ply = dir / "labelled.ply",
          .png = dir / "labelled.png",
          .pixel_size = 0.05,
          .has = {.sensors = true, .times = true, .intensities = true, .colors = true},
          .vertices = m.vertex_count(),
          .triangles = m.triangle_count()};
}

TEST(LabelledAcquisitionWriter, ChunksGiveTheBytesOfTheWholeMeshPlyAndPicture) {
  test::TempDir tmp;
  const Mesh m = random_mesh(3, 5000);
  const ChangeResult labels = random_labels(4, m.triangle_count());
  std::vector<std::int32_t> faces;
  for (const TriangleId& id : m.triangle_ids) faces.push_back(static_cast<std::int32_t>(id.face));

  // The reference: the whole mesh at once through write_mesh_ply and render_orthographic.
  std::vector<std::uint8_t> state;
  std::vector<double> first, last;
  for (std::size_t t = 0; t < m.triangle_count(); ++t) {
    state.push_back(static_cast<std::uint8_t>(labels.state[t]));
    first.push_back(static_cast<double>(labels.first_seen[t].time_since_epoch().count()) / 1000.0);
    last.push_back(static_cast<double>(labels.last_seen[t].time_since_epoch().count()) / 1000.0);
  }
  write_mesh_ply(tmp / "whole.ply", m,
                 {{kSourceFaceProperty, std::span<const std::int32_t>(faces)},
                  {kStateProperty, std::span<const std::uint8_t>(state)},
                  {"first_seen", std::span<const double>(first)},
                  {"last_seen", std::span<const double>(last)},
                  {"sustainable", std::span<const std::uint8_t>(labels.sustainable)},
                  {kKeptProperty, std::span<const std::uint8_t>(labels.kept)},
                  {"refutes", std::span<const std::uint8_t>(labels.refutes)}});
  RenderLayer layer{&m, {}};
  for (std::size_t t = 0; t < m.triangle_count(); ++t) {
    layer.face_colors.push_back(detect_color(labels.state[t], labels.kept[t] != 0, labels.refutes[t] != 0));
  }
  write_png(tmp / "whole.png", render_orthographic(std::span<const RenderLayer>(&layer, 1), {.pixel_size = 0.05}));

  // Uneven chunks of vertices, then of triangles.
  LabelledAcquisitionWriter out(params_for(m, tmp.path()));
  for (const auto& [begin, end] : {std::pair{0, 1}, std::pair{1, 3001}, std::pair{3001, 5000}}) {
    out.add_vertices(m, begin, end);
  }
  for (const auto& [begin, end] : {std::pair{0, 17}, std::pair{17, 4000}, std::pair{4000, 4001}, std::pair{4001, 10000}}) {
    out.add_triangles(std::span(m.triangles).subspan(begin, end - begin), std::span(faces).subspan(begin, end - begin),
                      label_view(labels, begin, end));
  }
  const StateCounts counts = out.finish();
  EXPECT_EQ(test::read_text(tmp / "labelled.ply"), test::read_text(tmp / "whole.ply"));
  EXPECT_EQ(test::read_text(tmp / "labelled.png"), test::read_text(tmp / "whole.png"));
  const StateCounts expected = count_states(labels, 0, m.triangle_count());
  EXPECT_EQ(counts.state, expected.state);
  EXPECT_EQ(counts.kept, expected.kept);
  EXPECT_GT(counts.kept, 0u);
}

TEST(LabelledAcquisitionWriter, RowsThatDoNotFitAreRefusedAndNothingIsLeft) {
  test::TempDir tmp;
  const Mesh m = random_mesh(5, 100);
  const ChangeResult labels = random_labels(6, m.triangle_count());
  const std::vector<std::int32_t> faces(m.triangle_count(), 0);
  {
    LabelledAcquisitionWriter out(params_for(m, tmp.path()));
    out.add_vertices(m, 0, 50);
    // A triangle on a vertex not given yet.
    EXPECT_THROW(out.add_triangles(m.triangles, faces, label_view(labels, 0, m.triangle_count())), ProcessingError);
    out.add_vertices(m, 50, 100);
    EXPECT_THROW(out.add_triangles(m.triangles, std::span(faces).first(3), label_view(labels, 0, m.triangle_count())),
                 ProcessingError);
    out.add_triangles(std::span(m.triangles).first(10), std::span(faces).first(10), label_view(labels, 0, 10));
    EXPECT_THROW((void)out.finish(), ProcessingError);  // fewer triangles than announced
  }
  EXPECT_FALSE(std::filesystem::exists(tmp / "labelled.ply"));
  EXPECT_FALSE(std::filesystem::exists(tmp / "labelled.png"));
}

}  // namespace
}  // namespace citymesh::app
