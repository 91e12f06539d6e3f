// SPDX-License-Identifier: MIT
// The run configuration: typed params structs whose member initialisers are the defaults,
// filled from one TOML file (plus command-line overrides).
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "citymesh/change/change_params.h"
#include "citymesh/mosaic/mosaic_params.h"
#include "citymesh/core/mesh.h"
#include "citymesh/core/time.h"
#include "citymesh/geo/crs.h"
#include "citymesh/io/ply_reader.h"

namespace citymesh {

struct ProjectParams {
  std::string crs;  ///< required: "EPSG:2154", "EPSG:326xx", "ENU:lat,lon,h"
  std::string vertical_datum;  ///< required: "ellipsoidal" or "orthometric"
  double geoid_undulation = 0.0;  ///< metres; orthometric only (h = H + N)
  std::filesystem::path output = "out";
  std::filesystem::path work = "work";
};

/// Property names of the input PLY files; the defaults are the reader's own.
struct InputParams {
  std::array<std::string, 3> sensor_origin = PlyReadParams{}.sensor_origin_names;
  std::vector<std::string> time = PlyReadParams{}.time_names;
  std::string intensity = PlyReadParams{}.intensity_name;
};

struct AcquisitionEntry {
  std::filesystem::path path;  ///< absolute (resolved against the config file's folder)
  TimePoint time{};
  std::string name;  ///< defaults to the file stem
  /// Withdrawn (a pass found faulty): kept in the list so that no later pass is renumbered,
  /// read as an empty mesh; its file need not exist.
  bool withdrawn = false;
  /// Its table's place among the config file's [[acquisition]] tables (from 0): the index the
  /// outputs name it by (source_acq, the labelled PLYs' names, the summaries).
  std::uint32_t listed = 0;
};

struct TilingParams {
  double tile_size = 50.0;  ///< metres
  double halo = 2.0;        ///< metres
  std::array<double, 2> origin{0.0, 0.0};
};

/// How a tiled run's final pass stitches the output.
enum class SeamPass {
  /// blocks where the tiles are large enough for its bands, else whole
  automatic,
  whole,   ///< the whole output at once, in memory
  /// block by block on the tile grid from files, the parts of each level in parallel: memory
  /// for a few parts, not the output
  blocks,
};

/// "auto", "whole" or "blocks".
std::string_view seam_pass_name(SeamPass p);

struct RunParams {
  unsigned threads = 0;  ///< 0: all cores
  std::uint64_t memory = 2ull << 30;
  SeamPass seam_pass = SeamPass::automatic;
};

struct OutputParams {
  bool tiles_3d = true;
  bool mosaic_ply = true;  ///< <output>/mosaic/mosaic.ply: the whole output in one file
  bool ply = false;
  bool labels = true;  ///< run: the change step's labelled PLYs (<output>/detect)
  double draco_tolerance = 0.001;  ///< metres
};

struct Config {
  std::filesystem::path file;      ///< the config file ("" for defaults)
  std::filesystem::path base_dir;  ///< relative paths resolve against this folder
  ProjectParams project;
  InputParams input;
  /// In processing order: by time, acquisitions of the same time in listing order. Every step
  /// numbers them so (tile store, triangle ids, stitching's ties), which makes the result
  /// independent of the order in which the file lists them; only the outputs' names of them
  /// follow the listing (`listed`).
  std::vector<AcquisitionEntry> acquisitions;
  ChangeParams change;
  MosaicParams mosaic;
  TilingParams tiling;
  RunParams run;
  OutputParams output;

  /// The project CRS with its vertical datum.
  [[nodiscard]] Crs crs() const;
  /// Acquisitions in processing order, indices 0..n-1.
  [[nodiscard]] std::vector<Acquisition> acquisition_list() const;
  /// Per acquisition in processing order, its `listed` index: what the outputs call it.
  [[nodiscard]] std::vector<std::int32_t> listed_indices() const;
  /// The acquisitions (indices in processing order) in the order the file lists them: the
  /// order of the printed config and of the summaries' lists.
  [[nodiscard]] std::vector<std::size_t> listed_order() const;
  [[nodiscard]] PlyReadParams ply_read_params() const;
};

struct ConfigLoadParams {
  /// "section.key=value" overrides applied on top of the file (value in TOML syntax; a bare
  /// word is taken as a string).
  std::vector<std::string> overrides;
  /// Check that every acquisition file exists.
  bool check_files = true;
};

/// Reads and validates a config file. Throws ConfigError "<file>:<line>:<col>: <key>: ..."; an
/// unknown key names the nearest valid one.
Config load_config(const std::filesystem::path& file, const ConfigLoadParams& params = {});
/// Same from text; `source` names the file in errors and gives the base folder.
Config parse_config(std::string_view text, const std::filesystem::path& source,
                    const ConfigLoadParams& params = {});

/// Every key with its default and a one-line meaning, as commented TOML (required keys are
/// shown commented out with an example).
std::string dump_default_config();
/// Which order effective_config_toml writes the [[acquisition]] tables in.
enum class TableOrder {
  listed,      ///< the file's (what a user reads: the outputs' indices)
  processing,  ///< Config::acquisitions' (what the work folder's fingerprints follow)
};

/// The effective configuration as TOML (what a run used).
std::string effective_config_toml(const Config& config, TableOrder order = TableOrder::listed);

}  // namespace citymesh
