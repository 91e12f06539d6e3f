// SPDX-License-Identifier: MIT
// citymesh run on the tile store, through the binary: tiled equals untiled, every triangle is
// owned once, runs are deterministic whatever the thread count, killed runs resume to the
// same bytes, and a changed config is refused without --force.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cfloat>
#include <cstdio>
#include <cstdlib>
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "citymesh/io/mesh_io.h"
#include "citymesh/io/ply_writer.h"
#include "face_table.h"
#include "mesh_parts.h"
#include "mosaic_ply.h"
#include "test_support.h"

namespace citymesh {
namespace {

nlohmann::json read_json(const std::filesystem::path& path) { return nlohmann::json::parse(test::read_text(path)); }

/// `run <sim>/<config>` into output `name` and work folder `work-<name>`, without pictures.
std::string run_file_args(const std::string& sim, const std::string& config, const std::string& name,
                          const std::string& extra) {
  return fmt::format("run {}/{} --no-pictures --set project.output={} --set project.work=work-{} {}", sim, config,
                     name, name, extra);
}

std::string run_args(const std::string& sim, const std::string& name, const std::string& extra) {
  return run_file_args(sim, "config.toml", name, extra);
}

/// Two outputs with the same result bytes and the same prefilter figures in their detect
/// summaries (a tile makes no work of a pass it does not hold, so a result made before a pass
/// was appended or withdrawn counts what a fresh run's counts).
void expect_same_outputs(const std::filesystem::path& output, const std::filesystem::path& fresh, const char* what) {
  EXPECT_TRUE(test::result_bytes(output) == test::result_bytes(fresh)) << what;
  EXPECT_EQ(read_json(output / "detect/summary.json")["prefilter"],
            read_json(fresh / "detect/summary.json")["prefilter"])
      << what;
}

/// A run that redid some tiles and reused others.
void expect_some_tiles_reused(const nlohmann::json& report, const char* reused, const char* redone) {
  EXPECT_GT(report["reused_tiles"].get<int>(), 0) << reused;
  EXPECT_LT(report["reused_tiles"].get<int>(), report["tiles"].get<int>()) << redone;
}

TEST(TiledRun, NineTilesOrMoreScoreLikeOneTile) {
  test::TempDir dir;
  const std::string sim = (dir / "sim").string();
  ASSERT_EQ(test::run_citymesh(fmt::format("simulate --out {}", sim)).exit_code, 0);
  for (const auto& [name, size] : {std::pair{"one", 1000}, std::pair{"many", 10}}) {
    const auto run = test::run_citymesh(run_args(sim, name, fmt::format("--set tiling.tile_size={}", size)));
    ASSERT_EQ(run.exit_code, 0) << run.err;
    EXPECT_EQ(run.err.find("more than the halo"), std::string::npos) << run.err;  // the default halo holds them
    const auto eval = test::run_citymesh(fmt::format("eval {}/{} --truth {}", sim, name, sim));
    ASSERT_EQ(eval.exit_code, 0) << eval.err;
  }
  const nlohmann::json one = read_json(dir / "sim/one/run.json"), many = read_json(dir / "sim/many/run.json");
  EXPECT_EQ(one["tiles"], 1);
  EXPECT_GE(many["tiles"].get<int>(), 9);
  // Every input triangle is owned by exactly one tile: the labels cover the input once.
  std::uint64_t input = 0;
  const nlohmann::json detect = read_json(dir / "sim/many/detect/summary.json");
  for (const auto& a : detect["acquisitions"]) input += a["triangles"].get<std::uint64_t>();
  EXPECT_EQ(many["input_triangles"].get<std::uint64_t>(), input);
  EXPECT_GT(many["tiling"]["halo_copies"].get<std::uint64_t>(), 0u);

  const nlohmann::json a = read_json(dir / "sim/one/eval.json"), b = read_json(dir / "sim/many/eval.json");
  for (const char* key : {"static_completeness", "dynamic_removed_overall", "dynamic_residue"}) {
    EXPECT_NEAR(a[key].get<double>(), b[key].get<double>(), 0.001) << key;
  }
  // Overlap and gaps along tile borders would show here: both within 0.1 percentage points.
  for (const char* key : {"overlap_ratio", "hole_ratio", "static_completeness", "dynamic_residue"}) {
    EXPECT_NEAR(a["mosaic"][key].get<double>(), b["mosaic"][key].get<double>(), 0.001) << key;
  }

  // The mosaic's counts of triangles are summed over the tiles' owned triangles: one tile
  // counts what the untiled mosaic counts (`selected` before the fill in both) (up to the float rounding of the tile's
  // frame), and the visibility check, which does not depend on the selection, gives the same count in many tiles.
  ASSERT_EQ(test::run_citymesh(fmt::format("detect {}/config.toml --no-pictures", sim)).exit_code, 0);
  ASSERT_EQ(test::run_citymesh(fmt::format("mosaic {}/config.toml --no-pictures", sim)).exit_code, 0);
  const nlohmann::json whole = read_json(dir / "sim/out/mosaic/summary.json")["counts"];
  const nlohmann::json tile1 = read_json(dir / "sim/one/mosaic/summary.json")["counts"];
  const nlohmann::json tiles = read_json(dir / "sim/many/mosaic/summary.json")["counts"];
  for (const char* key : {"selected", "seen_through", "filled", "fill_seen_through"}) {
    const auto expected = whole[key].get<double>();
    EXPECT_GT(expected, 0.0) << key;
    EXPECT_NEAR(tile1[key].get<double>(), expected, 0.005 * expected) << key;
  }
  EXPECT_NEAR(tiles["seen_through"].get<double>(), whole["seen_through"].get<double>(),
              0.02 * whole["seen_through"].get<double>());
  EXPECT_GT(tiles["filled"].get<std::uint64_t>(), 0u);

  // The detect summary's pre-filter figures are the tiles' summed: one tile finds what the
  // untiled step finds, many tiles more (their halo and empty-space copies are tested in each
  // tile that holds them). Up to the tile frame's rounding; the voxels lie on a grid anchored
  // at the tile's corner instead of the first mesh's origin, so the grid's figures differ more.
  const nlohmann::json untiled = read_json(dir / "sim/out/detect/summary.json")["prefilter"];
  const nlohmann::json in_one = read_json(dir / "sim/one/detect/summary.json")["prefilter"];
  const nlohmann::json in_many = detect["prefilter"];
  for (const auto& [key, tolerance] : {std::pair{"candidates", 0.01}, std::pair{"exact_tests", 0.01},
                                       std::pair{"skipped", 0.05}, std::pair{"marked_voxels", 0.05}}) {
    const auto expected = untiled[key].get<double>();
    EXPECT_GT(expected, 0.0) << key;
    EXPECT_NEAR(in_one[key].get<double>(), expected, tolerance * expected) << key;
    EXPECT_GT(in_many[key].get<double>(), in_one[key].get<double>()) << key;
  }
  // The labels of many tiles are the untiled ones, refutes too: a tile counts the conflicts of
  // its own triangles only, and the assembly gathers the refutations of every tile (before,
  // 10 m tiles missed up to 7.5 % of them). Up to the tile frame's rounding: one triangle.
  const nlohmann::json untiled_acquisitions = read_json(dir / "sim/out/detect/summary.json")["acquisitions"];
  std::uint64_t refuting = 0;
  for (std::size_t k = 0; k < untiled_acquisitions.size(); ++k) {
    for (const char* key : {"refutes", "conflicting", "kept"}) {
      const auto expected = untiled_acquisitions[k]["counts"][key].get<double>();
      EXPECT_NEAR(detect["acquisitions"][k]["counts"][key].get<double>(), expected, 2.0) << key << " " << k;
    }
    refuting += untiled_acquisitions[k]["counts"]["refutes"].get<std::uint64_t>();
  }
  EXPECT_GT(refuting, 10000u);
  EXPECT_GT(detect["seconds"]["consistency"].get<double>(), 0.0);
  EXPECT_GT(detect["seconds"]["detect_total"].get<double>(), detect["seconds"]["conflicts"].get<double>());
}

/// The source_face column of a labelled PLY.
std::vector<double> source_faces_of(const std::filesystem::path& ply) {
  PlyReadParams params;
  params.extra_face_properties = {"source_face"};
  PlyReader reader(ply, params);
  PlyVertexChunk vertices;
  PlyFaceChunk faces;
  std::vector<double> out;
  for (auto kind = reader.next(vertices, faces); kind != PlyReader::ChunkKind::end;
       kind = reader.next(vertices, faces)) {
    if (kind == PlyReader::ChunkKind::faces) out.insert(out.end(), faces.extras[0].begin(), faces.extras[0].end());
  }
  return out;
}

TEST(TiledRun, AHaloNarrowerThanTheTrianglesReachIsWarnedOf) {
  test::TempDir dir;
  const std::string sim = (dir / "sim").string();
  ASSERT_EQ(test::run_citymesh(fmt::format("simulate --out {} --length 30", sim)).exit_code, 0);
  const auto run = test::run_citymesh(run_args(sim, "narrow", "--set tiling.halo=0.2"));
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const double radius = read_json(dir / "sim/narrow/run.json")["tiling"]["largest_radius"].get<double>();
  EXPECT_GT(radius, 0.2);
  EXPECT_NE(run.err.find(
                fmt::format("some triangles reach {:.2f} m from their centroid, more than the halo (0.2 m)", radius)),
            std::string::npos)
      << run.err;
  // The halo it suggests holds them.
  const std::size_t at = run.err.find("[tiling] halo = ");
  ASSERT_NE(at, std::string::npos);
  EXPECT_GE(std::stod(run.err.substr(at + 16)), radius + 0.1);
}

TEST(TiledRun, TilesThatTakeTheProcessPastTheBudgetAreWarnedOf) {
  test::TempDir dir;
  const std::string sim = (dir / "sim").string();
  ASSERT_EQ(test::run_citymesh(fmt::format("simulate --out {} --length 30", sim)).exit_code, 0);
  constexpr const char* kPast = "past the memory budget of";
  const auto within = test::run_citymesh(run_args(sim, "within", ""));
  ASSERT_EQ(within.exit_code, 0) << within.err;
  EXPECT_EQ(within.err.find(kPast), std::string::npos) << within.err;
  const auto past = test::run_citymesh(run_args(sim, "past", "--memory 64MiB"));
  ASSERT_EQ(past.exit_code, 0) << past.err;
  const auto peak = read_json(dir / "sim/past/run.json")["peak_rss_bytes"].get<std::uint64_t>();
  ASSERT_GT(peak, std::uint64_t{64} << 20) << "the street no longer needs more than 64 MiB: take a longer one";
  EXPECT_NE(past.err.find(fmt::format("{} 64MiB", kPast)), std::string::npos) << past.err;
}

TEST(TiledRun, AZeroAreaInputTriangleIsDroppedAlikeByTheTilerAndTheLabelledPlys) {
  // The labelled PLYs read each file again: they must leave out the triangles the tiler left
  // out, or the labels of every later triangle are shifted (the run used to stop there).
  test::TempDir dir;
  const std::string sim = (dir / "sim").string();
  ASSERT_EQ(test::run_citymesh(fmt::format("simulate --out {} --length 30", sim)).exit_code, 0);
  const std::filesystem::path acquisition = dir / "sim/acq_2.ply";
  Mesh m = read_mesh(acquisition).mesh;
  const std::size_t triangles = m.triangle_count(), middle = triangles / 2;
  // A copy of vertex 0 and, midway through the faces, a face on vertices 0, 1 and the copy.
  const auto copy = static_cast<std::uint32_t>(m.vertex_count());
  m.positions.push_back(m.positions[0]);
  m.sensor_positions.push_back(m.sensor_positions[0]);
  if (!m.times.empty()) m.times.push_back(m.times[0]);
  if (!m.intensities.empty()) m.intensities.push_back(m.intensities[0]);
  if (!m.colors.empty()) m.colors.push_back(m.colors[0]);
  m.triangles.insert(m.triangles.begin() + static_cast<std::ptrdiff_t>(middle), Triangle{0, 1, copy});
  m.triangle_ids.insert(m.triangle_ids.begin() + static_cast<std::ptrdiff_t>(middle), TriangleId{});
  write_mesh_ply(acquisition, m);

  const auto run = test::run_citymesh(run_args(sim, "z", "--set tiling.tile_size=10"));
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.err.find("acq_2.ply: dropped 1 zero-area triangles"), std::string::npos) << run.err;
  const nlohmann::json summary = read_json(dir / "sim/z/detect/summary.json");
  EXPECT_EQ(summary["acquisitions"][2]["triangles"].get<std::size_t>(), triangles);
  // Face by face in file order, without the degenerate one.
  const std::vector<double> faces = source_faces_of(dir / "sim/z/detect/2_epoch 2.ply");
  ASSERT_EQ(faces.size(), triangles);
  for (std::size_t t = 0; t < triangles; ++t) {
    ASSERT_EQ(faces[t], static_cast<double>(t < middle ? t : t + 1)) << "triangle " << t;
  }
}

TEST(TiledRun, SameBytesOnOneAndTwoThreadsAndAfterKills) {
  test::TempDir dir;
  const std::string sim = (dir / "sim").string();
  ASSERT_EQ(test::run_citymesh(fmt::format("simulate --out {} --length 40", sim)).exit_code, 0);
  const std::string tiles = "--set tiling.tile_size=8";
  ASSERT_EQ(test::run_citymesh(run_args(sim, "t1", tiles + " --threads 1")).exit_code, 0);
  ASSERT_EQ(test::run_citymesh(run_args(sim, "t2", tiles + " --threads 2")).exit_code, 0);
  const auto reference = test::result_bytes(dir / "sim/t1");
  ASSERT_GE(reference.size(), 7u);  // labelled PLYs, pairs, mosaic
  EXPECT_TRUE(test::result_bytes(dir / "sim/t2") == reference) << "1 and 2 threads differ";
  EXPECT_GE(read_json(dir / "sim/t1/run.json")["tiles"].get<int>(), 9);

  // Killed (SIGKILL) at several moments, then run to the end: the same bytes. --foreground:
  // otherwise timeout kills its own process group, itself included, and the killed run is
  // reaped later by init; the next run may then start while it still exists, and rightly
  // leaves its temporary files alone (the check below failed about one time in ten).
  for (const double seconds : {0.3, 0.8, 1.5, 2.5}) {
    const std::string cmd = fmt::format("timeout --foreground -s KILL {} {} {} >/dev/null 2>&1", seconds,
                                        CITYMESH_BINARY, run_args(sim, "k", tiles));
    (void)std::system(cmd.c_str());
  }
  const auto resumed = test::run_citymesh(run_args(sim, "k", tiles));
  ASSERT_EQ(resumed.exit_code, 0) << resumed.err;
  EXPECT_TRUE(test::result_bytes(dir / "sim/k") == reference) << "a killed and resumed run differs";
  // What the killed runs left (temporary files, pair and staging folders) went with the resumed run.
  for (const auto& entry : std::filesystem::recursive_directory_iterator(dir / "sim")) {
    const std::string name = entry.path().filename().string();
    const bool pair_folder = entry.is_directory() && name.starts_with("pairs.");
    EXPECT_TRUE(name.find(".tmp.") == std::string::npos && !pair_folder &&
                entry.path().parent_path().filename() != "staging")
        << entry.path() << " left by a killed run";
  }
  // A re-run reuses every tile (and, with its report removed, writes the outputs again).
  std::filesystem::remove(dir / "sim/k/run.json");
  const auto again = test::run_citymesh(run_args(sim, "k", tiles));
  ASSERT_EQ(again.exit_code, 0) << again.err;
  const nlohmann::json report = read_json(dir / "sim/k/run.json");
  EXPECT_EQ(report["reused_tiles"], report["tiles"]);
  EXPECT_TRUE(report["triangles_per_second"].is_null()) << "a rate over a resumed run's own time";
}

TEST(TiledRun, SeamPassByBlocksScoresLikeWholeOnAnyThreadCount) {
  test::TempDir dir;
  const std::string sim = (dir / "sim").string();
  ASSERT_EQ(test::run_citymesh(fmt::format("simulate --out {} --length 40", sim)).exit_code, 0);
  // The default stitching reaches 3.75 m: tiles of 8 m cannot hold its bands. Refused before
  // anything is tiled, not after the tiles.
  const auto small = test::run_citymesh(run_args(sim, "s", "--set tiling.tile_size=8 --set run.seam_pass=blocks"));
  EXPECT_EQ(small.exit_code, 1);
  EXPECT_NE(small.err.find("tiling.tile_size must be over 15.00 m"), std::string::npos) << small.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "sim/work-s/tiles"));
  const auto check = test::run_citymesh(
      fmt::format("config --check {}/config.toml --set tiling.tile_size=8 --set run.seam_pass=blocks", sim));
  EXPECT_EQ(check.exit_code, 1);
  EXPECT_NE(check.err.find("tiling.tile_size must be over 15.00 m"), std::string::npos) << check.err;

  // "auto" (the default) stitches such tiles whole instead, and says so.
  const auto fallback = test::run_citymesh(run_args(sim, "a", "--set tiling.tile_size=8"));
  ASSERT_EQ(fallback.exit_code, 0) << fallback.err;
  EXPECT_NE(fallback.err.find("too narrow for the seam pass by blocks"), std::string::npos) << fallback.err;
  EXPECT_TRUE(read_json(dir / "sim/a/mosaic/summary.json")["stitch"]["by_blocks"].is_null());

  const std::string tiles = "--set tiling.tile_size=16";
  for (const auto& [name, extra] :
       {std::pair{"whole", " --set run.seam_pass=whole --threads 2"}, std::pair{"b1", " --threads 1"},
        std::pair{"b2", " --set run.seam_pass=blocks --threads 2"}}) {
    const auto run = test::run_citymesh(run_args(sim, name, tiles + extra));
    ASSERT_EQ(run.exit_code, 0) << run.err;
  }
  // b1 by "auto", b2 by "blocks": the same pass, the same bytes on 1 and 2 threads.
  EXPECT_TRUE(test::result_bytes(dir / "sim/b1") == test::result_bytes(dir / "sim/b2")) << "1 and 2 threads differ";
  const nlohmann::json parts = read_json(dir / "sim/b1/mosaic/summary.json")["stitch"]["by_blocks"]["parts"];
  EXPECT_GE(parts[0].get<int>(), 4);  // tile interiors
  EXPECT_GE(parts[3].get<int>(), 1);  // corner squares
  EXPECT_TRUE(read_json(dir / "sim/whole/mosaic/summary.json")["stitch"]["by_blocks"].is_null());

  const auto [non_manifold, sources] = test::inspect_mosaic_ply(dir / "sim/b1/mosaic/mosaic.ply");
  EXPECT_EQ(non_manifold, 0u);
  EXPECT_GT(sources.count(-1), 0u);  // stitch triangles
  nlohmann::json scores[2];
  for (int k = 0; k < 2; ++k) {
    const std::string name = k == 0 ? "whole" : "b1";
    ASSERT_EQ(test::run_citymesh(fmt::format("eval {}/{} --truth {}", sim, name, sim)).exit_code, 0);
    scores[k] = read_json(dir / "sim" / name / "eval.json")["mosaic"];
  }
  // Parts stitched one after the other close nearly what stitching at once closes (measured:
  // open seams 70.8 m against 63.3 m, holes 0.792 against 0.777 %).
  for (const char* key : {"overlap_ratio", "hole_ratio", "static_completeness"}) {
    EXPECT_NEAR(scores[1][key].get<double>(), scores[0][key].get<double>(), 0.001) << key;
  }
  EXPECT_LT(scores[1]["seam_length"].get<double>(), 1.25 * scores[0]["seam_length"].get<double>());
  EXPECT_LT(scores[1]["open_boundary_length"].get<double>(), 1.05 * scores[0]["open_boundary_length"].get<double>());
}

