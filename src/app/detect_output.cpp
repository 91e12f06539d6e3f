// SPDX-License-Identifier: MIT
#include "detect_output.h"

#include <fmt/format.h>

#include <array>
#include <nlohmann/json.hpp>

#include "citymesh/core/atomic_file.h"
#include "citymesh/core/log.h"
#include "citymesh/core/record_file.h"
#include "citymesh/core/stopwatch.h"
#include "citymesh/io/ply_writer.h"
#include "citymesh/render/render.h"

namespace citymesh::app {

Rgb8 detect_color(TriangleState state, bool kept, bool refutes) {
  if (state == TriangleState::conflicting) return {220, 30, 30};  // red: a surface that disappeared
  if (refutes) return {255, 150, 0};                              // orange: newer surface proving it
  if (state == TriangleState::single) return kept ? Rgb8{230, 0, 230} : Rgb8{110, 40, 160};  // magenta / purple
  return kept ? Rgb8{175, 175, 175} : Rgb8{110, 110, 110};  // grey: consistent (darker: unconfirmed)
}

namespace {

double unix_seconds(TimePoint t) { return static_cast<double>(t.time_since_epoch().count()) / 1000.0; }

std::string file_stem(const Config& config, std::size_t k) {
  return fmt::format("{}_{}", k, config.acquisitions[k].name);
}

void write_labelled_ply(const std::filesystem::path& path, const Mesh& mesh, std::span<const std::int32_t> source_face,
                        const ChangeResult& r, std::size_t begin) {
  const std::size_t n = mesh.triangle_count();
  std::vector<std::uint8_t> state(n);
  std::vector<double> first(n), last(n);
  for (std::size_t t = 0; t < n; ++t) {
    state[t] = static_cast<std::uint8_t>(r.state[begin + t]);
    first[t] = unix_seconds(r.first_seen[begin + t]);
    last[t] = unix_seconds(r.last_seen[begin + t]);
  }
  const auto slice = [&](const std::vector<std::uint8_t>& v) {
    return std::span<const std::uint8_t>(v.data() + begin, n);
  };
  write_mesh_ply(path, mesh,
                 {{kSourceFaceProperty, source_face},
                  {kStateProperty, std::span<const std::uint8_t>(state)},
                  {"first_seen", std::span<const double>(first)},
                  {"last_seen", std::span<const double>(last)},
                  {"sustainable", slice(r.sustainable)},
                  {kKeptProperty, slice(r.kept)},
                  {"refutes", slice(r.refutes)}});
}

void write_picture(const std::filesystem::path& path, const Mesh& mesh, const ChangeResult& r, std::size_t begin,
                   double pixel_size) {
  RenderLayer layer{&mesh, {}};
  layer.face_colors.resize(mesh.triangle_count());
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
    const std::size_t g = begin + t;
    layer.face_colors[t] = detect_color(r.state[g], r.kept[g] != 0, r.refutes[g] != 0);
  }
  ViewParams view;
  view.pixel_size = pixel_size;
  write_png(path, render_orthographic(std::span<const RenderLayer>(&layer, 1), view));
}

nlohmann::json counts_json(const StateCounts& c) {
  return {{"consistent", c.state[0]}, {"conflicting", c.state[1]},    {"single", c.state[2]},
          {"kept", c.kept},           {"sustainable", c.sustainable}, {"refutes", c.refutes}};
}

}  // namespace

void write_detect_outputs(const Config& config, const LoadedAcquisitions& input, const ChangeResult& r,
                          const DetectOutputParams& params) {
  Stopwatch clock;
  std::filesystem::create_directories(params.dir);
  nlohmann::json summary;
  summary["config"] = config.file.string();
  summary["policy"] = unconfirmed_policy_name(config.change.unconfirmed);
  summary["empty_space"] = empty_space_reach_name(config.change.empty_space);
  summary["sustainability"] = format_duration(config.change.sustainability);
  for (std::size_t k = 0; k < input.meshes.size(); ++k) {
    const std::size_t begin = r.index.offsets[k];
    const std::string stem = file_stem(config, k);
    const std::vector<std::int32_t> faces = input.source_faces(k);
    write_labelled_ply(params.dir / (stem + ".ply"), input.meshes[k], faces, r, begin);
    if (params.pictures) write_picture(params.dir / (stem + ".png"), input.meshes[k], r, begin, params.pixel_size);
    nlohmann::json entry = acquisition_json(config, input, k);
    entry["ply"] = stem + ".ply";
    entry["png"] = params.pictures ? stem + ".png" : "";
    entry["triangles"] = input.meshes[k].triangle_count();
    entry["counts"] = counts_json(count_states(r, begin, r.index.offsets[k + 1]));
    summary["acquisitions"].push_back(std::move(entry));
  }
  std::vector<std::uint32_t> flat;
  flat.reserve(2 * r.consistent_pairs.size());
  for (const auto& [a, b] : r.consistent_pairs) flat.insert(flat.end(), {a, b});
  write_u32_records(params.dir / kPairsFile, kPairsMagic, flat);
  summary["pairs"] = kPairsFile;
  const ChangeStats& s = r.stats;
  summary["totals"] = counts_json(count_states(r, 0, r.index.size()));
  summary["totals"]["triangles"] = s.triangles;
  summary["consistent_pairs"] = s.consistent_pairs;
  summary["prefilter"] = {{"enabled", config.change.prefilter}, {"voxel_size", config.change.voxel_size},
                          {"marked_voxels", s.marked_voxels},   {"candidates", s.conflict_candidates},
                          {"skipped", s.prefilter_skipped},     {"hit_rate", s.prefilter_hit_rate()},
                          {"exact_tests", s.exact_tests}};
  summary["seconds"] = {{"read", params.read_seconds},          {"prepare", s.seconds_prepare},
                        {"consistency", s.seconds_consistency}, {"grids", s.seconds_grids},
                        {"conflicts", s.seconds_conflicts},     {"time_series", s.seconds_time_series},
                        {"detect_total", s.seconds_total()},    {"write", clock.seconds()}};
  write_file_atomically(params.dir / "summary.json", summary.dump(1) + "\n");
}

}  // namespace citymesh::app
