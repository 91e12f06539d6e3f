// SPDX-License-Identifier: MIT
// stitch_in_blocks: a merged mesh split into keyed parts (a vertex's key is its index in the
// mesh), stitched part by part in memory, and put back together.
#include <algorithm>
#include <map>

#include "citymesh/core/stopwatch.h"
#include "citymesh/mosaic/stitch_blocks.h"
#include "mesh_topology.h"

namespace citymesh {

namespace {

/// The parts, kept in memory.
class MemoryPartStore final : public PartStore {
 public:
  explicit MemoryPartStore(std::vector<KeyedPiece> initial) : stitched_(initial.size()) {
    for (KeyedPiece& p : initial) initial_.push_back(std::make_shared<const KeyedPiece>(std::move(p)));
  }
  [[nodiscard]] std::shared_ptr<const KeyedPiece> load(std::size_t part, bool stitched) const override {
    return stitched ? stitched_[part] : initial_[part];
  }
  void save_stitched(std::size_t part, KeyedPiece stitched) override {
    stitched_[part] = std::make_shared<const KeyedPiece>(std::move(stitched));
  }
  void release_input(std::size_t part) override { initial_[part].reset(); }
  /// The stitched parts, handed over.
  std::vector<std::shared_ptr<const KeyedPiece>> take_stitched() {
    initial_.clear();
    return std::move(stitched_);
  }

