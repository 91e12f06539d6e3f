// SPDX-License-Identifier: MIT
#include "assembly_ranks.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <nlohmann/json.hpp>
#include <optional>
#include <type_traits>

#include "citymesh/core/atomic_file.h"
#include "citymesh/core/error.h"
#include "citymesh/core/interrupt.h"
#include "citymesh/core/log.h"
#include "citymesh/core/parallel.h"
#include "citymesh/core/process_memory.h"
#include "json_bits.h"
#include "mosaic_step.h"
#include "run_stages.h"
#include "shared_steps.h"
#include "work_schedule.h"

namespace citymesh::app {

namespace {

/// What reading a tile's result holds at most, per byte of its file: the file, its decoded
/// sections (the pairs stay as the file holds them), and a million pairs at a time as the
/// assembly files them (a spinning street's largest result, a 291 MB file, took the final
/// pass from 0.05 to 0.69 GB read alone: 2.2 bytes a byte; 5.5 while the pairs were decoded).
constexpr std::uint64_t kResultReadBytesPerFileByte = 3;

/// The plan of the step being shared, written by the root before it shares the step.
std::filesystem::path plan_path(const Config& config) { return config.project.work / "assembly-step.json"; }

/// What another rank needs for one step: the root's folder of parts, and for "merge" every
/// part with its fragments (for "file" the tiles are the store's, which every rank holds).
struct StepPlan {
  std::string step;  ///< "file" or "merge"
  std::filesystem::path dir;
  std::vector<BlockPartKey> parts;
  std::vector<std::vector<std::filesystem::path>> fragments;
};

void write_plan(const Config& config, const StepPlan& plan) {
  nlohmann::json fragments = nlohmann::json::array();
  for (const auto& of_part : plan.fragments) {
    nlohmann::json files = nlohmann::json::array();
    for (const std::filesystem::path& f : of_part) files.push_back(std::filesystem::absolute(f).string());
    fragments.push_back(std::move(files));
  }
  const nlohmann::json j{{"step", plan.step},
                         {"dir", std::filesystem::absolute(plan.dir).string()},
                         {"parts", block_part_keys_json(plan.parts)},
                         {"fragments", fragments}};
  write_file_atomically(plan_path(config), j.dump() + "\n");
}

StepPlan read_plan(const Config& config) {
  return decode_json_file(plan_path(config), "rank 0's plan of the assembly", [](const nlohmann::json& j) {
    StepPlan plan;
    plan.step = j.at("step").get<std::string>();
    plan.dir = j.at("dir").get<std::string>();
    plan.parts = block_part_keys_from(j.at("parts"));
    for (const auto& of_part : j.at("fragments")) {
      plan.fragments.emplace_back();
      for (const auto& f : of_part) plan.fragments.back().emplace_back(f.get<std::string>());
    }
    if (plan.fragments.size() != plan.parts.size()) throw ProcessingError("the plan's fragments are not its parts'");
    return plan;
  });
}

/// Where a tile's filing is reported for the root: beside the parts.
std::filesystem::path filed_file(const std::filesystem::path& dir, TileKey key) {
  return dir / fmt::format("{}.filed.json", key.name());
}

/// A tally's counts and seconds, in the order its JSON lists them.
constexpr std::array kTallyCounts{&TileTally::owned, &TileTally::candidates, &TileTally::seen_through,
                                  &TileTally::filled, &TileTally::fill_left_out};
constexpr std::array kTallySeconds{&TileTally::seconds_read, &TileTally::seconds_detect, &TileTally::seconds_mosaic};

/// The fields `fields` of `object` as a JSON list, doubles as their bits (a sum over ranks
/// must equal one process's).
template <class Object, class Fields>
nlohmann::json fields_json(const Object& object, const Fields& fields) {
  nlohmann::json out = nlohmann::json::array();
  for (const auto field : fields) {
    if constexpr (std::is_same_v<std::remove_cvref_t<decltype(object.*field)>, double>) {
      out.push_back(double_bits(object.*field));
    } else {
      out.push_back(object.*field);
    }
  }
  return out;
}

/// The inverse of fields_json; throws nlohmann's errors when the list is short.
template <class Object, class Fields>
void fields_from(const nlohmann::json& list, const Fields& fields, Object& object) {
  std::size_t i = 0;
  for (const auto field : fields) {
    using Value = std::remove_cvref_t<decltype(object.*field)>;
    if constexpr (std::is_same_v<Value, double>) {
      object.*field = double_from_bits(list.at(i++));
    } else {
      object.*field = list.at(i++).template get<Value>();
    }
  }
}

nlohmann::json tally_json(const TileTally& t) {
  return {{"counts", fields_json(t, kTallyCounts)},
          {"change_counts", fields_json(t.change, kChangeCounts)},
          {"change_seconds", fields_json(t.change, kChangeSeconds)},
          {"seconds", fields_json(t, kTallySeconds)}};
}

TileTally tally_from(const nlohmann::json& j) {
  TileTally t;
  fields_from(j.at("counts"), kTallyCounts, t);
  fields_from(j.at("change_counts"), kChangeCounts, t.change);
  fields_from(j.at("change_seconds"), kChangeSeconds, t.change);
  fields_from(j.at("seconds"), kTallySeconds, t);
  return t;
}

}  // namespace

nlohmann::json filed_result_json(const FiledResult& r) {
  nlohmann::json files = nlohmann::json::array(), boxes = nlohmann::json::array();
  for (const std::filesystem::path& f : r.filed.files) files.push_back(f.string());
  for (const Box3d& b : r.filed.boxes) boxes.push_back(box_bits(b));
  return {{"parts", block_part_keys_json(r.filed.parts)},
          {"files", files},
          {"boxes", boxes},
          {"source_sizes", r.filed.source_sizes},
          {"tally", tally_json(r.tally)}};
}

FiledResult filed_result_from(const nlohmann::json& j) {
  FiledResult r;
  r.filed.parts = block_part_keys_from(j.at("parts"));
  for (const auto& f : j.at("files")) r.filed.files.emplace_back(f.get<std::string>());
  for (const auto& b : j.at("boxes")) r.filed.boxes.push_back(box_from_bits(b));
  if (r.filed.files.size() != r.filed.parts.size() || r.filed.boxes.size() != r.filed.parts.size()) {
    throw ProcessingError("a filed tile's parts, files and boxes differ in number");
  }
  r.filed.source_sizes = j.at("source_sizes").get<std::vector<std::uint64_t>>();
  r.tally = tally_from(j.at("tally"));
  return r;
}

namespace {

/// The assembly's steps on every rank: filing the tile results, as many at once as the budget
/// holds (`bytes`: each result's read size), then merging the parts' fragments.
SharedStep filing_step(const Config& config, std::span<const std::uint64_t> bytes) {
  return {
      .workers = results_at_once(config, bytes), .what = "the assembly", .progress = "final pass: tile results read"};
}
SharedStep merging_step() {
  return {.workers = available_threads(), .what = "the assembly", .progress = "final pass: seam parts assembled"};
}

}  // namespace

std::vector<std::uint64_t> result_read_bytes(const Config& config, const TileStore& store) {
  std::vector<std::uint64_t> bytes;
  for (const TileContents& tile : store.tiles) {
    std::error_code ec;
    const std::uintmax_t size = std::filesystem::file_size(result_path(config, tile.key), ec);
    bytes.push_back(ec ? 0 : std::uint64_t{size} * kResultReadBytesPerFileByte);
  }
  return bytes;
}

unsigned results_at_once(const Config& config, std::span<const std::uint64_t> bytes) {
  const std::uint64_t largest = bytes.empty() ? 0 : *std::max_element(bytes.begin(), bytes.end());
  const std::uint64_t fit = largest == 0 ? available_threads() : memory_left(config.run.memory) / largest;
  return static_cast<unsigned>(std::clamp<std::uint64_t>(fit, 1, available_threads()));
}

FiledResult file_tile_result(const Config& config, const TileStore& store, std::size_t k, std::uint64_t digest,
                             const SeamPartFiles& files) {
  const TileKey key = store.tiles.at(k).key;
  const std::filesystem::path path = result_path(config, key);
  const std::optional<TileResult> r = read_tile_result(path, digest, store, {.pairs = false});
  if (!r) {
    // Checked whole before the pass began: gone since, or whole but not decodable (a warning
    // above says why; only a fault of citymesh writes such a file).
    throw ProcessingError(
        fmt::format("{}: the tile result cannot be read any more; remove it and run again to process the tile anew",
                    path.string()));
  }
  return {files.file_tile(key, r->selected), tally_of(*r, store)};
}

AssemblyWork share_assembly(const Config& config, Cluster& cluster, const SeamPartFiles& files,
                            const TileStore& store) {
  AssemblyWork work;
  work.file_tiles = [&config, &cluster, &files, &store](const std::function<FiledResult(std::size_t)>& here) {
    write_plan(config, {.step = "file", .dir = files.dir(), .parts = {}, .fragments = {}});
    std::vector<std::uint64_t> bytes = result_read_bytes(config, store);
    const SharedStep step = filing_step(config, bytes);
    return share_and_gather<FiledResult>(cluster, std::move(bytes), step, "tile results read and filed", here,
                                         [&](std::size_t k) {
                                           return take_json_file(filed_file(files.dir(), store.tiles[k].key),
                                                                 "a tile another rank filed", filed_result_from);
                                         });
  };
  work.merge_parts = [&config, &cluster, &files](std::span<const BlockPartKey> parts,
                                                 std::span<const std::vector<std::filesystem::path>> fragments,
                                                 const std::function<void(std::size_t)>& here) {
    write_plan(config, {.step = "merge",
                        .dir = files.dir(),
                        .parts = {parts.begin(), parts.end()},
                        .fragments = {fragments.begin(), fragments.end()}});
    std::vector<std::uint64_t> costs;  // fragments to read: the most first
    for (const auto& of_part : fragments) costs.push_back(of_part.size());
    share_items(cluster, std::move(costs), merging_step(), here);
  };
  return work;
}

void remove_assembly_plan(const Config& config) {
  std::error_code ec;
  std::filesystem::remove(plan_path(config), ec);
}

void help_assembly(const Config& config, Cluster& cluster, const TileStore& store,
                   std::span<const std::uint64_t> digests) {
  std::atomic<std::size_t> filed = 0, merged = 0;
  for (const std::string_view expected : {"file", "merge"}) {
    // The root writes the plan before it shares the step, and sharing starts with a barrier.
    auto channel = cluster.share(nullptr, {});
    const StepPlan plan = read_plan(config);
    if (plan.step != expected) {
      throw ProcessingError(fmt::format("{}: step '{}' where step '{}' of the assembly was expected",
                                        plan_path(config).string(), plan.step, expected));
    }
    const SeamPartFiles files(plan.dir, tile_grid_blocks(config), SeamPartFiles::Folder::others);
    // Each item's outcome is written before the root hears that it is done (the worker's
    // next request says so).
    if (plan.step == "file") {
      work_on_shared_items(*channel, filing_step(config, result_read_bytes(config, store)), [&](std::size_t k) {
        const FiledResult r = file_tile_result(config, store, k, digests[k], files);
        write_file_atomically(filed_file(plan.dir, store.tiles.at(k).key), filed_result_json(r).dump());
        ++filed;
      });
      continue;
    }
    work_on_shared_items(*channel, merging_step(), [&](std::size_t p) {
      files.merge_fragments(plan.parts.at(p), plan.fragments.at(p));
      ++merged;
    });
  }
  log::info("rank {}: read and filed {} tile results and merged {} seam parts of the assembly", cluster.rank(),
            filed.load(), merged.load());
}

}  // namespace citymesh::app
