// SPDX-License-Identifier: MIT
#include "tiled_run.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <iostream>
#include <nlohmann/json.hpp>
#include <optional>
#include <string_view>

#include "assembly_ranks.h"
#include "citymesh/core/atomic_file.h"
#include "citymesh/core/checksum.h"
#include "citymesh/core/error.h"
#include "citymesh/core/log.h"
#include "citymesh/core/parallel.h"
#include "citymesh/core/process_memory.h"
#include "citymesh/core/progress.h"
#include "citymesh/core/stopwatch.h"
#include "citymesh/io/ply_reader.h"
#include "detect_output.h"
#include "leaf_outputs.h"
#include "leftovers.h"
#include "mosaic_output.h"
#include "mosaic_step.h"
#include "output_ranks.h"
#include "output_record.h"
#include "run_plan.h"
#include "run_stages.h"
#include "run_state.h"
#include "seam_cache.h"
#include "seam_parts.h"
#include "seam_ranks.h"
#include "tile_assembly.h"
#include "tile_job.h"
#include "tiled_detect_output.h"
#include "tileset_output.h"
#include "work_lock.h"
#include "work_schedule.h"

namespace citymesh::app {

namespace {

LoadedAcquisitions describe_acquisitions(const Config& config) {
  LoadedAcquisitions d;
  d.acquisitions = config.acquisition_list();
  for (const Acquisition& a : d.acquisitions) d.dates.push_back(a.date);
  return d;
}

/// How many acquisitions' labelled outputs are written at once: as many as the budget left
/// holds, by their headers' vertex counts.
unsigned labels_at_once(const Config& config, const LoadedAcquisitions& described, bool pictures) {
  std::vector<std::uint64_t> vertices;
  for (const Acquisition& a : described.acquisitions) {
    vertices.push_back(a.withdrawn ? 0 : PlyReader(a.path, config.ply_read_params()).vertex_count());
  }
  return labelled_outputs_at_once(vertices, TiledDetectOutput::kBytesPerVertex, pictures, config.run.memory);
}

void write_labels(const Config& config, const TileAssembly& assembly, const PictureOptions& pictures) {
  const LoadedAcquisitions described = describe_acquisitions(config);
  TiledDetectOutput source(config, described, assembly);
  write_detect_outputs(config, described, source,
                       {.dir = config.project.output / "detect",
                        .pixel_size = pictures.pixel_size,
                        .pictures = pictures.pictures,
                        .at_once = labels_at_once(config, described, pictures.pictures)});
}

/// A tile's entry in the run report: its counts, and its seconds when it was processed now.
nlohmann::json tile_entry(const TileContents& tile, bool processed, const TileTally& tally) {
  nlohmann::json entry{{"tile", tile.key.name()}, {"owned", tile.owned()}, {"triangles", tile.total()}};
  if (processed) {
    entry["seconds"] = {
        {"read", tally.seconds_read}, {"detect", tally.seconds_detect}, {"mosaic", tally.seconds_mosaic}};
  } else {
    entry["reused"] = true;
  }
  return entry;
}

/// Adds one tile's result to the assembly and its entry to the run report.
void add_tile_result(const Config& config, const TileContents& tile, bool processed, std::optional<TileResult> r,
                     TileAssembly& assembly, std::vector<nlohmann::json>& per_tile) {
  if (!r) {
    // Checked whole before the pass began: gone since, or whole but not decodable (a warning
    // above says why; only a fault of citymesh writes such a file).
    throw ProcessingError(
        fmt::format("{}: the tile result cannot be read any more; remove it and run again to process the tile anew",
                    result_path(config, tile.key).string()));
  }
  per_tile.push_back(tile_entry(
      tile, processed,
      {.seconds_read = r->seconds_read, .seconds_detect = r->seconds_detect, .seconds_mosaic = r->seconds_mosaic}));
  assembly.add(std::move(*r));
}

/// The final pass's output: assembled whole in memory (`[run] seam_pass` whole, or auto on
/// narrow tiles), or filed by block-stitching part and then by grid tile (blocks), so that
/// nothing holds it whole. Every step of the pass asks it, whichever it is.
class FinalOutput {
 public:
  /// `cluster`: the MPI job whose ranks share the seam pass (null or one rank: this process).
  FinalOutput(const Config& config, Cluster* cluster) : config_(config), cluster_(cluster) {
    if (seam_pass_in_blocks(config)) {
      seams_.emplace(seam_parts_folder(config.project.work), tile_grid_blocks(config));
    } else if (config.run.seam_pass == SeamPass::automatic && config.mosaic.method == MosaicMethod::energy) {
      log::info(
          "tiles of {} m are too narrow for the seam pass by blocks (over {:.2f} m): the whole output is "
          "stitched at once, in memory",
          config.tiling.tile_size, 4 * tile_grid_blocks(config).band);
    }
  }

