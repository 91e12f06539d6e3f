// SPDX-License-Identifier: MIT
#include "mosaic_step.h"

#include <fmt/format.h>

#include <cmath>
#include <iostream>

#include "citymesh/core/error.h"
#include "citymesh/core/log.h"
#include "citymesh/core/progress.h"
#include "citymesh/core/record_file.h"
#include "citymesh/core/stopwatch.h"
#include "citymesh/mosaic/merged_mesh.h"
#include "citymesh/mosaic/mosaic.h"
#include "citymesh/mosaic/stitch.h"
#include "citymesh/mosaic/stitch_blocks.h"
#include "detect_output.h"
#include "face_table.h"
#include "mosaic_eval.h"
#include "mosaic_output.h"
#include "seam_cache.h"
#include "tileset_output.h"

namespace citymesh::app {

namespace {

/// Strip corners closer than this many distance thresholds are welded (5 mm at 10 cm).
constexpr double kWeldInThresholds = 0.05;

MosaicSelection select(const Config& config, const LoadedAcquisitions& input, const ChangeResult& change) {
  const MosaicInput in{input.meshes, input.dates, &change, config.change.distance_threshold, {}};
  return config.mosaic.method == MosaicMethod::update_model ? select_update_model(in)
                                                            : select_mosaic(in, config.mosaic);
}

}  // namespace

StitchParams stitch_params(const Config& config) {
  const double reach = config.mosaic.stitch_reach * config.change.distance_threshold;
  return {.snap = reach,
          .reach = reach,
          .weld = kWeldInThresholds * config.change.distance_threshold,
          .clip = config.mosaic.clip_overlaps ? config.mosaic.clip_reach * config.change.distance_threshold : 0.0,
          .clip_angle = config.mosaic.clip_angle,
          .gap = config.mosaic.close_gaps ? config.mosaic.gap_width * config.change.distance_threshold : 0.0,
          .join_own_pieces = config.mosaic.stitch_own_pieces,
          .own_clip = config.mosaic.clip_overlaps ? config.change.distance_threshold : 0.0};
}

namespace {

/// Whether the tiles are wide enough for the bands of the seam pass by blocks.
bool tiles_fit_blocks(const Config& config) {
  return 4 * block_context(stitch_params(config)) < config.tiling.tile_size;
}

}  // namespace

bool seam_pass_in_blocks(const Config& config) {
  if (config.mosaic.method != MosaicMethod::energy) return false;  // the baseline is not stitched
  switch (config.run.seam_pass) {
    case SeamPass::blocks:
      return true;
    case SeamPass::whole:
      return false;
    default:
      return tiles_fit_blocks(config);
  }
}

void check_seam_pass(const Config& config) {
  if (config.run.seam_pass != SeamPass::blocks || config.mosaic.method != MosaicMethod::energy) return;
  if (tiles_fit_blocks(config)) return;
  const double band = block_context(stitch_params(config));
  throw ConfigError(
      fmt::format("{}: [run] seam_pass = \"blocks\": tiles of {} m are too small for bands of {:.2f} m (the "
                  "stitching's reach): tiling.tile_size must be over {:.2f} m, or use seam_pass = \"whole\"",
                  config.file.string(), config.tiling.tile_size, band, 4 * band));
}

/// Prints the stitching's line and returns its figures for the summary.
nlohmann::json report_stitching(const StitchStats& s, const BlockStitchStats* blocks) {
  // The centroid splits happen only when a pass's own turns are clipped: said only then.
  const std::string split =
      s.triangles_split > 0 ? fmt::format(" ({} split over an earlier turn's hole first)", s.triangles_split) : "";
  std::cout << fmt::format(
      "stitching: {} triangles clipped{} and {} removed under other surfaces, {} strips and {} gaps closed with {} "
      "triangles, open boundary "
      "{:.1f} m -> {:.1f} m\n",
      s.triangles_clipped, split, s.triangles_uncovered, s.strips, s.gaps_filled, s.triangles_added,
      s.open_boundary_before, s.open_boundary_after);
  nlohmann::json report{{"open_boundary_before_m", s.open_boundary_before},
                        {"open_boundary_after_m", s.open_boundary_after},
                        {"triangles_clipped", s.triangles_clipped},
                        {"triangles_uncovered", s.triangles_uncovered},
                        {"triangles_split", s.triangles_split},
                        {"strips", s.strips},
                        {"gaps_filled", s.gaps_filled},
                        {"triangles_added", s.triangles_added},
                        {"vertices_snapped", s.vertices_snapped},
                        {"edges_split", s.edges_split},
                        {"vertices_welded", s.vertices_welded},
                        {"rejected", s.rejected},
                        {"seconds", s.seconds}};
  if (blocks != nullptr) {
    report["by_blocks"] = {{"parts", blocks->parts},
                           {"largest_part_triangles", blocks->largest_part},
                           {"reused_parts", blocks->reused_parts}};
  }
  return report;
}

nlohmann::json stitch_and_report(const Config& config, MergedMesh& merged) {
  const StitchStats s = stitch(merged, stitch_params(config));
  shrink_to_fit(merged);  // the outputs and the export that follow peak on top of it
  return report_stitching(s, nullptr);
}

BlockStitchParams tile_grid_blocks(const Config& config) {
  return {.origin_x = config.tiling.origin[0],
          .origin_y = config.tiling.origin[1],
          .size = config.tiling.tile_size,
          .band = block_context(stitch_params(config))};
}

nlohmann::json stitch_parts_and_report(const Config& config, std::vector<BlockPart>& parts, PartStore& store,
                                       std::span<const std::uint64_t> source_sizes, const SeamPassWork& work,
                                       SeamPartCache* cache) {
  check_seam_pass(config);
  Stopwatch clock;
  const BlockStitchParams blocks = tile_grid_blocks(config);
  const double before = parts_open_boundary(parts, store, false, blocks, work.measure_parts);
  log::debug("stitch by blocks: open boundary before measured at {:.2f} s", clock.seconds());
  // Weighed by their input's size: the tile interiors, stitched first, are the largest parts,
  // and an ETA counting parts alike ran three times too high at the start (the city's).
  std::uint64_t total_work = 0;
  for (std::size_t p = 0; p < parts.size(); ++p) total_work += store.input_bytes(p);
  // Started once the measure above is done, so that its time is not taken for stitching's.
  StageProgress progress({.stage = "final pass: seam parts stitched", .total = parts.size(), .total_work = total_work});
  const PartStitchRun run{.params = stitch_params(config),
                          .blocks = blocks,
                          .source_sizes = {source_sizes.begin(), source_sizes.end()},
                          .frame = std::nullopt,
                          .run_level = work.run_level,
                          .cache = cache,
                          .progress = &progress};
  BlockStitchStats s = stitch_parts(parts, store, run);
  if (cache != nullptr) cache->prune(parts, s.digests);
  log::debug("stitch by blocks: stitched at {:.2f} s", clock.seconds());
  s.stitch.open_boundary_before = before;
  s.stitch.open_boundary_after = parts_open_boundary(parts, store, true, run.blocks, work.measure_parts);
  log::debug("stitch by blocks: open boundary after measured at {:.2f} s", clock.seconds());
  s.stitch.seconds = clock.seconds();
  std::cout << fmt::format(
      "stitching by blocks: {} tile interiors, {} + {} bands and {} corners; largest part {} "
      "triangles with its surroundings{}\n",
      s.parts[0], s.parts[1], s.parts[2], s.parts[3], s.largest_part,
      cache != nullptr ? fmt::format("; {} parts as stitched by the last run", s.reused_parts) : std::string());
  return report_stitching(s.stitch, &s);
}

namespace {

void report(const std::filesystem::path& dir, const MergedMesh& merged, const MosaicStats& s) {
  std::cout << fmt::format("{}: {} triangles kept of {} candidates", dir.string(), merged.mesh.triangle_count(),
                           s.candidates);
  if (s.seen_through > 0) std::cout << fmt::format(" ({} seen through by another pass)", s.seen_through);
  if (s.seam_terms + s.overlap_terms > 0) {
    std::cout << fmt::format("; energy {:.1f} (quality {:.1f}, boundary {:.1f}, seams {:.1f}, overlaps {:.1f})",
                             s.energy, s.quality, s.boundary, s.seam, s.overlap);
  }
  if (s.filled + s.fill_seen_through > 0) {
    std::cout << fmt::format("; {} added by the hole fill ({} left out: another pass saw through them)", s.filled,
                             s.fill_seen_through);
  }
  std::cout << fmt::format("\n  {:.3f} s: energy {:.3f}, solve {:.3f}, fill {:.3f}\n",
                           s.seconds_build + s.seconds_solve + s.seconds_fill, s.seconds_build, s.seconds_solve,
                           s.seconds_fill);
}

}  // namespace

void run_mosaic_step(const Config& config, const LoadedAcquisitions& input, const ChangeResult& change,
                     const PictureOptions& pictures, nlohmann::json seconds) {
  Stopwatch clock;
  const MosaicSelection selection = select(config, input, change);
  MergedMesh merged = merge_selection(input.meshes, change.index, selection.selected);
  seconds["mosaic"] = clock.restart();
  seconds["energy"] = selection.stats.seconds_build;
  seconds["solve"] = selection.stats.seconds_solve;
  seconds["fill"] = selection.stats.seconds_fill;
  // The baseline, like the paper's, is not stitched.
  const nlohmann::json stitched =
      config.mosaic.method == MosaicMethod::energy ? stitch_and_report(config, merged) : nlohmann::json::object();
  seconds["stitch"] = clock.restart();
  const std::filesystem::path dir = config.project.output / "mosaic";
  write_mosaic_outputs(config, input, merged, selection.stats,
                       {.dir = dir,
                        .pixel_size = pictures.pixel_size,
                        .pictures = pictures.pictures,
                        .seconds = std::move(seconds),
                        .stitch = stitched});
  report(dir, merged, selection.stats);
  write_tileset_outputs(config, merged);
}

ChangeResult read_detect_result(const std::filesystem::path& dir, const Config& config,
                                const LoadedAcquisitions& input) {
  const nlohmann::json summary = read_json(dir / "summary.json", "run citymesh detect first");
  ChangeResult r;
  r.index.offsets.assign(1, 0);
  for (const Mesh& m : input.meshes) r.index.offsets.push_back(r.index.offsets.back() + m.triangle_count());
  try {
    const auto& acquisitions = summary.at("acquisitions");
    if (acquisitions.size() != input.meshes.size()) {
      throw InputError(fmt::format("{}: {} acquisitions, the config has {} (run citymesh detect again)",
                                   (dir / "summary.json").string(), acquisitions.size(), input.meshes.size()));
    }
    for (std::size_t k = 0; k < input.meshes.size(); ++k) {
      if (input.acquisitions[k].withdrawn) continue;  // an empty mesh: no labels written
      const auto& entry = acquisitions.at(config.acquisitions[k].listed);
      if (entry.at("input").get<std::string>() != input.acquisitions[k].path.string()) {
        throw InputError(fmt::format("{}: acquisition {} is {}, the config lists {} there (run citymesh detect again)",
                                     (dir / "summary.json").string(), config.acquisitions[k].listed,
                                     entry.at("input").get<std::string>(), input.acquisitions[k].path.string()));
      }
      const std::filesystem::path ply = dir / entry.at("ply").get<std::string>();
      const FaceTable t = read_face_table(ply, {kKeptProperty});
      if (t.triangles.size() != input.meshes[k].triangle_count()) {
        throw InputError(fmt::format("{}: {} triangles, {} has {} (run citymesh detect again)", ply.string(),
                                     t.triangles.size(), input.acquisitions[k].path.string(),
                                     input.meshes[k].triangle_count()));
      }
      for (const double kept : t.extras[0]) r.kept.push_back(kept != 0 ? 1 : 0);
    }
    const std::filesystem::path pairs_file = dir / summary.at("pairs").get<std::string>();
    const std::vector<std::uint32_t> flat = read_u32_records(pairs_file, kPairsMagic, "consistent pairs");
    const std::size_t n = r.index.size();
    std::vector<TrianglePair> consistent, layers;
    for (std::size_t k = 0; k + 1 < flat.size(); k += 2) {
      if (flat[k] >= n || flat[k + 1] >= n || !(flat[k] < flat[k + 1])) {
        throw InputError(fmt::format("{}: pair {} ({}, {}) is not a pair of the {} triangles", pairs_file.string(),
                                     k / 2, flat[k], flat[k + 1], n));
      }
      const bool one_pass = r.index.acquisition_of(flat[k]) == r.index.acquisition_of(flat[k + 1]);
      (one_pass ? layers : consistent).emplace_back(flat[k], flat[k + 1]);
    }
    r.consistent_pairs = std::move(consistent);
    r.layer_pairs = std::move(layers);
  } catch (const nlohmann::json::exception& e) {
    throw InputError(fmt::format("{}: {}", (dir / "summary.json").string(), e.what()));
  }
  return r;
}

}  // namespace citymesh::app