TEST(TiledRun, ChangedConfigIsRefusedWithoutForceAndDamagedTilesAreRedone) {
  test::TempDir dir;
  const std::string sim = (dir / "sim").string();
  ASSERT_EQ(test::run_citymesh(fmt::format("simulate --out {} --length 30", sim)).exit_code, 0);
  ASSERT_EQ(test::run_citymesh(run_args(sim, "c", "--set tiling.tile_size=10")).exit_code, 0);
  const auto reference = test::result_bytes(dir / "sim/c");

  const auto changed =
      test::run_citymesh(run_args(sim, "c", "--set tiling.tile_size=10 --set change.distance_threshold=0.2"));
  EXPECT_EQ(changed.exit_code, 1);
  EXPECT_NE(changed.err.find("change.distance_threshold (0.1 -> 0.2)"), std::string::npos) << changed.err;
  EXPECT_NE(changed.err.find("--force"), std::string::npos) << changed.err;
  // The same config named from another working directory (a relative path) resumes: every
  // tile is reused.
  const std::string relative = fmt::format("cd '{}' && {} {} >/dev/null 2>&1", dir.path().string(), CITYMESH_BINARY,
                                           run_args("sim", "c", "--set tiling.tile_size=10"));
  EXPECT_EQ(std::system(relative.c_str()), 0);
  const nlohmann::json resumed = read_json(dir / "sim/c/run.json");
  EXPECT_EQ(resumed["reused_tiles"], resumed["tiles"]);
  // The project folder moved whole (config, acquisitions, work): it resumes too.
  std::filesystem::rename(dir / "sim", dir / "moved");
  const auto moved = test::run_citymesh(run_args((dir / "moved").string(), "c", "--set tiling.tile_size=10"));
  EXPECT_EQ(moved.exit_code, 0) << moved.err;
  const nlohmann::json resumed_moved = read_json(dir / "moved/c/run.json");
  EXPECT_EQ(resumed_moved["reused_tiles"], resumed_moved["tiles"]);
  std::filesystem::rename(dir / "moved", dir / "sim");
  // Settings that do not change results (threads, memory, pictures) resume freely, to the
  // same bytes with the smallest budget.
  const auto small = test::run_citymesh(run_args(sim, "c", "--set tiling.tile_size=10 --threads 1 --memory 64MiB"));
  ASSERT_EQ(small.exit_code, 0) << small.err;
  EXPECT_TRUE(test::result_bytes(dir / "sim/c") == reference);

  // A damaged tile result is processed again, to the same bytes.
  const std::filesystem::path results = dir / ("sim/work-c/results");
  const auto first = std::filesystem::directory_iterator(results)->path();
  test::write_text(first, test::read_text(first).substr(0, 100));
  const auto redone = test::run_citymesh(run_args(sim, "c", "--set tiling.tile_size=10"));
  ASSERT_EQ(redone.exit_code, 0) << redone.err;
  EXPECT_NE(redone.err.find("processed again"), std::string::npos) << redone.err;
  EXPECT_TRUE(test::result_bytes(dir / "sim/c") == reference);

  // A rewritten input file (same bytes, new modification time) is redone, not refused.
  const std::string input = test::read_text(dir / "sim/acq_0.ply");
  std::filesystem::remove(dir / "sim/acq_0.ply");
  test::write_text(dir / "sim/acq_0.ply", input);
  const auto rewritten = test::run_citymesh(run_args(sim, "c", "--set tiling.tile_size=10"));
  ASSERT_EQ(rewritten.exit_code, 0) << rewritten.err;
  EXPECT_NE(rewritten.err.find("acq_0.ply) was rewritten since the last run (same size"), std::string::npos)
      << rewritten.err;
  EXPECT_EQ(read_json(dir / "sim/c/run.json")["reused_tiles"], 0);
  EXPECT_GT(read_json(dir / "sim/c/run.json")["triangles_per_second"].get<double>(), 0.0);
  EXPECT_TRUE(test::result_bytes(dir / "sim/c") == reference);

  const auto forced =
      test::run_citymesh(run_args(sim, "c", "--set tiling.tile_size=10 --set change.distance_threshold=0.2 --force"));
  EXPECT_EQ(forced.exit_code, 0) << forced.err;
  EXPECT_EQ(read_json(dir / "sim/c/run.json")["reused_tiles"], 0);
}

