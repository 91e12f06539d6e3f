// SPDX-License-Identifier: MIT
#include "detect_output.h"

#include <fmt/format.h>

#include <algorithm>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <string>

#include "citymesh/core/atomic_file.h"
#include "citymesh/core/error.h"
#include "citymesh/core/interrupt.h"
#include "citymesh/core/log.h"
#include "citymesh/core/parallel.h"
#include "citymesh/core/process_memory.h"
#include "citymesh/core/read_file.h"
#include "citymesh/core/record_file.h"
#include "citymesh/core/stopwatch.h"
#include "citymesh/render/render.h"

namespace citymesh::app {

Rgb8 detect_color(TriangleState state, bool kept, bool refutes) {
  if (state == TriangleState::conflicting) return {220, 30, 30};  // red: a surface that disappeared
  if (refutes) return {255, 150, 0};                              // orange: newer surface proving it
  if (state == TriangleState::single) return kept ? Rgb8{230, 0, 230} : Rgb8{110, 40, 160};  // magenta / purple
  return kept ? Rgb8{175, 175, 175} : Rgb8{110, 110, 110};  // grey: consistent (darker: unconfirmed)
}

namespace {

/// Acquisition k's files, named by its place in the config file.
std::string file_stem(const Config& config, std::size_t k) {
  return fmt::format("{}_{}", config.acquisitions[k].listed, config.acquisitions[k].name);
}

nlohmann::json counts_json(const StateCounts& c) {
  return {{"consistent", c.state[0]}, {"conflicting", c.state[1]},    {"single", c.state[2]},
          {"kept", c.kept},           {"sustainable", c.sustainable}, {"refutes", c.refutes}};
}

}  // namespace

LabelledOutputParams InMemoryDetectOutput::layout(std::size_t k) {
  const Mesh& mesh = input_.meshes[k];
  LabelledOutputParams p;
  p.has = vertex_attributes(mesh);
  p.vertices = mesh.vertex_count();
  p.triangles = mesh.triangle_count();
  return p;
}

void InMemoryDetectOutput::feed(std::size_t k, LabelledAcquisitionWriter& out) {
  const Mesh& mesh = input_.meshes[k];
  out.add_vertices(mesh, 0, mesh.vertex_count());
  out.add_triangles(mesh.triangles, source_faces(mesh),
                    label_view(result_, result_.index.offsets[k], result_.index.offsets[k + 1]));
}

std::uint64_t InMemoryDetectOutput::write_pairs(const std::filesystem::path& path) {
  // Consistent pairs and pairs of layers of one pass, in one sorted list (a reader tells them
  // apart by their acquisitions), as a tiled run writes them.
  std::vector<TrianglePair> pairs;
  pairs.reserve(result_.consistent_pairs.size() + result_.layer_pairs.size());
  std::merge(result_.consistent_pairs.begin(), result_.consistent_pairs.end(), result_.layer_pairs.begin(),
             result_.layer_pairs.end(), std::back_inserter(pairs));
  std::vector<std::uint32_t> flat;
  flat.reserve(2 * pairs.size());
  for (const auto& [a, b] : pairs) flat.insert(flat.end(), {a, b});
  write_u32_records(path, kPairsMagic, flat);
  return pairs.size();
}

namespace {

/// One acquisition's labelled PLY and picture, and its entry in the summary.
struct AcquisitionOutputs {
  nlohmann::json entry;
  StateCounts counts;
};

AcquisitionOutputs write_acquisition_outputs(const Config& config, const LoadedAcquisitions& described,
                                             DetectOutputSource& source, const DetectOutputParams& params,
                                             std::size_t k) {
  if (described.acquisitions[k].withdrawn) {  // no labels: no file (an earlier run's is removed)
    AcquisitionOutputs none{acquisition_json(config, described, k), {}};
    none.entry["withdrawn"] = true;
    none.entry["ply"] = "";
    none.entry["png"] = "";
    none.entry["triangles"] = 0;
    none.entry["counts"] = counts_json(none.counts);
    return none;
  }
  const std::string stem = file_stem(config, k);
  LabelledOutputParams files = source.layout(k);
  files.ply = params.dir / (stem + ".ply");
  if (params.pictures) files.png = params.dir / (stem + ".png");
  files.pixel_size = params.pixel_size;
  LabelledAcquisitionWriter out(files);
  source.feed(k, out);
  AcquisitionOutputs done{acquisition_json(config, described, k), out.finish()};
  done.entry["ply"] = stem + ".ply";
  done.entry["png"] = params.pictures ? stem + ".png" : "";
  done.entry["triangles"] = files.triangles;
  done.entry["counts"] = counts_json(done.counts);
  return done;
}

/// The labelled PLYs and pictures a summary lists (plain names only: nothing outside its
/// folder).
std::set<std::string> listed_outputs(const nlohmann::json& summary) {
  std::set<std::string> names;
  if (!summary.is_object() || !summary.contains("acquisitions") || !summary["acquisitions"].is_array()) return names;
  for (const nlohmann::json& entry : summary["acquisitions"]) {
    for (const char* key : {"ply", "png"}) {
      if (!entry.is_object() || !entry.contains(key) || !entry[key].is_string()) continue;
      const std::filesystem::path name = entry[key].get<std::string>();
      if (!name.empty() && name == name.filename() && name != "." && name != "..") names.insert(name.string());
    }
  }
  return names;
}

/// What the summary.json already in `dir` lists; none when there is no readable one.
std::set<std::string> listed_outputs(const std::filesystem::path& dir) {
  const std::optional<std::string> text = read_file_bytes(dir / "summary.json");
  return text ? listed_outputs(nlohmann::json::parse(*text, nullptr, false)) : std::set<std::string>{};
}

/// Removes the files of `before` that the run did not write again: a withdrawn or renamed
/// pass's labelled PLY would otherwise stay beside the others as if it were current.
void remove_unlisted(const std::filesystem::path& dir, const std::set<std::string>& before,
                     const std::set<std::string>& now) {
  for (const std::string& name : before) {
    if (now.contains(name)) continue;
    std::error_code ec;
    if (std::filesystem::remove(dir / name, ec))
      log::info("{}: removed (no longer an output of this config)", (dir / name).string());
  }
}

}  // namespace

void remove_detect_outputs(const std::filesystem::path& dir) {
  const std::set<std::string> listed = listed_outputs(dir);
  std::error_code ec;
  if (listed.empty() && !std::filesystem::exists(dir / kPairsFile, ec)) return;
  remove_unlisted(dir, listed, {});  // this run lists nothing
  std::filesystem::remove(dir / kPairsFile, ec);
  std::filesystem::remove(dir / "summary.json", ec);  // last: what it lists is gone
  log::info("{}: an earlier run's labelled outputs removed (this run writes none: [output] labels = false)",
            dir.string());
}

std::uint64_t labelled_output_bytes(std::uint64_t vertices, std::uint64_t bytes_per_vertex, bool pictures) {
  const std::uint64_t side = ViewParams{}.max_side;
  constexpr std::uint64_t kPixelBytes = sizeof(Rgb8) + sizeof(float);  // the picture and its depth
  return vertices * bytes_per_vertex + (pictures ? side * side * kPixelBytes : 0);
}

unsigned labelled_output_workers(std::uint64_t largest, std::uint64_t memory) {
  const std::uint64_t fits = memory / std::max<std::uint64_t>(largest, 1);
  return static_cast<unsigned>(std::clamp<std::uint64_t>(fits, 1, available_threads()));
}

unsigned labelled_outputs_at_once(std::span<const std::uint64_t> vertex_counts, std::uint64_t bytes_per_vertex,
                                  bool pictures, std::uint64_t budget) {
  std::uint64_t largest = 0;
  for (const std::uint64_t v : vertex_counts)
    largest = std::max(largest, labelled_output_bytes(v, bytes_per_vertex, pictures));
  return labelled_output_workers(largest, memory_left(budget));
}

void write_detect_outputs(const Config& config, const LoadedAcquisitions& described, DetectOutputSource& source,
                          const DetectOutputParams& params) {
  Stopwatch clock;
  std::filesystem::create_directories(params.dir);
  const std::set<std::string> before = listed_outputs(params.dir);
  nlohmann::json summary;
  summary["config"] = config.file.string();
  summary["policy"] = unconfirmed_policy_name(config.change.unconfirmed);
  summary["empty_space"] = empty_space_reach_name(config.change.empty_space);
  summary["sustainability"] = format_duration(config.change.sustainability);
  // Job 0 writes the pairs, job k + 1 acquisition k's files: each job its own files, so the
  // bytes depend neither on the order nor on how many run at once. The pairs come first, as
  // the longest job.
  const std::size_t n = described.acquisitions.size();
  std::vector<AcquisitionOutputs> written(n);
  std::uint64_t pairs = 0;
  parallel_jobs(n + 1, params.at_once, [&](std::size_t job) {
    throw_if_interrupted("the change step's outputs");
    Stopwatch job_clock;
    if (job == 0) {
      pairs = source.write_pairs(params.dir / kPairsFile);
      log::debug("{}: {} pairs in {:.2f} s", kPairsFile, pairs, job_clock.seconds());
    } else {
      written[job - 1] = write_acquisition_outputs(config, described, source, params, job - 1);
      log::debug("labelled outputs of {} in {:.2f} s", file_stem(config, job - 1), job_clock.seconds());
    }
  });
  StateCounts totals;
  std::uint64_t triangles = 0;
  for (const std::size_t k : config.listed_order()) {
    AcquisitionOutputs& w = written[k];
    totals += w.counts;
    triangles += w.entry["triangles"].get<std::uint64_t>();
    summary["acquisitions"].push_back(std::move(w.entry));
  }
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
  // Before the summary that no longer lists them: a run killed in between removes them next time.
  remove_unlisted(params.dir, before, listed_outputs(summary));
  write_file_atomically(params.dir / "summary.json", summary.dump(1) + "\n");
}

}  // namespace citymesh::app
