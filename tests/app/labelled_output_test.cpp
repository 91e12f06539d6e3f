// SPDX-License-Identifier: MIT
// The labelled PLY and picture written chunk by chunk are those of the whole mesh.
#include <gtest/gtest.h>

#include <fmt/format.h>

#include <map>
#include <nlohmann/json.hpp>
#include <random>

#include "citymesh/core/error.h"
#include "citymesh/core/parallel.h"
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


/// Three random acquisitions with labels and pairs, as `citymesh detect` holds them.
struct DetectFixture {
  Config config;
  LoadedAcquisitions input;
  ChangeResult result;

  DetectFixture() {
    std::vector<ChangeResult> parts;
    for (std::uint32_t k = 0; k < 3; ++k) {
      const TimePoint date(Duration(std::int64_t{86400000} * (k + 1)));
      config.acquisitions.push_back({fmt::format("/data/acq_{}.ply", k), date, fmt::format("epoch {}", k)});
      config.acquisitions.back().listed = k;
      input.acquisitions.push_back({k, date, config.acquisitions.back().path});
      input.dates.push_back(date);
      input.meshes.push_back(random_mesh(20 + k, 300 + 100 * k));
      parts.push_back(random_labels(30 + k, input.meshes.back().triangle_count()));
    }
    result.index.offsets = {0};
    for (const ChangeResult& p : parts) {
      result.index.offsets.push_back(result.index.offsets.back() + p.state.size());
      result.state.insert(result.state.end(), p.state.begin(), p.state.end());
      result.first_seen.insert(result.first_seen.end(), p.first_seen.begin(), p.first_seen.end());
      result.last_seen.insert(result.last_seen.end(), p.last_seen.begin(), p.last_seen.end());
      result.sustainable.insert(result.sustainable.end(), p.sustainable.begin(), p.sustainable.end());
      result.kept.insert(result.kept.end(), p.kept.begin(), p.kept.end());
      result.refutes.insert(result.refutes.end(), p.refutes.begin(), p.refutes.end());
    }
    std::vector<TrianglePair> pairs;
    for (std::uint32_t t = 0; t + 700 < result.state.size(); t += 7) pairs.push_back({t, t + 700});
    result.consistent_pairs = std::move(pairs);
  }
};

TEST(DetectOutputs, AcquisitionsWrittenAtOnceGiveTheBytesOfOneAtATime) {
  const ThreadLimit limit(2);
  const DetectFixture f;
  test::TempDir tmp;
  std::map<std::string, std::string> first;
  for (const unsigned at_once : {1u, 2u, 8u}) {
    const std::filesystem::path dir = tmp / fmt::format("at_once_{}", at_once);
    InMemoryDetectOutput source(f.input, f.result);
    write_detect_outputs(f.config, f.input, source, {.dir = dir, .pixel_size = 0.1, .at_once = at_once});
    std::map<std::string, std::string> files;
    for (const auto& entry : std::filesystem::directory_iterator(dir)) {
      nlohmann::json summary;
      std::string bytes = test::read_text(entry.path());
      if (entry.path().filename() == "summary.json") {  // without its timings
        summary = nlohmann::json::parse(bytes);
        summary.erase("seconds");
        bytes = summary.dump();
      }
      files[entry.path().filename().string()] = std::move(bytes);
    }
    ASSERT_EQ(files.size(), 8u);  // three PLYs and PNGs, pairs, summary
    if (first.empty()) {
      first = files;
    } else {
      EXPECT_TRUE(files == first) << at_once << " at once differ from one at a time";
    }
  }
  const nlohmann::json summary = nlohmann::json::parse(first["summary.json"]);
  EXPECT_EQ(summary["consistent_pairs"].get<std::size_t>(), f.result.consistent_pairs.size());
  EXPECT_EQ(summary["totals"]["triangles"].get<std::size_t>(), f.result.state.size());
  EXPECT_EQ(summary["acquisitions"][2]["name"], "epoch 2");
}

TEST(DetectOutputs, AsManyAtOnceAsTheBudgetHolds) {
  const ThreadLimit limit(2);
  // With pictures, the largest picture with its depth is held whatever the vertices.
  const std::uint64_t picture = labelled_output_bytes(0, 48, true);
  EXPECT_EQ(picture, 8192ull * 8192 * 7);
  EXPECT_EQ(labelled_output_bytes(1000, 48, false), 48000u);
  EXPECT_EQ(labelled_output_workers(picture + 48000, 2 * picture), 1u);
  EXPECT_EQ(labelled_output_workers(picture + 48000, 3 * picture), 2u);
  EXPECT_EQ(labelled_output_workers(48000, 1 << 30), 2u);  // never more than the threads
  EXPECT_EQ(labelled_output_workers(48000, 0), 1u);        // never none
}

}  // namespace
}  // namespace citymesh::app