TEST(TiledRun, AnotherBuildsTileResultsAreMadeAgainAndThisBuildsAreReused) {
  // An upgraded citymesh may decide otherwise: a work folder another build filled is done
  // again (its tiling kept), never mixed into this build's output.
  test::TempDir dir;
  const std::string sim = (dir / "sim").string();
  ASSERT_EQ(test::run_citymesh(fmt::format("simulate --out {} --length 30", sim)).exit_code, 0);
  const std::filesystem::path other = test::copy_as_another_build(dir.path());
  const auto by_other = test::run_program(other, run_args(sim, "c", "--set tiling.tile_size=10"));
  ASSERT_EQ(by_other.exit_code, 0) << by_other.err;
  const nlohmann::json other_build = read_json(dir / "sim/c/run.json")["citymesh"];
  const auto made_again = test::run_citymesh(run_args(sim, "c", "--set tiling.tile_size=10"));
  ASSERT_EQ(made_again.exit_code, 0) << made_again.err;
  EXPECT_NE(made_again.err.find("made by another build of citymesh"), std::string::npos) << made_again.err;
  const nlohmann::json report = read_json(dir / "sim/c/run.json");
  EXPECT_EQ(report["reused_tiles"], 0);
  EXPECT_GT(report["tiles"].get<int>(), 1);
  EXPECT_NE(made_again.err.find("reusing the tile store"), std::string::npos) << made_again.err;
  // run.json names the build that made the whole output.
  EXPECT_EQ(report["citymesh"]["version"], other_build["version"]);
  EXPECT_EQ(report["citymesh"]["build"].get<std::string>().size(), 16u);
  EXPECT_NE(report["citymesh"]["build"], other_build["build"]);
  std::filesystem::remove(dir / "sim/c/run.json");  // else the outputs are found up to date
  const auto reused = test::run_citymesh(run_args(sim, "c", "--set tiling.tile_size=10"));
  ASSERT_EQ(reused.exit_code, 0) << reused.err;
  EXPECT_EQ(reused.err.find("another build"), std::string::npos) << reused.err;
  EXPECT_EQ(read_json(dir / "sim/c/run.json")["reused_tiles"], report["tiles"]);
}

