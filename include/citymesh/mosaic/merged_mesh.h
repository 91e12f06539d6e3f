// SPDX-License-Identifier: MIT
// The mosaic's output mesh: the selected triangles of every acquisition in one mesh, each
// remembering where it came from (stitching adds triangles of no source).
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "citymesh/change/detect.h"
#include "citymesh/core/mesh.h"

namespace citymesh {

/// Source of stitch triangles.
constexpr std::int32_t kNoSource = -1;

struct MergedMesh {
  Mesh mesh;  ///< positions, sensor positions (and the rest the inputs carry) of used vertices
  std::vector<std::int32_t> source_acq;       ///< per triangle: input acquisition, or kNoSource
  std::vector<std::int32_t> source_triangle;  ///< per triangle: triangle of that acquisition's mesh
};

/// The selected triangles, acquisition by acquisition in index order, with the vertices they
/// use (no vertex is shared between acquisitions).
MergedMesh merge_selection(std::span<const Mesh> meshes, const GlobalTriangles& index,
                           std::span<const std::uint8_t> selected);

/// Hands back the room `m`'s arrays grew beyond their size (stitching appends to them: up to
/// twice what they hold), so that later stages do not carry it.
void shrink_to_fit(MergedMesh& m);

/// Per source acquisition, its triangles in `m` (stitch triangles not counted).
std::vector<std::uint64_t> source_sizes(const MergedMesh& m);

/// Per triangle, the piece it belongs to: the triangles of one source joined through shared
/// vertices, named by the smallest triangle index among them (kNoSource for stitch
/// triangles). A pass meshed turn by turn (a spinning scanner) comes as many pieces of one
/// source that share no vertex; a profiler's pass as one sheet, cut only where other sources
/// took over.
std::vector<std::int32_t> source_pieces(const MergedMesh& m);

}  // namespace citymesh