  /// Whether the ranks of an MPI job read and file the tile results together (by blocks).
  [[nodiscard]] bool shares_assembly() const { return seams_ && shared(); }
  /// Every tile's result read and filed by the ranks (shares_assembly()), in tile order; the
  /// parts are then merged by the ranks too (assemble()).
  std::vector<FiledResult> file_tiles_shared(const TileStore& store, std::span<const std::uint64_t> digests) {
    assembly_work_ = share_assembly(config_, *cluster_, *seams_, store);
    return assembly_work_->file_tiles(
        [&](std::size_t k) { return file_tile_result(config_, store, k, digests[k], *seams_); });
  }

  /// Writes a tile's selected triangles under their parts and takes them out of its result
  /// before it goes to the assembly (by blocks; whole, the assembly keeps them). Safe from
  /// several threads for different tiles; add_filed() then adds them, in tile order.
  std::optional<SeamPartFiles::FiledTile> file_tile(TileKey key, TileResult& result) const {
    if (!seams_) return std::nullopt;
    SeamPartFiles::FiledTile filed = seams_->file_tile(key, result.selected);
    result.selected.clear();
    return filed;
  }
  void add_filed(const std::optional<SeamPartFiles::FiledTile>& filed) {
    if (filed) seams_->add_filed(*filed);
  }

  /// After the last tile: the assembled mesh, or the parts. Returns the triangles selected.
  std::uint64_t assemble(TileAssembly& assembly) {
    std::uint64_t selected = 0;
    if (seams_) {
      parts_ = seams_->finish(assembly_work_ ? assembly_work_->merge_parts : SeamPartFiles::PartMerging{});
      if (assembly_work_) remove_assembly_plan(config_);
      for (const std::uint64_t n : seams_->source_sizes()) selected += n;
    } else {
      merged_ = assembly.take_merged();
      selected = merged_.mesh.triangle_count();
    }
    return selected;
  }

  /// The seam pass: stitching runs on the assembled mesh (or its parts), so seams between
  /// tiles are joined like seams inside a tile. Returns the figures for the summary.
  nlohmann::json stitch() {
    if (seams_) {
      const bool shared = this->shared();
      // The stitched parts stay in the work folder: the next run (an acquisition appended)
      // restitches only those whose inputs changed.
      SeamPartCache cache = seam_part_cache(config_);
      nlohmann::json figures =
          stitch_parts_and_report(config_, parts_, *seams_, seams_->source_sizes(),
                                  shared ? share_seam_pass(config_, *cluster_, *seams_) : SeamPassWork{}, &cache);
      if (shared) remove_seam_plan(config_);
      // The outputs read the stitched output one grid tile at a time.
      std::vector<BlockPartKey> keys;
      for (const BlockPart& p : parts_) keys.push_back(p.key);
      leaves_.emplace(
          seams_->dir() / "tiles", TileGrid({config_.tiling.tile_size, config_.tiling.halo, config_.tiling.origin}),
          parts_, *seams_,
          shared ? share_leaf_filing(config_, *cluster_, seams_->dir(), std::move(keys)) : LeafFilingWork{});
      seams_->release_stitched();
      return figures;
    }
    // The baseline, like the paper's, is not stitched.
    return config_.mosaic.method == MosaicMethod::energy ? stitch_and_report(config_, merged_)
                                                         : nlohmann::json::object();
  }

  void write_mosaic(const MosaicStats& stats, const MosaicOutputParams& params) const {
    if (leaves_) {
      write_mosaic_outputs(config_, describe_acquisitions(config_), *leaves_, stats, params);
    } else {
      write_mosaic_outputs(config_, describe_acquisitions(config_), merged_, stats, params);
    }
  }