/// The store tiles (by name) that hold triangles of acquisition `a` (any role) and those
/// that hold none, as the tile manifest counts them.
struct TilesByPass {
  std::set<std::string> holding, others;
};
TilesByPass tiles_by_pass(const nlohmann::json& manifest, std::size_t a) {
  TilesByPass out;
  for (const auto& tile : manifest["tiles"]) {
    const auto& counts = tile["triangles"];
    const bool holds =
        counts.size() > a && counts[a][0].get<int>() + counts[a][1].get<int>() + counts[a][2].get<int>() > 0;
    (holds ? out.holding : out.others).insert(fmt::format("{}_{}", tile["i"].get<int>(), tile["j"].get<int>()));
  }
  return out;
}

/// The per_tile entries of the tiles a run processed (its report's tiles not marked reused).
std::vector<nlohmann::json> processed_entries(const nlohmann::json& report) {
  std::vector<nlohmann::json> processed;
  for (const auto& entry : report["per_tile"]) {
    if (!entry.contains("reused")) processed.push_back(entry);
  }
  return processed;
}

/// The tiles a run processed.
std::set<std::string> processed_tiles(const nlohmann::json& report) {
  std::set<std::string> processed;
  for (const auto& entry : processed_entries(report)) processed.insert(entry["tile"].get<std::string>());
  return processed;
}

/// A 60 m street in <dir>/sim with five.toml (its first five passes) and six.toml, whose
/// sixth pass covers the first 21 m of the street on one side and 27.8 m on the other: it ends
/// in the third of six 10 m tile columns, whose later-phase neighbours in the fourth wait for
/// it. Their border with the third is 9 m from the pass's end on the first side (decisions
/// there unchanged: those tiles are kept) and 2.2 m on the other (a decision on their halo
/// changed: redone). False when the street could not be made.
bool write_append_street(const std::filesystem::path& dir) {
  return test::run_citymesh(fmt::format("simulate --out {} --length 60", (dir / "sim").string())).exit_code == 0 &&
         test::write_append_configs(dir / "sim", 0.35, 27.8 / 60);
}

TEST(TiledRun, AnAppendedAcquisitionRedoesOnlyTheTilesItReachesToTheBytesOfAFreshRun) {
  test::TempDir dir;
  const std::string sim = (dir / "sim").string();
  // Five passes first; then the sixth is appended.
  ASSERT_TRUE(write_append_street(dir.path()));
  const auto run = [&](const std::string& file, const std::string& name) {
    return test::run_citymesh(run_file_args(sim, file, name, "--set tiling.tile_size=10"));
  };
  const auto five = run("five.toml", "u");
  ASSERT_EQ(five.exit_code, 0) << five.err;
  const auto appended = run("six.toml", "u");
  ASSERT_EQ(appended.exit_code, 0) << appended.err;
  // Named relative to the config's folder, where it lies.
  EXPECT_NE(appended.err.find("acquisition[5] (acq_5_part.ply) was added"), std::string::npos) << appended.err;
  EXPECT_NE(appended.err.find("reusing the tiling of 5 of 6 acquisitions"), std::string::npos) << appended.err;
  const nlohmann::json report = read_json(dir / "sim/u/run.json");
  expect_some_tiles_reused(report, "tiles far from the new pass", "tiles the new pass reaches");
  // Progress counts the tiles to process, not the reused ones (nor do they enter the ETA).
  const int redone = report["tiles"].get<int>() - report["reused_tiles"].get<int>();
  EXPECT_NE(
      appended.err.find(fmt::format("tiles {}/{} ({} reused)", redone, redone, report["reused_tiles"].get<int>())),
      std::string::npos)
      << appended.err;

  // The tiles redone are those the new pass reaches (their inputs changed) and later-phase
  // neighbours whose border decisions changed; the other later-phase neighbours of redone
  // tiles keep their results (kept_after_neighbours).
  const std::set<std::string> reached = tiles_by_pass(read_json(dir / "sim/work-u/tiles/manifest.json"), 5).holding;
  const std::set<std::string> processed = processed_tiles(report);
  EXPECT_FALSE(reached.empty());
  for (const std::string& tile : reached) EXPECT_TRUE(processed.contains(tile)) << tile << " is reached";
  EXPECT_GT(report["kept_tiles"].get<int>(), 0) << "later-phase neighbours of reached tiles, decisions unchanged";
  EXPECT_EQ(processed.size() + report["reused_tiles"].get<std::size_t>(), report["tiles"].get<std::size_t>());

  const auto fresh = run("six.toml", "f");
  ASSERT_EQ(fresh.exit_code, 0) << fresh.err;
  ASSERT_GE(test::result_bytes(dir / "sim/f").size(), 8u);
  expect_same_outputs(dir / "sim/u", dir / "sim/f", "appending differs from a fresh run");

  // Withdrawing the appended pass again (found faulty, say) renumbers no other: like
  // appending it, it redoes only the tiles it reached, to the bytes of a fresh run (its
  // labelled PLY removed from the outputs).
  const auto withdrawn = run("five.toml", "u");
  ASSERT_EQ(withdrawn.exit_code, 0) << withdrawn.err;
  EXPECT_NE(withdrawn.err.find("acquisition[5] (acq_5_part.ply) was withdrawn"), std::string::npos) << withdrawn.err;
  EXPECT_EQ(withdrawn.err.find("do not fit"), std::string::npos) << withdrawn.err;
  const nlohmann::json after = read_json(dir / "sim/u/run.json");
  expect_some_tiles_reused(after, "tiles the pass did not reach", "tiles the pass reached");
  const auto five_fresh = run("five.toml", "g");
  ASSERT_EQ(five_fresh.exit_code, 0) << five_fresh.err;
  expect_same_outputs(dir / "sim/u", dir / "sim/g", "withdrawing differs from a fresh run");
}

/// What the first line of `run --plan` says: tiles in all, to process and their input
/// triangles, kept unless a neighbour decides otherwise (and theirs), reused. Zeros and a
/// failure when the line is not there.
struct PlanLine {
  long tiles = 0, to_process = 0, to_process_triangles = 0, may_be_kept = 0, may_be_kept_triangles = 0, reused = 0;
};
PlanLine plan_line(const std::string& out) {
  PlanLine p;
  const std::size_t at = out.find("plan: ");
  const std::string line = at == std::string::npos ? std::string() : out.substr(at, out.find('\n', at) - at);
  const std::size_t kept = line.find(" kept unless ");
  const std::size_t reused = line.rfind(", ");
  bool read = std::sscanf(line.c_str(), "plan: %ld tiles: %ld to process (%ld input triangles)", &p.tiles,
                          &p.to_process, &p.to_process_triangles) == 3 &&
              reused != std::string::npos && std::sscanf(line.c_str() + reused, ", %ld reused", &p.reused) == 1;
  if (read && kept != std::string::npos) {
    const std::size_t count = line.rfind(", ", kept), triangles = line.find('(', kept);
    read = count != std::string::npos && triangles != std::string::npos &&
           std::sscanf(line.c_str() + count, ", %ld", &p.may_be_kept) == 1 &&
           std::sscanf(line.c_str() + triangles, "(%ld input triangles)", &p.may_be_kept_triangles) == 1;
  }
  if (!read) ADD_FAILURE() << "no plan line in:\n" << out;
  return p;
}

