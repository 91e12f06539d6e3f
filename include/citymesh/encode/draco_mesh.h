// SPDX-License-Identifier: MIT
// Draco compression of triangle meshes (Draco behind this header), for glTF
// KHR_draco_mesh_compression tile content.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "citymesh/core/mesh.h"

namespace citymesh {

/// A quantization lattice shared by several meshes: positions snap to
/// origin + k * range / (2^bits - 1), so equal input positions in different tiles decode to
/// bit-identical values.
struct DracoLattice {
  std::array<float, 3> origin{0, 0, 0};
  float range = 1.0f;  ///< metres, > 0: the edge of the cube the lattice covers
};

struct DracoEncodeParams {
  int position_bits = 14;  ///< 1..30
  int speed = 5;           ///< 0 (best compression) .. 10 (fastest)
  /// When set, every mesh uses this lattice; otherwise Draco fits one to the mesh.
  std::optional<DracoLattice> lattice;
};

struct DecodedMesh {
  std::vector<Vec3f> positions;
  std::vector<Triangle> triangles;
};

/// Compresses positions and triangles. Draco may reorder vertices and faces. Throws
/// ProcessingError when the parameters are out of range or encoding fails.
std::vector<std::uint8_t> draco_encode(std::span<const Vec3f> positions, std::span<const Triangle> triangles,
                                       const DracoEncodeParams& params = {});

/// Decodes a buffer made by draco_encode. Throws InputError on corrupt data.
DecodedMesh draco_decode(std::span<const std::uint8_t> data);

}  // namespace citymesh