 private:
  std::vector<std::shared_ptr<const KeyedPiece>> initial_, stitched_;
};

/// The triangles `ts` of `m` as a keyed piece, positions as doubles in the project CRS.
KeyedPiece piece_of(const MergedMesh& m, std::span<const std::uint32_t> ts) {
  const Mesh& mesh = m.mesh;
  KeyedPiece p;
  for (const std::uint32_t t : ts) p.keys.insert(p.keys.end(), mesh.triangles[t].begin(), mesh.triangles[t].end());
  std::sort(p.keys.begin(), p.keys.end());
  p.keys.erase(std::unique(p.keys.begin(), p.keys.end()), p.keys.end());
  // The keys are the mesh's vertex indices, taken in order: re-appended with their vertices.
  std::vector<std::uint64_t> keys;
  keys.swap(p.keys);
  for (const std::uint64_t key : keys) p.append_mesh_vertex(mesh, static_cast<std::uint32_t>(key), key);
  const auto local = [&](std::uint32_t v) {
    return static_cast<std::uint32_t>(std::lower_bound(p.keys.begin(), p.keys.end(), v) - p.keys.begin());
  };
  for (const std::uint32_t t : ts) {
    const Triangle& tri = mesh.triangles[t];
    p.triangles.push_back({local(tri[0]), local(tri[1]), local(tri[2])});
    p.ids.push_back(mesh.triangle_ids[t]);
    p.source_acq.push_back(m.source_acq[t]);
    p.source_triangle.push_back(m.source_triangle[t]);
  }
  return p;
}

/// Every triangle of `m` in the part holding its centroid; the parts in key order.
std::vector<BlockPart> split_into_parts(const MergedMesh& m, const BlockStitchParams& blocks,
                                        std::vector<KeyedPiece>& pieces) {
  std::map<BlockPartKey, std::vector<std::uint32_t>> by_part;
  for (std::uint32_t t = 0; t < m.mesh.triangle_count(); ++t) {
    const Triangle& tri = m.mesh.triangles[t];
    const Vec3d c = (m.mesh.world_position(tri[0]) + m.mesh.world_position(tri[1]) + m.mesh.world_position(tri[2])) / 3.0;
    by_part[block_part_of(c, blocks)].push_back(t);
  }
  std::vector<BlockPart> parts;
  for (const auto& [key, ts] : by_part) {
    pieces.push_back(piece_of(m, ts));
    parts.push_back({key, pieces.back().box(), {}});
  }
  return parts;
}

/// The stitched parts as `m`'s triangles, in part order: the mesh's vertices stay where they
/// are (moved where stitching moved them), the new ones follow in key order.
void gather(MergedMesh& m, std::span<const std::shared_ptr<const KeyedPiece>> parts) {
  Mesh& mesh = m.mesh;
  std::vector<std::pair<std::uint64_t, std::pair<const KeyedPiece*, std::uint32_t>>> added;
  for (const auto& piece : parts) {
    for (std::uint32_t v = 0; v < piece->vertex_count(); ++v) {
      const std::uint64_t key = piece->keys[v];
      if (key >= kNewVertexKey) {
        added.push_back({key, {piece.get(), v}});
      } else if (piece->positions[v] != mesh.world_position(key)) {
        mesh.positions[key] = to_local(piece->positions[v], mesh.origin);
      }
    }
  }
  std::sort(added.begin(), added.end());
  added.erase(std::unique(added.begin(), added.end(),
                          [](const auto& a, const auto& b) { return a.first == b.first; }),
              added.end());
  const std::size_t first_added = mesh.vertex_count();
  for (const auto& [key, at] : added) {
    const auto& [piece, v] = at;
    mesh.positions.push_back(to_local(piece->positions[v], mesh.origin));
    if (mesh.has_sensor_positions()) mesh.sensor_positions.push_back(to_local(piece->sensors[v], mesh.origin));
    if (!mesh.times.empty()) mesh.times.push_back(piece->times[v]);
    if (!mesh.intensities.empty()) mesh.intensities.push_back(piece->intensities[v]);
    if (!mesh.colors.empty()) mesh.colors.push_back(piece->colors[v]);
  }
  const auto index_of = [&](std::uint64_t key) -> std::uint32_t {
    if (key < kNewVertexKey) return static_cast<std::uint32_t>(key);
    const auto it = std::lower_bound(added.begin(), added.end(), key,
                                     [](const auto& a, std::uint64_t k) { return a.first < k; });
    return static_cast<std::uint32_t>(first_added + static_cast<std::size_t>(it - added.begin()));
  };
  std::size_t triangles = 0;
  for (const auto& piece : parts) triangles += piece->triangle_count();
  mesh.triangles.reserve(triangles);
  mesh.triangle_ids.reserve(triangles);
  m.source_acq.reserve(triangles);
  m.source_triangle.reserve(triangles);
  for (const auto& piece : parts) {
    for (std::size_t t = 0; t < piece->triangle_count(); ++t) {
      const Triangle& tri = piece->triangles[t];
      mesh.triangles.push_back({index_of(piece->keys[tri[0]]), index_of(piece->keys[tri[1]]),
                                index_of(piece->keys[tri[2]])});
      mesh.triangle_ids.push_back(piece->ids[t]);
      m.source_acq.push_back(piece->source_acq[t]);
      m.source_triangle.push_back(piece->source_triangle[t]);
    }
  }
}

}  // namespace

BlockStitchStats stitch_in_blocks(MergedMesh& mesh, const StitchParams& params, const BlockStitchParams& blocks) {
  Stopwatch clock;
  PartStitchRun run{.params = params, .blocks = blocks, .source_sizes = source_sizes(mesh), .frame = mesh.mesh.origin, .run_level = {}};
  run.blocks.origin_x += mesh.mesh.origin.x;  // the pieces' positions are in the project CRS
  run.blocks.origin_y += mesh.mesh.origin.y;
  run.blocks.context = blocks.context > 0 ? blocks.context : block_context(params);
  check_block_layout(run.blocks, run.blocks.context);
  const double before = mosaic_detail::MeshTopology(mesh).boundary_length();
  std::vector<KeyedPiece> pieces;
  std::vector<BlockPart> parts = split_into_parts(mesh, run.blocks, pieces);
  // The parts hold the triangles now; gather() puts them back.
  std::vector<Triangle>().swap(mesh.mesh.triangles);
  std::vector<TriangleId>().swap(mesh.mesh.triangle_ids);
  std::vector<std::int32_t>().swap(mesh.source_acq);
  std::vector<std::int32_t>().swap(mesh.source_triangle);
  MemoryPartStore store(std::move(pieces));
  BlockStitchStats stats = stitch_parts(parts, store, run);
  gather(mesh, store.take_stitched());
  stats.stitch.open_boundary_before = before;
  stats.stitch.open_boundary_after = mosaic_detail::MeshTopology(mesh).boundary_length();
  stats.stitch.seconds = clock.seconds();
  return stats;
}

}  // namespace citymesh
