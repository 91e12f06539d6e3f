// SPDX-License-Identifier: MIT
// glTF 2.0 binary (glb) tile content: one TRIANGLES primitive in a local z-up frame (the root
// node turns it into glTF's y-up), Draco-compressed (KHR_draco_mesh_compression) or plain,
// with the source acquisition of each vertex as an EXT_mesh_features feature id whose
// EXT_structural_metadata property table names and dates the acquisitions.
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "citymesh/encode/draco_mesh.h"

namespace citymesh {

/// Feature id of vertices that belong to no acquisition (stitch triangles).
inline constexpr std::uint16_t kNullFeatureId = 65535;
/// glTF attribute names of the per-vertex acquisition id and intensity.
inline constexpr const char* kFeatureIdAttribute = "_FEATURE_ID_0";
inline constexpr const char* kIntensityAttribute = "_INTENSITY";

/// One row of the acquisition property table: feature id k names acquisition k.
struct GlbAcquisition {
  std::string name;
  std::string date;  ///< ISO 8601, UTC
};

/// A glb's Draco-compressed primitive once encoded: its JSON, its accessors (counts and
/// bounds of the decoded mesh) and the Draco bytes, its only buffer view. What a tile whose
/// mesh did not change needs to be written again without encoding (or decoding) it.
struct GlbPrimitive {
  nlohmann::json primitive, accessors;
  std::vector<std::uint8_t> draco;
};

/// Encoded primitives kept by a digest of the mesh and the Draco parameters
/// (glb_primitive_digest). Called from several threads at once.
class GlbPrimitiveCache {
 public:
  virtual ~GlbPrimitiveCache() = default;
  [[nodiscard]] virtual std::optional<GlbPrimitive> find(std::uint64_t digest) const = 0;
  virtual void keep(std::uint64_t digest, const GlbPrimitive& primitive) = 0;
};

struct GlbParams {
  bool draco = true;  ///< false: plain accessors (larger; for comparison and debugging)
  DracoEncodeParams draco_params;
  std::vector<GlbAcquisition> acquisitions;
  /// With Draco: where encoded primitives are looked up first and kept after (null: none).
  GlbPrimitiveCache* primitives = nullptr;
};

/// The digest GlbPrimitiveCache finds a mesh's primitive by: every array of `mesh` and every
/// Draco parameter.
std::uint64_t glb_primitive_digest(const DracoMeshView& mesh, const DracoEncodeParams& params);

/// The glb bytes of one mesh. The mesh's positions are already in the tile's local frame.
/// Throws ProcessingError when the mesh is inconsistent (attribute sizes, indices).
std::vector<std::uint8_t> write_glb(const DracoMeshView& mesh, const GlbParams& params);

/// A parsed glb: its JSON chunk and binary chunk.
struct GlbFile {
  nlohmann::json json;
  std::vector<std::uint8_t> bin;
};

/// Parses glb bytes; throws InputError naming `name` and what is wrong (magic, version,
/// lengths, chunk types, JSON syntax).
GlbFile parse_glb(std::span<const std::uint8_t> bytes, const std::string& name);

/// The mesh of the first primitive of a glb written by write_glb (Draco or plain): positions
/// in the local z-up frame, triangles, and the attributes present. Throws InputError naming
/// `name` when the file does not describe such a mesh.
DecodedMesh read_glb_mesh(const GlbFile& glb, const std::string& name);

}  // namespace citymesh
