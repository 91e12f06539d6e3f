// SPDX-License-Identifier: MIT
#include "detect_output.h"

#include <fmt/format.h>

#include <array>
#include <nlohmann/json.hpp>

#include "citymesh/core/atomic_file.h"
#include "citymesh/core/error.h"
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
                        const LabelView& labels) {
  const std::size_t n = mesh.triangle_count();
  std::vector<std::uint8_t> state(n);
  std::vector<double> first(n), last(n);
  for (std::size_t t = 0; t < n; ++t) {
    state[t] = static_cast<std::uint8_t>(labels.state[t]);
    first[t] = unix_seconds(labels.first_seen[t]);
    last[t] = unix_seconds(labels.last_seen[t]);
  }
  write_mesh_ply(path, mesh,
                 {{kSourceFaceProperty, source_face},
                  {kStateProperty, std::span<const std::uint8_t>(state)},
                  {"first_seen", std::span<const double>(first)},
                  {"last_seen", std::span<const double>(last)},
                  {"sustainable", labels.sustainable},
                  {kKeptProperty, labels.kept},
                  {"refutes", labels.refutes}});
}

void write_picture(const std::filesystem::path& path, const Mesh& mesh, const LabelView& labels, double pixel_size) {
  RenderLayer layer{&mesh, {}};
  layer.face_colors.resize(mesh.triangle_count());
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
    layer.face_colors[t] = detect_color(labels.state[t], labels.kept[t] != 0, labels.refutes[t] != 0);
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

LabelView InMemoryDetectOutput::labels(std::size_t k) {
  return label_view(result_, result_.index.offsets[k], result_.index.offsets[k + 1]);
}

std::uint64_t InMemoryDetectOutput::write_pairs(const std::filesystem::path& path) {
  std::vector<std::uint32_t> flat;
  flat.reserve(2 * result_.consistent_pairs.size());
  for (const auto& [a, b] : result_.consistent_pairs) flat.insert(flat.end(), {a, b});
  write_u32_records(path, kPairsMagic, flat);
  return result_.consistent_pairs.size();
}

void write_detect_outputs(const Config& config, const LoadedAcquisitions& described, DetectOutputSource& source,
                          const DetectOutputParams& params) {
  Stopwatch clock;
  std::filesystem::create_directories(params.dir);
  nlohmann::json summary;
  summary["config"] = config.file.string();
  summary["policy"] = unconfirmed_policy_name(config.change.unconfirmed);
  summary["empty_space"] = empty_space_reach_name(config.change.empty_space);
  summary["sustainability"] = format_duration(config.change.sustainability);
  StateCounts totals;
  std::uint64_t triangles = 0;
  for (std::size_t k = 0; k < described.acquisitions.size(); ++k) {
    const std::string stem = file_stem(config, k);
    const Mesh& mesh = source.mesh(k);
    const LabelView labels = source.labels(k);
    if (labels.size() != mesh.triangle_count()) {
      throw InputError(fmt::format("{}: {} triangles now, {} labelled (run with --force)",
                                   described.acquisitions[k].path.string(), mesh.triangle_count(), labels.size()));
    }
    write_labelled_ply(params.dir / (stem + ".ply"), mesh, source_faces(mesh), labels);
    if (params.pictures) write_picture(params.dir / (stem + ".png"), mesh, labels, params.pixel_size);
    nlohmann::json entry = acquisition_json(config, described, k);
    entry["ply"] = stem + ".ply";
    entry["png"] = params.pictures ? stem + ".png" : "";
    entry["triangles"] = mesh.triangle_count();
    const StateCounts counts = count_states(labels);
    entry["counts"] = counts_json(counts);
    totals += counts;
    triangles += mesh.triangle_count();
    summary["acquisitions"].push_back(std::move(entry));
  }
  const std::uint64_t pairs = source.write_pairs(params.dir / kPairsFile);
  summary["pairs"] = kPairsFile;
  const ChangeStats s = source.stats();
  summary["totals"] = counts_json(totals);
  summary["totals"]["triangles"] = triangles;
  summary["consistent_pairs"] = pairs;
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
