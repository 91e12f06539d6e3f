// SPDX-License-Identifier: MIT
// What `citymesh run` and `citymesh mosaic` write for viewers and analysis: the 3D Tiles
// tileset (<output>/tiles) and, when [output] ply asks, one provenance PLY per tile
// (<output>/ply/<i>_<j>.ply, DESIGN §3).
#pragma once

#include <filesystem>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <span>

#include "citymesh/config/config.h"
#include "citymesh/mosaic/merged_mesh.h"
#include "citymesh/tiles3d/export.h"
#include "seam_parts.h"

namespace citymesh::app {

/// The tileset a user names on the command line: <given>/tiles/tileset.json (a run's output
/// folder), <given>/tileset.json, or the file itself. Throws InputError when there is none.
std::filesystem::path find_tileset(const std::filesystem::path& given);

/// Writes what [output] asks for; returns figures for the run report ({} when nothing).
nlohmann::json write_tileset_outputs(const Config& config, const MergedMesh& merged);
/// How the per-tile PLYs are written: given each leaf's file and `here(l)` (leaf l's written
/// in this process). Empty: here, on the pool's threads.
using LeafPlyWork =
    std::function<void(std::span<const std::filesystem::path> files, const std::function<void(std::size_t)>& here)>;
/// The same from the output's tiles in files (a tiled run's seam pass block by block), the
/// 3D Tiles export's leaves mapped and cells built as `work` says, and the per-tile PLYs
/// written as `plys` says (default: here; an MPI job's ranks share them).
nlohmann::json write_tileset_outputs(const Config& config, const OutputLeaves& leaves, const ExportWork& work = {},
                                     const LeafPlyWork& plys = {});
/// Leaf `l`'s provenance PLY (as [output] ply writes it) in `file`: safe from several threads
/// (or processes) for different leaves. `listed`: Config::listed_indices().
void write_leaf_ply(const OutputLeaves& leaves, std::size_t l, const std::filesystem::path& file,
                    std::span<const std::int32_t> listed);

/// The 3D Tiles export's settings from the config.
TilesetExportParams tileset_export_params(const Config& config);

/// `leaves` as the 3D Tiles export reads them (each leaf's positions, once mapped, kept beside
/// it): what a rank sharing the root's export (export_leaf_box, export_cell) reads.
std::unique_ptr<TilesetLeaves> export_view(const OutputLeaves& leaves);

}  // namespace citymesh::app