/// The owned triangles of the tiles `report` (run.json) says were processed.
long processed_triangles(const nlohmann::json& report) {
  long n = 0;
  for (const auto& entry : processed_entries(report)) n += entry["owned"].get<long>();
  return n;
}

TEST(TiledRun, APlanSaysWhatARunWouldDoWithEachTileAndDoesNoneOfIt) {
  test::TempDir dir;
  const std::string sim = (dir / "sim").string();
  // As in the append test above: a sixth pass that some tiles' neighbours wait for.
  ASSERT_TRUE(write_append_street(dir.path()));
  const auto command = [&](const std::string& file, const std::string& extra) {
    return test::run_citymesh(run_file_args(sim, file, "u", "--set tiling.tile_size=10 " + extra));
  };

  // A new work folder: every tile to process, none processed, no output, no run recorded.
  const auto fresh = command("five.toml", "--plan");
  ASSERT_EQ(fresh.exit_code, 0) << fresh.err;
  const PlanLine first = plan_line(fresh.out);
  EXPECT_GT(first.tiles, 8);
  EXPECT_EQ(first.to_process, first.tiles);
  EXPECT_EQ(first.may_be_kept + first.reused, 0);
  EXPECT_NE(fresh.out.find("no estimate of the time"), std::string::npos) << fresh.out;
  EXPECT_TRUE(!std::filesystem::exists(dir / "sim/work-u/results") ||
              std::filesystem::is_empty(dir / "sim/work-u/results"));
  EXPECT_FALSE(std::filesystem::exists(dir / "sim/u"));
  EXPECT_FALSE(std::filesystem::exists(dir / "sim/work-u/run-config.json"));

  const auto five = command("five.toml", "");
  ASSERT_EQ(five.exit_code, 0) << five.err;
  const nlohmann::json five_report = read_json(dir / "sim/u/run.json");
  EXPECT_EQ(five_report["tiles"].get<long>(), first.tiles);
  EXPECT_EQ(processed_triangles(five_report), first.to_process_triangles);
  const auto outputs = test::result_bytes(dir / "sim/u");
  const auto results = test::result_bytes(dir / "sim/work-u/results");

  // The sixth pass appended: the plan tiles it, and changes no result and no output.
  const auto planned = command("six.toml", "--plan --threads 2");
  ASSERT_EQ(planned.exit_code, 0) << planned.err;
  const PlanLine plan = plan_line(planned.out);
  EXPECT_GT(plan.to_process, 0);
  EXPECT_GT(plan.may_be_kept, 0) << "later-phase neighbours of the tiles the pass reaches";
  EXPECT_GT(plan.reused, 0);
  EXPECT_EQ(plan.to_process + plan.may_be_kept + plan.reused, plan.tiles);
  EXPECT_TRUE(test::result_bytes(dir / "sim/work-u/results") == results) << "the plan changed a tile result";
  EXPECT_TRUE(test::result_bytes(dir / "sim/u") == outputs) << "the plan changed an output";
  // The estimate is the five-pass run's thread-seconds per triangle over the triangles to
  // process and those that may be kept, on two threads.
  double seconds = 0;
  for (const auto& entry : five_report["per_tile"]) {
    for (const auto& [step, s] : entry["seconds"].items()) seconds += s.get<double>();
  }
  const double per_thread = seconds / static_cast<double>(first.to_process_triangles) / 2;
  EXPECT_NE(
      planned.out.find(fmt::format(
          "would take {:.1f} to {:.1f} s on 2 thread(s)", static_cast<double>(plan.to_process_triangles) * per_thread,
          static_cast<double>(plan.to_process_triangles + plan.may_be_kept_triangles) * per_thread)),
      std::string::npos)
      << planned.out;

  // The run does what the plan said: it processes every tile to process, and of those that
  // may be kept, keeps the ones whose neighbours decided the same.
  const auto appended = command("six.toml", "");
  ASSERT_EQ(appended.exit_code, 0) << appended.err;
  const nlohmann::json report = read_json(dir / "sim/u/run.json");
  const long processed = report["tiles"].get<long>() - report["reused_tiles"].get<long>();
  const long kept = report["kept_tiles"].get<long>();
  EXPECT_EQ(processed + kept, plan.to_process + plan.may_be_kept);
  EXPECT_GE(processed, plan.to_process);
  EXPECT_GE(processed_triangles(report), plan.to_process_triangles);
  EXPECT_LE(processed_triangles(report), plan.to_process_triangles + plan.may_be_kept_triangles);
  EXPECT_EQ(report["reused_tiles"].get<long>() - kept, plan.reused);

  // Planned again: nothing left to do.
  const auto again = command("six.toml", "--plan");
  ASSERT_EQ(again.exit_code, 0) << again.err;
  const PlanLine none = plan_line(again.out);
  EXPECT_EQ(none.reused, none.tiles);
  EXPECT_NE(again.out.find("the outputs are the last run's, made from the same: the run would write nothing"),
            std::string::npos)
      << again.out;
  // With an output gone, the final pass only.
  std::filesystem::remove(dir / "sim/u/run.json");
  const auto outputs_gone = command("six.toml", "--plan");
  EXPECT_NE(outputs_gone.out.find("the run would do the final pass only"), std::string::npos) << outputs_gone.out;

  // What --plan does not take.
  EXPECT_EQ(command("six.toml", "--plan --force").exit_code, 1);
  EXPECT_EQ(command("six.toml", "--plan --subset 1/2").exit_code, 1);
}

/// The simulator's config with epoch 2's table moved to the end (a pass delivered late), and
/// with it left out (the passes before it was delivered). False when the config is not the
/// simulator's six passes.
bool write_late_configs(const std::filesystem::path& sim) {
  const std::string config = test::read_text(sim / "config.toml");
  const std::size_t path = config.find("path = \"acq_2.ply\"");
  if (path == std::string::npos) return false;
  const std::size_t begin = config.rfind("[[acquisition]]", path), end = config.find("[[acquisition]]", path);
  if (begin == std::string::npos || end == std::string::npos) return false;
  const std::string rest = config.substr(0, begin) + config.substr(end);
  test::write_text(sim / "late.toml", rest + "\n" + config.substr(begin, end - begin));
  test::write_text(sim / "five.toml", rest);
  return true;
}

/// The mosaic PLY's rows: positions, then per triangle its corners, source_acq and source_face.
struct MosaicRows {
  std::vector<Vec3d> positions;
  std::vector<Triangle> triangles;
  std::vector<double> source_acq, source_face;
};

MosaicRows mosaic_rows(const std::filesystem::path& ply) {
  app::FaceTable t = app::read_face_table(ply, {"source_acq", "source_face"});
  return {std::move(t.positions), std::move(t.triangles), std::move(t.extras[0]), std::move(t.extras[1])};
}

/// `late`, the mosaic PLY of a config listing the passes in another order than `in_order`'s,
/// holds the same map: the same rows to the byte, each source_acq renamed as `listed_at` (per
/// place in `in_order`'s file, the place in `late`'s) says.
void expect_same_map_renamed(const std::filesystem::path& in_order, const std::filesystem::path& late,
                             const std::vector<int>& listed_at) {
  const MosaicRows d = mosaic_rows(in_order), l = mosaic_rows(late);
  ASSERT_GT(d.triangles.size(), 1000u);
  EXPECT_TRUE(d.positions == l.positions);
  EXPECT_TRUE(d.triangles == l.triangles);
  EXPECT_TRUE(d.source_face == l.source_face);
  ASSERT_EQ(d.source_acq.size(), l.source_acq.size());
  std::set<int> places;
  for (std::size_t t = 0; t < d.source_acq.size(); ++t) {
    const int place = static_cast<int>(d.source_acq[t]);
    ASSERT_EQ(static_cast<int>(l.source_acq[t]), place < 0 ? place : listed_at.at(static_cast<std::size_t>(place)))
        << "triangle " << t;
    places.insert(place);
  }
  EXPECT_GE(places.size(), listed_at.size()) << "every pass in the map (and stitching's -1)";
}

