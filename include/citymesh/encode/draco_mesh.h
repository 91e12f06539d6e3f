// SPDX-License-Identifier: MIT
// Draco compression of triangle meshes (Draco behind this header), for glTF
// KHR_draco_mesh_compression tile content.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <string_view>
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

/// The version of the Draco library citymesh was built with.
std::string_view draco_version();

struct DracoEncodeParams {
  int position_bits = 14;  ///< 1..30
  int speed = 5;           ///< 0 (best compression) .. 10 (fastest)
  /// When set, every mesh uses this lattice; otherwise Draco fits one to the mesh.
  std::optional<DracoLattice> lattice;
};

/// A mesh to compress: positions and triangles, and per-vertex attributes that are either
/// empty or one per vertex. Feature ids and intensities are lossless; colours are 8-bit.
struct DracoMeshView {
  std::span<const Vec3f> positions;
  std::span<const Triangle> triangles;
  std::span<const std::uint16_t> feature_ids;
  std::span<const float> intensities;
  std::span<const Rgb8> colors;
};

/// Draco's unique id of each attribute in a buffer (-1: absent), as glTF's
/// KHR_draco_mesh_compression `attributes` map names them.
struct DracoAttributeIds {
  int position = -1, feature_id = -1, intensity = -1, color = -1;
};

struct DracoEncoded {
  std::vector<std::uint8_t> bytes;
  DracoAttributeIds ids;
};

struct DecodedMesh {
  std::vector<Vec3f> positions;
  std::vector<Triangle> triangles;
  std::vector<std::uint16_t> feature_ids;  ///< empty when the buffer has none
  std::vector<float> intensities;
  std::vector<Rgb8> colors;
};

/// Compresses a mesh. Draco may reorder (and, at non-manifold vertices, split) vertices and
/// reorder faces. Throws ProcessingError when the parameters or attribute sizes are wrong or
/// encoding fails.
DracoEncoded draco_encode(const DracoMeshView& mesh, const DracoEncodeParams& params = {});

/// Positions and triangles only.
inline std::vector<std::uint8_t> draco_encode(std::span<const Vec3f> positions, std::span<const Triangle> triangles,
                                              const DracoEncodeParams& params = {}) {
  return draco_encode(DracoMeshView{positions, triangles, {}, {}, {}}, params).bytes;
}

/// Decodes a Draco buffer. Attributes are looked up by the given unique ids; the position
/// falls back to Draco's POSITION attribute when its id is -1. Throws InputError on corrupt
/// data or a missing attribute.
DecodedMesh draco_decode(std::span<const std::uint8_t> data, const DracoAttributeIds& ids = {});

}  // namespace citymesh
