// SPDX-License-Identifier: MIT
// The mosaic's outputs written from the output's tiles one at a time (a tiled run whose seam
// pass ran block by block in files): the PLY and the picture.
#pragma once

#include <cstdint>
#include <filesystem>
#include <span>
#include <string_view>
#include <vector>

#include "citymesh/io/ply_writer.h"
#include "seam_parts.h"

namespace citymesh::app {

/// The vertex rows of `piece` in citymesh's input format: those `owned` marks (a byte per
/// vertex, non-zero: written), or every one when `owned` is empty.
MeshVertexRows piece_rows(const KeyedPiece& piece, std::string_view owned = {});

/// The provenance columns of a piece's triangles, as the mosaic's PLYs carry them:
/// source_acq (each source by its place in the config file: `listed`, per acquisition in
/// processing order), and source_face (kNoSource for the triangles stitching made).
struct Provenance {
  std::vector<std::int32_t> acq, face;
  Provenance() = default;  ///< no triangles: the columns' layout
  Provenance(const KeyedPiece& piece, std::span<const std::int32_t> listed);
  [[nodiscard]] std::vector<PlyColumn> columns() const;
};

/// Writes the output held by `leaves` as one PLY in the input format with the provenance
/// columns (source_acq, source_face), as write_mesh_ply writes a merged mesh: each vertex
/// once, numbered by the first tile (in key order) holding it, then by key; the faces tile by
/// tile. Holds a few tiles at a time. `listed`: as for Provenance.
void write_leaves_ply(const std::filesystem::path& path, const OutputLeaves& leaves,
                      std::span<const std::int32_t> listed);

}  // namespace citymesh::app