TEST(TiledRun, AcquisitionsListedOutOfDateOrderGiveTheSameMapNamedByTheirPlaceInTheFile) {
  test::TempDir dir;
  const std::string sim = (dir / "sim").string();
  ASSERT_EQ(test::run_citymesh(fmt::format("simulate --out {} --length 30", sim)).exit_code, 0);
  ASSERT_TRUE(write_late_configs(dir / "sim"));
  const auto run = [&](const std::string& file, const std::string& name) {
    return test::run_citymesh(run_file_args(sim, file, name, "--set tiling.tile_size=10"));
  };
  const auto in_order = run("config.toml", "d");
  ASSERT_EQ(in_order.exit_code, 0) << in_order.err;
  const auto late = run("late.toml", "l");
  ASSERT_EQ(late.exit_code, 0) << late.err;
  EXPECT_NE(late.err.find("acquisition[5] (epoch 2) is listed after newer passes: it is processed 3rd by time"),
            std::string::npos)
      << late.err;
  EXPECT_EQ(in_order.err.find("is listed after newer passes"), std::string::npos) << in_order.err;

  // Listed at place 5, epoch 2 is processed third as before: the same map to the byte, each
  // pass named by its place in the file (epochs 3 to 5 move up one).
  const std::vector<int> listed_at{0, 1, 5, 2, 3, 4};  // per epoch
  expect_same_map_renamed(dir / "sim/d/mosaic/mosaic.ply", dir / "sim/l/mosaic/mosaic.ply", listed_at);
  // The other results have the same bytes; the labelled PLYs are named by place in the file.
  std::map<std::string, std::string> expected;
  for (auto& [name, bytes] : test::result_bytes(dir / "sim/d")) {
    if (name == "mosaic/mosaic.ply") continue;
    std::string renamed = name;
    if (name.starts_with("detect/") && name.ends_with(".ply")) {
      const int epoch = std::stoi(name.substr(7));
      renamed = fmt::format("detect/{}{}", listed_at.at(static_cast<std::size_t>(epoch)), name.substr(name.find('_')));
    }
    expected[renamed] = std::move(bytes);
  }
  std::map<std::string, std::string> got = test::result_bytes(dir / "sim/l");
  got.erase("mosaic/mosaic.ply");
  EXPECT_TRUE(got == expected);
  EXPECT_TRUE(got.contains("detect/5_epoch 2.ply"));
  const nlohmann::json summary = read_json(dir / "sim/l/mosaic/summary.json");
  EXPECT_EQ(summary["acquisitions"][5]["name"], "epoch 2");
  EXPECT_EQ(summary["acquisitions"][5]["index"], 5);
  // Scored, the same figures to the byte: eval adds the passes up by date too.
  for (const char* name : {"d", "l"}) {
    const auto eval = test::run_citymesh(fmt::format("eval {}/{} --truth {}", sim, name, sim));
    ASSERT_EQ(eval.exit_code, 0) << eval.err;
  }
  EXPECT_EQ(test::read_text(dir / "sim/d/eval.json"), test::read_text(dir / "sim/l/eval.json"));
  // The tables reordered in a finished run's config: all its work is reused, the outputs
  // renamed (they are written again).
  const auto reordered = run("late.toml", "d");
  ASSERT_EQ(reordered.exit_code, 0) << reordered.err;
  const nlohmann::json report = read_json(dir / "sim/d/run.json");
  EXPECT_EQ(report["reused_tiles"], report["tiles"]);
  EXPECT_TRUE(test::result_bytes(dir / "sim/d") == test::result_bytes(dir / "sim/l"));

  // The same without tiles (detect, then mosaic); a mosaic on the labels of another listing
  // is refused, naming the summary.
  const auto untiled = [&](const std::string& file, const std::string& name, const char* step) {
    return test::run_citymesh(fmt::format("{} {}/{} --no-pictures --set project.output={} --set project.work=work-{}",
                                          step, sim, file, name, name));
  };
  for (const auto& [file, name] : {std::pair{"config.toml", "ud"}, std::pair{"late.toml", "ul"}}) {
    for (const char* step : {"detect", "mosaic"}) ASSERT_EQ(untiled(file, name, step).exit_code, 0) << step;
  }
  expect_same_map_renamed(dir / "sim/ud/mosaic/mosaic.ply", dir / "sim/ul/mosaic/mosaic.ply", listed_at);
  const auto mixed = untiled("late.toml", "ud", "mosaic");
  EXPECT_NE(mixed.exit_code, 0);
  EXPECT_NE(mixed.err.find("detect/summary.json: acquisition 5 is"), std::string::npos) << mixed.err;
  EXPECT_NE(mixed.err.find("run citymesh detect again"), std::string::npos) << mixed.err;

  // Delivered late into a run of the five others, the pass is processed among them by date:
  // the run resumes (no config change) to the bytes of a fresh run.
  ASSERT_EQ(run("five.toml", "i").exit_code, 0);
  const auto inserted = run("late.toml", "i");
  ASSERT_EQ(inserted.exit_code, 0) << inserted.err;
  EXPECT_NE(inserted.err.find("1 pass(es) added since the last run, older than passes already processed"),
            std::string::npos)
      << inserted.err;
  expect_same_outputs(dir / "sim/i", dir / "sim/l", "a pass delivered late differs from a fresh run");
}

/// Epoch 2's pass cut to the first `share` of the street (acq_2_part.ply), its table listed
/// last in late-part.toml after the five others (five.toml, as write_late_configs). False when
/// the config is not the simulator's six passes.
bool write_late_part_configs(const std::filesystem::path& sim, double share) {
  if (!write_late_configs(sim)) return false;
  std::string late = test::read_text(sim / "late.toml");
  const std::size_t path = late.find("acq_2.ply");
  if (path == std::string::npos) return false;
  late.replace(path, 9, "acq_2_part.ply");
  test::write_text(sim / "late-part.toml", late);
  write_mesh_ply(sim / "acq_2_part.ply", test::first_part(read_mesh(sim / "acq_2.ply").mesh, share));
  return true;
}

TEST(TiledRun, APassDeliveredLateRedoesOnlyTheTilesItReachesTheOthersRenumberedToTheBytesOfAFreshRun) {
  test::TempDir dir;
  const std::string sim = (dir / "sim").string();
  ASSERT_EQ(test::run_citymesh(fmt::format("simulate --out {} --length 60", sim)).exit_code, 0);
  // Epoch 2 over the first 21 m of the 60 m street, delivered after the run of the five
  // others: epochs 3 to 5 become 3rd to 5th by time in every tile, but only the tiles of the
  // first three 10 m columns (and their later-phase neighbours) hold the new pass.
  ASSERT_TRUE(write_late_part_configs(dir / "sim", 0.35));
  const auto run = [&](const std::string& file, const std::string& name) {
    return test::run_citymesh(run_file_args(sim, file, name, "--set tiling.tile_size=10"));
  };
  ASSERT_EQ(run("five.toml", "l").exit_code, 0);
  const auto five = test::result_bytes(dir / "sim/l");
  const auto late = run("late-part.toml", "l");
  ASSERT_EQ(late.exit_code, 0) << late.err;
  EXPECT_NE(late.err.find("1 pass(es) added since the last run, older than passes already processed"),
            std::string::npos)
      << late.err;
  // Only the late pass is tiled: the three after it have their tiling moved up one.
  EXPECT_NE(late.err.find("the tiling of 3 renumbered acquisition(s) moved"), std::string::npos) << late.err;
  EXPECT_NE(late.err.find("reusing the tiling of 5 of 6 acquisitions"), std::string::npos) << late.err;
  const nlohmann::json report = read_json(dir / "sim/l/run.json");
  const nlohmann::json manifest = read_json(dir / "sim/work-l/tiles/manifest.json");
  for (const auto& tile : manifest["tiles"]) ASSERT_EQ(tile["triangles"].size(), 6u);
  // Reached by epoch 2 (now acquisition 2 by time), and the others.
  const auto [reached, renumbered] = tiles_by_pass(manifest, 2);
  ASSERT_FALSE(reached.empty());
  ASSERT_FALSE(renumbered.empty());
  const std::set<std::string> processed = processed_tiles(report);
  for (const std::string& tile : reached) EXPECT_TRUE(processed.contains(tile)) << tile << " is reached";
  // Every tile holds a renumbered pass, so none is reused as it was; those the new pass does
  // not reach are kept renumbered, unless a decision on their border changed.
  EXPECT_EQ(report["reused_tiles"], report["kept_tiles"]);
  EXPECT_GE(report["kept_tiles"].get<std::size_t>(), renumbered.size() / 2) << late.err;
  EXPECT_LT(processed.size(), report["tiles"].get<std::size_t>());

  const auto fresh = run("late-part.toml", "f");
  ASSERT_EQ(fresh.exit_code, 0) << fresh.err;
  ASSERT_GE(test::result_bytes(dir / "sim/f").size(), 8u);
  expect_same_outputs(dir / "sim/l", dir / "sim/f", "a pass delivered late differs from a fresh run");

  // Removed again (found faulty): the later passes move back down, the tiles it reached are
  // redone and the others kept, renumbered, to the bytes of the first run.
  const auto removed = run("five.toml", "l");
  ASSERT_EQ(removed.exit_code, 0) << removed.err;
  EXPECT_EQ(removed.err.find("processed again"), std::string::npos) << removed.err;
  EXPECT_NE(removed.err.find("reusing the tiling of 5 of 5 acquisitions"), std::string::npos) << removed.err;
  const nlohmann::json after = read_json(dir / "sim/l/run.json");
  EXPECT_EQ(after["reused_tiles"], after["kept_tiles"]);
  EXPECT_GE(after["kept_tiles"].get<std::size_t>(), renumbered.size() / 2) << removed.err;
  EXPECT_TRUE(test::result_bytes(dir / "sim/l") == five) << "removing the late pass differs from the first run";
}

