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

}  // namespace citymesh