  /// The 3D Tiles and per-tile PLYs; then the pass's files go.
  nlohmann::json export_tiles() {
    if (!leaves_) return write_tileset_outputs(config_, merged_);
    // The other ranks, done with the seam pass and the filing by grid tile, map leaves and
    // build cells of the tree until the root ends (help_outputs).
    const bool shared = this->shared();
    ExportWork work = shared ? share_export(config_, *cluster_, *leaves_) : ExportWork{};
    work.progress = "final pass: 3D Tiles";
    const nlohmann::json exported = write_tileset_outputs(
        config_, *leaves_, work, shared ? share_leaf_plys(config_, *cluster_, *leaves_) : LeafPlyWork{});
    if (shared) end_shared_outputs(config_, *cluster_);
    leaves_.reset();
    seams_.reset();
    return exported;
  }

  [[nodiscard]] std::uint64_t triangles() const {
    if (!leaves_) return merged_.mesh.triangle_count();
    std::uint64_t n = 0;
    for (const OutputLeaf& leaf : leaves_->leaves()) n += leaf.triangles;
    return n;
  }

 private:
  /// Whether other MPI ranks share the pass.
  [[nodiscard]] bool shared() const { return cluster_ != nullptr && cluster_->size() > 1; }

  const Config& config_;
  Cluster* cluster_;
  std::optional<AssemblyWork> assembly_work_;  ///< while the ranks share the assembly
  MergedMesh merged_;
  std::optional<SeamPartFiles> seams_;
  std::vector<BlockPart> parts_;
  std::optional<OutputLeaves> leaves_;
};

/// Reads every tile's result (checked) into the assembly and the final output, a few at a
/// time in parallel (each filed under the seam pass's parts there too), then added in tile
/// order: a read result is several times the piece the assembly keeps of it, so not all at
/// once, and no more at once than the memory budget holds (a spinning street's two largest
/// results are 0.29 and 0.19 GB files: read together they took its final pass to 2.3 GB).
/// `file_selected` false: only the labels, pairs and figures (the ranks filed the rest).
void read_tile_results(const Config& config, const TileStore& store, std::span<const std::uint64_t> digests,
                       const TileStageReport& tiles, TileAssembly& assembly, FinalOutput& output,
                       std::vector<nlohmann::json>& per_tile, bool file_selected = true) {
  constexpr std::size_t kBatch = 4;
  std::vector<std::optional<TileResult>> batch(kBatch);
  std::vector<std::optional<SeamPartFiles::FiledTile>> filed(kBatch);
  const std::vector<std::uint64_t> read_bytes = result_read_bytes(config, store);
  StageProgress progress({.stage = file_selected ? "final pass: tile results read" : "final pass: tile labels read",
                          .total = store.tiles.size()});
  for (std::size_t first = 0, count = 0; first < store.tiles.size(); first += count) {
    count = batch_within(read_bytes, first, kBatch, memory_left(config.run.memory));
    parallel_for_blocks(count, 1, [&](std::size_t begin, std::size_t end) {
      for (std::size_t i = begin; i < end; ++i) {
        const TileKey key = store.tiles[first + i].key;
        batch[i] = read_tile_result(result_path(config, key), digests[first + i], store,
                                    {.pairs = config.output.labels, .selected = file_selected});
        filed[i] = batch[i] && file_selected ? output.file_tile(key, *batch[i]) : std::nullopt;
      }
    });
    for (std::size_t i = 0; i < count; ++i) {
      output.add_filed(filed[i]);
      add_tile_result(config, store.tiles[first + i], tiles.processed[first + i] != 0, std::move(batch[i]), assembly,
                      per_tile);
    }
    progress.advance(count);
  }
}

/// Under MPI (by blocks): every rank reads and files tile results (share_assembly); the root
/// adds what they report in tile order, and reads the labels itself when it writes labelled
/// outputs.
void gather_filed_results(const Config& config, const TileStore& store, std::span<const std::uint64_t> digests,
                          const TileStageReport& tiles, TileAssembly& assembly, FinalOutput& output,
                          std::vector<nlohmann::json>& per_tile) {
  const std::vector<FiledResult> filed = output.file_tiles_shared(store, digests);
  for (const FiledResult& r : filed) output.add_filed(r.filed);
  if (config.output.labels) {
    read_tile_results(config, store, digests, tiles, assembly, output, per_tile, false);
    return;
  }
  for (std::size_t k = 0; k < filed.size(); ++k) {
    assembly.add_tally(filed[k].tally);
    per_tile.push_back(tile_entry(store.tiles[k], tiles.processed[k] != 0, filed[k].tally));
  }
}

/// The outputs from every tile's result: assembly, labels, the seam pass, mosaic, 3D Tiles and
/// run.json. `seconds` holds the stages timed so far.
void write_run_outputs(const Config& config, const TileStore& store, std::span<const std::uint64_t> digests,
                       const TileStageReport& tiles, const PictureOptions& pictures, nlohmann::json seconds,
                       Cluster* cluster) {
  const int ranks = cluster != nullptr ? cluster->size() : 1;
  Stopwatch total, clock;
  forget_outputs(config.project.work);
  // Each stage hands the memory it freed back to the system: the next one then starts from
  // what is still in use, and the pass peaks at its largest stage rather than at the heap
  // every stage left behind (city: 1.37 -> 0.99 GiB).
  const auto stage_done = [&](const char* stage) {
    release_freed_memory();
    seconds[stage] = clock.restart();
    log::debug("final pass: {} done, {}", stage, memory_note());
  };
  // The pairs and labels wait on disk (a city has 0.7 GB of pairs), in a folder of this
  // process's own.
  TileAssembly assembly(store,
                        config.output.labels ? std::optional(pair_spill_folder(config.project.work)) : std::nullopt);
  FinalOutput output(config, cluster);
  std::vector<nlohmann::json> per_tile;
  if (output.shares_assembly()) {
    gather_filed_results(config, store, digests, tiles, assembly, output, per_tile);
  } else {
    read_tile_results(config, store, digests, tiles, assembly, output, per_tile);
  }
  const std::uint64_t selected = output.assemble(assembly);
  stage_done("assembly");
  if (config.output.labels) {
    write_labels(config, assembly, pictures);
  } else if (cluster == nullptr || cluster->root()) {
    remove_detect_outputs(config.project.output / "detect");
  }
  stage_done("labels");
  const nlohmann::json stitched = output.stitch();
  stage_done("stitch");
  MosaicStats stats;
  stats.candidates = assembly.candidates();
  stats.seen_through = assembly.seen_through();
  stats.filled = assembly.filled();
  // As in `citymesh mosaic`: the solver's selection, before the fill added to it (every
  // filled triangle is one of the selected owned ones).
  stats.selected = selected - std::min(selected, stats.filled);
  stats.fill_seen_through = assembly.fill_left_out();
  output.write_mosaic(stats, {.dir = config.project.output / "mosaic",
                              .pixel_size = pictures.pixel_size,
                              .pictures = pictures.pictures,
                              .seconds = seconds,
                              .stitch = stitched,
                              .solved_per_tile = true});
  const std::uint64_t output_triangles = output.triangles();
  stage_done("outputs");
  const nlohmann::json exported = output.export_tiles();
  stage_done("export");

  double wall = total.seconds();
  for (const auto& [stage, s] : seconds.items()) {
    if (stage == "tiling" || stage == "tiles") wall += s.get<double>();
  }
  const std::size_t reused = store.tiles.size() - tiles.count;
  nlohmann::json report;
  // Which citymesh made the output: all of it, since another build's work is never reused.
  report["citymesh"] = {{"version", CITYMESH_VERSION}, {"build", build_name()}};
  report["tiles"] = store.tiles.size();
  report["reused_tiles"] = reused;
  // Of the reused: kept when a neighbour was redone or a pass delivered late renumbered theirs.
  report["kept_tiles"] = tiles.kept;
  report["input_triangles"] = assembly.owned();
  report["output_triangles"] = output_triangles;
  report["ranks"] = ranks;
  report["threads"] = available_threads();
  report["memory_budget"] = format_byte_size(config.run.memory);
  report["peak_rss_bytes"] = peak_resident_bytes();
  report["seconds"] = seconds;
  report["seconds"]["total"] = wall;
  // Over a resumed run's time, a rate says nothing of the work the reused tiles took: null.
  report["triangles_per_second"] =
      reused == 0 ? nlohmann::json(static_cast<double>(assembly.owned()) / std::max(wall, 1e-9)) : nlohmann::json();
  report["tiling"] = {{"halo_copies", store.stats.halo_copies},
                      {"empty_space_copies", store.stats.empty_space_copies},
                      {"bytes_written", store.stats.bytes_written},
                      {"largest_radius", store.stats.largest_radius}};
  report["export"] = exported;
  report["per_tile"] = per_tile;
  write_file_atomically(config.project.output / "run.json", report.dump(1) + "\n");
  // Over a resumed run's time, the rate says nothing of the work the reused tiles took.
  const std::string rate = reused == 0 ? fmt::format("{:.2f} M triangles/s",
                                                     static_cast<double>(assembly.owned()) / std::max(wall, 1e-9) / 1e6)
                                       : std::string("no rate: tiles reused");
  const std::string kept =
      tiles.kept > 0 ? fmt::format(", {} of them kept: a neighbour redone, or their passes renumbered", tiles.kept)
                     : "";
  std::cout << fmt::format(
      "run: {} tiles ({} reused{}), {} input triangles -> {} output triangles in {:.2f} s ({}), {} rank(s), peak "
      "memory {:.0f} MiB (rank 0)\n",
      store.tiles.size(), reused, kept, assembly.owned(), output_triangles, wall, rate, ranks,
      static_cast<double>(peak_resident_bytes()) / (1 << 20));
  record_outputs(config, final_pass_digest(config, digests, pictures));
}

/// Whether no tile was processed and the outputs are the last run's, made from what this run's
/// final pass would make them from (outputs.json): it would write the same again. Collective:
/// under MPI each rank looks (they share the folders) and true only when every rank found so.
bool nothing_to_write(const Config& config, std::span<const std::uint64_t> result_digests,
                      const PictureOptions& pictures, bool tiles_processed, Cluster& cluster) {
  const bool here = !tiles_processed && outputs_up_to_date(config, final_pass_digest(config, result_digests, pictures));
  return cluster.same_everywhere(here ? 1 : 0) && here;
}

/// What `command` says when it finds nothing to write.
std::string nothing_written(std::string_view command, std::size_t tiles, const Config& config) {
  return fmt::format(
      "{}: {} tiles (all reused); the outputs in {} are the last run's and nothing they are made from has changed: "
      "nothing written. Remove any of them to have them written again\n",
      command, tiles, config.project.output.string());
}

/// Every tile index of the store.
std::vector<std::size_t> all_tiles(const TileStore& store) {
  std::vector<std::size_t> tiles(store.tiles.size());
  for (std::size_t k = 0; k < tiles.size(); ++k) tiles[k] = k;
  return tiles;
}

/// A subset's share: its tiles and, where they wait for tiles of other subsets that are not
/// finished yet, those too (the same bytes whoever makes them). No outputs: `merge` writes them.
void run_subset(const Config& config, const TileStore& store, const TileDigests& digests, const Subset& subset,
                Cluster& cluster) {
  Stopwatch clock;
  const std::vector<std::size_t> own = subset_tiles(store, subset);
  const std::vector<std::size_t> needed = with_dependencies(store, own);
  std::vector<std::uint8_t> theirs(store.tiles.size(), 1);
  for (const std::size_t k : own) theirs[k] = 0;
  const TileStageReport report = process_tiles(config, store, digests, cluster, needed, theirs);
  std::size_t own_processed = 0;
  for (const std::size_t k : own) own_processed += report.processed[k];
  std::cout << fmt::format(
      "subset {}: {} of its {} tiles processed ({} reused); {} tiles of other subsets it waits "
      "for processed here, {} reused; {:.2f} s. When every subset is done: citymesh merge CONFIG\n",
      subset.name(), own_processed, own.size(), own.size() - own_processed, report.count - own_processed,
      needed.size() - own.size() - (report.count - own_processed), clock.seconds());
}

}  // namespace

void run_tiled(const Config& config, const TiledRunOptions& options, Cluster& cluster) {
  Stopwatch clock;
  // Every rank computes the digests its results are filed under: they must agree.
  if (!cluster.same_everywhere(executable_identity())) {
    throw ConfigError(
        "the ranks of this MPI job run different builds of citymesh: every rank must run the same executable, "
        "byte for byte");
  }
  check_seam_pass(config);
  const auto keys = result_keys(config);
  std::optional<WorkFolderLock> lock;
  if (cluster.root()) {
    // The root holds the lock for the whole job (its ranks share the work); subsets share it.
    lock.emplace(config.project.work, !options.subset);
    if (options.plan) {
      check_run_config_unrecorded(config.project.work, keys, options.force);
    } else {
      check_run_config(config.project.work, keys, options.force);
    }
    remove_leftovers_of_ended_runs(config);
  }
  const RunFingerprints fingerprints = run_fingerprints(keys, config.acquisitions.size());
  const TileStore store = prepare_tile_store(config, fingerprints, cluster, options.subset);
  const TileDigests digests = tile_digests(store, fingerprints.settings, fingerprints.identities);
  // Each stage's arrays differ from the last one's: the memory one freed goes back to the
  // system instead of staying resident under the next one's peak.
  release_freed_memory();
  nlohmann::json seconds{{"tiling", clock.restart()}};
  if (options.plan) {
    RunPlan plan = plan_run(config, store, digests);
    plan.outputs_up_to_date =
        nothing_to_write(config, digests.result, options.pictures, plan.to_process + plan.may_be_kept > 0, cluster);
    std::cout << describe_plan(plan, available_threads());
    return;
  }
  if (options.subset) return run_subset(config, store, digests, *options.subset, cluster);
  const TileStageReport tiles = process_tiles(config, store, digests, cluster, all_tiles(store));
  release_freed_memory();
  seconds["tiles"] = clock.restart();
  if (nothing_to_write(config, digests.result, options.pictures, tiles.count > 0, cluster)) {
    if (cluster.root()) std::cout << nothing_written("run", store.tiles.size(), config);
    return;
  }
  // The seam pass and the outputs need every tile: the root writes them, the other ranks
  // help it stitch.
  if (cluster.root()) {
    write_run_outputs(config, store, digests.result, tiles, options.pictures, seconds, &cluster);
  } else if (seam_pass_in_blocks(config)) {
    help_assembly(config, cluster, store, digests.result);
    help_seam_pass(config, cluster);
    help_outputs(config, cluster);
  }
  cluster.barrier();
}

void merge_tiled(const Config& config, const PictureOptions& pictures) {
  check_seam_pass(config);
  const auto keys = result_keys(config);
  const WorkFolderLock lock(config.project.work, true);
  check_run_config(config.project.work, keys, false);
  remove_leftovers_of_ended_runs(config);
  const RunFingerprints fingerprints = run_fingerprints(keys, config.acquisitions.size());
  const std::optional<TileStore> store = finished_tile_store(config, fingerprints);
  if (!store) {
    throw InputError(
        fmt::format("{}: no finished tile store for this config; run the subsets first "
                    "(citymesh run CONFIG --subset i/N)",
                    (config.project.work / "tiles").string()));
  }
  const std::vector<std::uint64_t> digests =
      tile_digests(*store, fingerprints.settings, fingerprints.identities).result;
  std::vector<std::string> missing;
  for (std::size_t k = 0; k < store->tiles.size(); ++k) {
    // Whole (the checksum covers every section): decoded once, when the outputs read them.
    if (!tile_result_is_finished(result_path(config, store->tiles[k].key), digests[k], *store))
      missing.push_back(store->tiles[k].key.name());
  }
  if (!missing.empty()) {
    const std::size_t shown = std::min<std::size_t>(missing.size(), 8);
    throw InputError(
        fmt::format("{}: {} of {} tiles have no finished result ({}{}); run the subsets that own them "
                    "again, or citymesh run CONFIG to finish them here (results made by another build of "
                    "citymesh do not count)",
                    (config.project.work / "results").string(), missing.size(), store->tiles.size(),
                    fmt::join(missing.begin(), missing.begin() + static_cast<std::ptrdiff_t>(shown), ", "),
                    shown < missing.size() ? ", ..." : ""));
  }
  if (nothing_to_write(config, digests, pictures, false, *single_process())) {
    std::cout << nothing_written("merge", store->tiles.size(), config);
    return;
  }
  const TileStageReport none{std::vector<std::uint8_t>(store->tiles.size(), 0), 0, 0};
  write_run_outputs(config, *store, digests, none, pictures, nlohmann::json::object(), nullptr);
}

}  // namespace citymesh::app