/// `files` without the change step's labelled outputs (detect/...).
std::map<std::string, std::string> without_labels(std::map<std::string, std::string> files) {
  std::erase_if(files, [](const auto& f) { return f.first.starts_with("detect/"); });
  return files;
}

TEST(TiledRun, APassWithdrawnInPlaceIsReadAsEmptyAndPutBackGivesTheFirstBytes) {
  test::TempDir dir;
  const std::filesystem::path sim = dir / "sim";
  ASSERT_EQ(test::run_citymesh(fmt::format("simulate --out {} --length 30", sim.string())).exit_code, 0);
  const auto run = [&](const std::string& config, const std::string& name) {
    return test::run_citymesh(run_file_args(sim.string(), config, name, "--set tiling.tile_size=10"));
  };
  ASSERT_EQ(run("config.toml", "w").exit_code, 0);
  const auto first = test::result_bytes(sim / "w");
  ASSERT_TRUE(first.contains("detect/1_epoch 1.ply"));

  // Acquisition 1 found faulty: withdrawn in place, its file moved away (it is not read).
  const std::string config = test::read_text(sim / "config.toml");
  std::string withdrawn = config;
  withdrawn.replace(withdrawn.find("path = \"acq_1.ply\"\n") + 19, 0, "withdrawn = true\n");
  test::write_text(sim / "withdrawn.toml", withdrawn);
  std::filesystem::rename(sim / "acq_1.ply", sim / "acq_1.moved");
  const auto without = run("withdrawn.toml", "w");
  ASSERT_EQ(without.exit_code, 0) << without.err;
  EXPECT_NE(without.err.find("acquisition[1] (acq_1.ply) was withdrawn"), std::string::npos) << without.err;
  const auto after = test::result_bytes(sim / "w");
  EXPECT_FALSE(after.contains("detect/1_epoch 1.ply")) << "its labelled PLY removed";
  EXPECT_TRUE(after.contains("detect/2_epoch 2.ply")) << "no pass renumbered";
  EXPECT_TRUE(read_json(sim / "w/detect/summary.json")["acquisitions"][1]["withdrawn"].get<bool>());
  EXPECT_EQ(test::run_citymesh(fmt::format("eval {}/w --truth {}", sim.string(), sim.string())).exit_code, 0);

  // The output is that of a fresh run in which the pass's file holds no triangle.
  test::write_text(sim / "empty.ply",
                   "ply\nformat ascii 1.0\nelement vertex 0\nproperty double x\nproperty double y\n"
                   "property double z\nproperty double x_origin\nproperty double y_origin\nproperty double z_origin\n"
                   "element face 0\nproperty list uchar uint vertex_indices\nend_header\n");
  std::string emptied = config;
  emptied.replace(emptied.find("acq_1.ply"), 9, "empty.ply");
  test::write_text(sim / "emptied.toml", emptied);
  ASSERT_EQ(run("emptied.toml", "e").exit_code, 0);
  const auto reference = without_labels(test::result_bytes(sim / "e"));
  ASSERT_TRUE(reference.contains("mosaic/mosaic.ply"));
  EXPECT_TRUE(without_labels(after) == reference) << "withdrawn differs from an empty file";
  EXPECT_NE(without_labels(after), without_labels(first));

  // Put back: the bytes of the first run, its labelled PLY again.
  std::filesystem::rename(sim / "acq_1.moved", sim / "acq_1.ply");
  const auto back = run("config.toml", "w");
  ASSERT_EQ(back.exit_code, 0) << back.err;
  EXPECT_NE(back.err.find("acquisition[1] (acq_1.ply) is no longer withdrawn"), std::string::npos) << back.err;
  EXPECT_TRUE(test::result_bytes(sim / "w") == first);

  // A run that writes no labels leaves none of an earlier run's beside its mosaic.
  const auto unlabelled =
      test::run_citymesh(run_args(sim.string(), "w", "--set tiling.tile_size=10 --set output.labels=false"));
  ASSERT_EQ(unlabelled.exit_code, 0) << unlabelled.err;
  EXPECT_FALSE(std::filesystem::exists(sim / "w/detect/summary.json"));
  EXPECT_FALSE(std::filesystem::exists(sim / "w/detect/0_epoch 0.ply"));
  EXPECT_FALSE(std::filesystem::exists(sim / "w/detect/pairs.bin"));
  EXPECT_TRUE(std::filesystem::exists(sim / "w/mosaic/mosaic.ply"));
  const auto no_labels = test::run_citymesh(fmt::format("eval {}/w --truth {}", sim.string(), sim.string()));
  EXPECT_EQ(no_labels.exit_code, 2);
  EXPECT_NE(no_labels.err.find("labels = true"), std::string::npos) << no_labels.err;
}

/// The face count a PLY header declares.
std::size_t ply_faces(const std::filesystem::path& ply) {
  const std::string text = test::read_text(ply);
  const auto at = text.find("element face ");
  return at == std::string::npos ? 0 : std::stoul(text.substr(at + 13));
}

/// One stage's progress lines (StageProgress: "<stage> <done>/<total>, ETA ..."), in order,
/// with the place in `err` of each.
struct ProgressLine {
  std::size_t at = 0;
  long done = 0, total = 0;
};
std::vector<ProgressLine> progress_lines(const std::string& err, const std::string& stage) {
  std::vector<ProgressLine> lines;
  for (std::size_t at = err.find(stage + " "); at != std::string::npos; at = err.find(stage + " ", at + 1)) {
    ProgressLine l{.at = at};
    EXPECT_EQ(std::sscanf(err.c_str() + at + stage.size(), " %ld/%ld, ETA", &l.done, &l.total), 2)
        << err.substr(at, 80);
    lines.push_back(l);
  }
  return lines;
}

TEST(TiledRun, TheFinalPassSaysHowFarEachOfItsStagesHasGot) {
  test::TempDir dir;
  const std::string sim = (dir / "sim").string();
  ASSERT_EQ(test::run_citymesh(fmt::format("simulate --out {} --length 30", sim)).exit_code, 0);
  // Tiles of 20 m: wide enough for the seam pass by blocks (10 m tiles are stitched whole).
  const auto run = test::run_citymesh(run_args(sim, "out", "--set tiling.tile_size=20"));
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const nlohmann::json parts = read_json(dir / "sim/out/mosaic/summary.json")["stitch"]["by_blocks"]["parts"];
  long part_count = 0;
  for (const auto& n : parts) part_count += n.get<long>();
  const long tiles = read_json(dir / "sim/out/run.json")["tiles"].get<long>();
  // Each stage counts up to its total and ends on it, once; the stages come in order.
  std::size_t after = run.err.find("tiles " + std::to_string(tiles) + "/" + std::to_string(tiles));
  ASSERT_NE(after, std::string::npos) << run.err;
  for (const auto& [stage, total] :
       std::vector<std::pair<std::string, long>>{{"final pass: tile results read", tiles},
                                                 {"final pass: seam parts stitched", part_count},
                                                 {"final pass: 3D Tiles cells built", -1}}) {
    const std::vector<ProgressLine> lines = progress_lines(run.err, stage);
    ASSERT_FALSE(lines.empty()) << stage << " said nothing:\n" << run.err;
    for (std::size_t k = 0; k < lines.size(); ++k) {
      EXPECT_EQ(lines[k].total, total < 0 ? lines[0].total : total) << stage;
      EXPECT_LE(lines[k].done, lines[k].total) << stage;
      EXPECT_EQ(lines[k].done == lines[k].total, k + 1 == lines.size()) << stage << ": the total said once, last";
      if (k > 0) {
        EXPECT_GT(lines[k].done, lines[k - 1].done) << stage;
      }
    }
    EXPECT_GT(lines[0].at, after) << stage << " said before the stage before it ended";
    after = lines.back().at;
  }
  EXPECT_GT(part_count, 1);
  EXPECT_GT(run.err.find("final pass: 3D Tiles: the levels above the cells"), after);
}

