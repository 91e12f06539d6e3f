// SPDX-License-Identifier: MIT
// What `citymesh run` writes for the mosaic: the merged mesh with provenance (DESIGN §3), a
// top-down picture coloured by source acquisition, and a summary JSON. `citymesh eval` reads
// them back.
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>

#include "acquisitions.h"
#include "citymesh/mosaic/merged_mesh.h"
#include "citymesh/mosaic/mosaic.h"
#include "seam_parts.h"

namespace citymesh::app {

/// Face properties of the mosaic PLY (int; -1 for triangles that stitching created).
inline constexpr const char* kSourceAcqProperty = "source_acq";
inline constexpr const char* kMosaicFile = "mosaic.ply";

struct MosaicOutputParams {
  std::filesystem::path dir;  ///< <output>/mosaic
  double pixel_size = 0.05;
  bool pictures = true;
  nlohmann::json seconds;  ///< time per step, for the summary
  nlohmann::json stitch;   ///< stitching figures, for the summary
  /// The selection was solved tile by tile (citymesh run): the energy and the numbers of
  /// terms belong to each tile's problem (owned and halo triangles) and do not add up, so the
  /// summary writes null for them rather than zeros. The counts of triangles (seen through,
  /// filled, left out by the fill) are the owned triangles' and are written.
  bool solved_per_tile = false;
};

/// Writes <dir>/mosaic.ply, mosaic.png and summary.json (last), each atomically. `input` needs
/// only its acquisitions and dates; each face's source_face comes from the merged mesh's
/// triangle ids (merging, snapping and stitching keep them).
void write_mosaic_outputs(const Config& config, const LoadedAcquisitions& input, const MergedMesh& merged,
                          const MosaicStats& stats, const MosaicOutputParams& params);

/// The same from the output's tiles in files (a tiled run's seam pass block by block): the
/// PLY's vertices are numbered tile by tile (write_leaves_ply), the picture drawn a tile at
/// a time.
void write_mosaic_outputs(const Config& config, const LoadedAcquisitions& input, const OutputLeaves& leaves,
                          const MosaicStats& stats, const MosaicOutputParams& params);

/// Removes `path` (a file or a folder of citymesh's outputs) when an earlier run wrote it and
/// this one writes nothing there (`why`: the key turned off, or no triangle left), so that no
/// other run's output lies beside this one's. Best effort: several MPI ranks may remove it at
/// once.
void remove_earlier_output(const std::filesystem::path& path, const char* why);

/// Per triangle of the merged mesh: its face index in its source acquisition's file
/// (kNoSource for stitch triangles).
std::vector<std::int32_t> source_faces(const MergedMesh& merged);

/// Colour of a source acquisition in the pictures (stitch triangles: magenta).
Rgb8 source_color(std::int32_t acquisition);

}  // namespace citymesh::app
