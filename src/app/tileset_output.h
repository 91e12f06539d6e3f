// SPDX-License-Identifier: MIT
// What `citymesh run` and `citymesh mosaic` write for viewers and analysis: the 3D Tiles
// tileset (<output>/tiles) and, when [output] ply asks, one provenance PLY per tile
// (<output>/ply/<i>_<j>.ply, DESIGN §3).
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>

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
/// The same from the output's tiles in files (a tiled run's seam pass block by block), the
/// cells of the 3D Tiles tree built by `cells` (default: here; an MPI job's ranks share them).
nlohmann::json write_tileset_outputs(const Config& config, const OutputLeaves& leaves, const ExportCells& cells = {});

/// Cell `cell` of the 3D Tiles export of `leaves` in `frame`, its tiles written: a rank's share
/// of the export write_tileset_outputs() runs on the root.
ExportedCell export_leaves_cell(const Config& config, const OutputLeaves& leaves, const TilesetFrame& frame,
                                std::size_t cell);

}  // namespace citymesh::app