TEST(TiledRun, ProvenancePlyPerTileAndTilesetCheck) {
  test::TempDir dir;
  const std::string sim = (dir / "sim").string();
  ASSERT_EQ(test::run_citymesh(fmt::format("simulate --out {} --length 30", sim)).exit_code, 0);
  const auto run = test::run_citymesh(run_args(sim, "p", "--set tiling.tile_size=10 --set output.ply=true"));
  ASSERT_EQ(run.exit_code, 0) << run.err;
  // Every output triangle is in exactly one tile's provenance PLY.
  std::size_t faces = 0, files = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir / "sim/p/ply")) {
    faces += ply_faces(e.path());
    ++files;
  }
  EXPECT_GT(files, 1u);
  EXPECT_EQ(faces, ply_faces(dir / "sim/p/mosaic/mosaic.ply"));
  EXPECT_NE(
      test::read_text(dir / "sim/p/ply" / std::filesystem::directory_iterator(dir / "sim/p/ply")->path().filename())
          .find("property int source_face"),
      std::string::npos);

  const auto ok = test::run_citymesh(fmt::format("check {}/p", sim));
  EXPECT_EQ(ok.exit_code, 0) << ok.out << ok.err;
  EXPECT_NE(ok.out.find("ok"), std::string::npos);
  std::filesystem::path glb;
  for (const auto& e : std::filesystem::directory_iterator(dir / "sim/p/tiles"))
    if (e.path().extension() == ".glb") glb = e.path();
  test::write_text(glb, "glTF but not really");
  const auto broken = test::run_citymesh(fmt::format("check {}/p", sim));
  EXPECT_EQ(broken.exit_code, 2);
  EXPECT_NE(broken.out.find(glb.filename().string() + ": not a valid glb"), std::string::npos) << broken.out;
  EXPECT_EQ(test::run_citymesh(fmt::format("check {}/nothing", sim)).exit_code, 2);
  const auto no_tileset = test::run_citymesh(fmt::format("view {}/nothing --port 0", sim));
  EXPECT_EQ(no_tileset.exit_code, 2);
  EXPECT_NE(no_tileset.err.find("no tileset.json"), std::string::npos) << no_tileset.err;

  // A run that writes neither leaves none of the earlier run's beside its mosaic.
  const auto neither =
      test::run_citymesh(run_args(sim, "p", "--set tiling.tile_size=10 --set output.ply=false --set output.tiles_3d=false"));
  ASSERT_EQ(neither.exit_code, 0) << neither.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "sim/p/ply"));
  EXPECT_FALSE(std::filesystem::exists(dir / "sim/p/tiles"));
  EXPECT_TRUE(std::filesystem::exists(dir / "sim/p/mosaic/mosaic.ply"));
  EXPECT_EQ(test::run_citymesh(fmt::format("check {}/p", sim)).exit_code, 2) << "no tileset to check";
}

TEST(TiledRun, WithoutTheMosaicPlyEveryOtherOutputIsTheSameAndEvalSaysWhyItCannotScore) {
  test::TempDir dir;
  const std::string sim = (dir / "sim").string();
  ASSERT_EQ(test::run_citymesh(fmt::format("simulate --out {} --length 30", sim)).exit_code, 0);
  const std::string args = "--set tiling.tile_size=10 --set output.ply=true";
  ASSERT_EQ(test::run_citymesh(run_args(sim, "p", args)).exit_code, 0);
  std::map<std::string, std::string> with = test::result_bytes(dir / "sim/p");
  const std::size_t mosaic_faces = ply_faces(dir / "sim/p/mosaic/mosaic.ply");
  ASSERT_EQ(with.erase("mosaic/mosaic.ply"), 1u);

  const auto without = test::run_citymesh(run_args(sim, "p", args + " --set output.mosaic_ply=false"));
  ASSERT_EQ(without.exit_code, 0) << without.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "sim/p/mosaic/mosaic.ply")) << "the earlier run's is removed";
  EXPECT_TRUE(std::filesystem::exists(dir / "sim/p/mosaic/summary.json"));
  EXPECT_EQ(nlohmann::json::parse(test::read_text(dir / "sim/p/mosaic/summary.json")).at("ply"), "");
  EXPECT_TRUE(test::result_bytes(dir / "sim/p") == with) << "the tiles, per-tile PLYs and labels are unchanged";
  std::size_t tile_faces = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir / "sim/p/ply")) tile_faces += ply_faces(e.path());
  EXPECT_EQ(tile_faces, mosaic_faces);

  const auto eval = test::run_citymesh(fmt::format("eval {}/p --truth {}", sim, sim));
  EXPECT_EQ(eval.exit_code, 2);
  EXPECT_NE(eval.err.find("mosaic.ply: the run wrote no mosaic ([output] mosaic_ply = false)"), std::string::npos)
      << eval.err;
}

TEST(TiledRun, ARunWithNothingNewLeavesTheOutputsAsTheLastRunWroteThem) {
  test::TempDir dir;
  const std::string sim = (dir / "sim").string();
  ASSERT_EQ(test::run_citymesh(fmt::format("simulate --out {} --length 30", sim)).exit_code, 0);
  const std::string args = run_args(sim, "p", "--set tiling.tile_size=10");
  ASSERT_EQ(test::run_citymesh(args).exit_code, 0);
  const std::map<std::string, std::string> bytes = test::result_bytes(dir / "sim/p");
  const std::string report = test::read_text(dir / "sim/p/run.json");
  const auto skipped = [](const test::CommandResult& r) { return r.out.find("nothing written") != std::string::npos; };

  const auto again = test::run_citymesh(args);
  ASSERT_EQ(again.exit_code, 0) << again.err;
  EXPECT_TRUE(skipped(again)) << again.out;
  EXPECT_EQ(test::read_text(dir / "sim/p/run.json"), report) << "its timings would differ had it been written again";
  EXPECT_TRUE(test::result_bytes(dir / "sim/p") == bytes);

  // An output removed is written again, to the same bytes.
  std::filesystem::path glb;
  for (const auto& e : std::filesystem::directory_iterator(dir / "sim/p/tiles"))
    if (e.path().extension() == ".glb") glb = e.path();
  std::filesystem::remove(glb);
  const auto restored = test::run_citymesh(args);
  ASSERT_EQ(restored.exit_code, 0) << restored.err;
  EXPECT_FALSE(skipped(restored)) << restored.out;
  EXPECT_TRUE(test::result_bytes(dir / "sim/p") == bytes);
  EXPECT_NE(test::read_text(dir / "sim/p/run.json"), report);

  // Another output key, or another picture scale, is not the same run.
  const auto with_ply = test::run_citymesh(args + " --set output.ply=true");
  ASSERT_EQ(with_ply.exit_code, 0) << with_ply.err;
  EXPECT_FALSE(skipped(with_ply)) << with_ply.out;
  EXPECT_TRUE(std::filesystem::is_directory(dir / "sim/p/ply"));
  EXPECT_TRUE(skipped(test::run_citymesh(args + " --set output.ply=true")));
  EXPECT_FALSE(skipped(test::run_citymesh(args + " --set output.ply=true --pixel 0.1")));

  // A record that cannot be read only means the outputs are written again.
  test::write_text(dir / "sim/work-p/outputs.json", "{not json");
  const auto damaged = test::run_citymesh(args + " --set output.ply=true --pixel 0.1");
  ASSERT_EQ(damaged.exit_code, 0) << damaged.err;
  EXPECT_FALSE(skipped(damaged)) << damaged.out;
  EXPECT_TRUE(skipped(test::run_citymesh(args + " --set output.ply=true --pixel 0.1")));
}

}  // namespace
}  // namespace citymesh
