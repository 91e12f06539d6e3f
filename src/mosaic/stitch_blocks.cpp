// SPDX-License-Identifier: MIT
#include "citymesh/mosaic/stitch_blocks.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <optional>
#include <span>
#include <stdexcept>
#include <unordered_map>

#include "citymesh/core/error.h"
#include "citymesh/core/log.h"
#include "citymesh/core/parallel.h"
#include "citymesh/core/process_memory.h"
#include "citymesh/core/stopwatch.h"
#include "gap_fill.h"
#include "mesh_topology.h"

namespace citymesh {

namespace {

constexpr int kLevels = 4;

/// The part a triangle belongs to. Level 0: a block interior (x, y: the block). Level 1: a
/// band along the grid line x, without its ends (y: the block row). Level 2: the same along
/// the grid line y (x: the block column). Level 3: the corner square at grid point (x, y).
/// The parts of one level lie apart: the bands along x are held apart by the corner squares,
/// and so on (the two kinds of band touch at the corner squares' inner corners).
struct PartKey {
  int level = 0;
  std::int64_t x = 0, y = 0;
  friend auto operator<=>(const PartKey&, const PartKey&) = default;
};

/// Along one axis: the block holding a coordinate and, within `band` of a block side, that
/// side's grid line.
struct AxisCell {
  std::int64_t block = 0;
  std::optional<std::int64_t> line;
};

AxisCell axis_cell(double c, double origin, double size, double band) {
  const double f = (c - origin) / size;
  const auto block = static_cast<std::int64_t>(std::floor(f));
  const double u = (f - static_cast<double>(block)) * size;
  if (u < band) return {block, block};
  if (u > size - band) return {block, block + 1};
  return {block, std::nullopt};
}

PartKey part_of(const Vec3d& centroid, const BlockStitchParams& p) {
  const AxisCell x = axis_cell(centroid.x, p.origin_x, p.size, p.band);
  const AxisCell y = axis_cell(centroid.y, p.origin_y, p.size, p.band);
  if (x.line && y.line) return {3, *x.line, *y.line};
  if (x.line) return {1, *x.line, y.block};
  if (y.line) return {2, x.block, *y.line};
  return {0, x.block, y.block};
}

/// A part's triangles, on the vertices of the whole mesh, with their provenance: first its
/// input, then (once done) its stitched output.
struct Part {
  PartKey key;
  std::vector<Triangle> triangles;
  std::vector<TriangleId> ids;
  std::vector<std::int32_t> acq, from;
  Box3d box;  ///< of its triangles' corners
  bool done = false;
};

Box3d box_of(const Mesh& m, const Triangle& tri) {
  Box3d b;
  for (const std::uint32_t v : tri) b.extend(Vec3d(m.positions[v]));
  return b;
}

void add_triangle(Part& part, const Mesh& m, const Triangle& tri, const TriangleId& id, std::int32_t acq,
                  std::int32_t from) {
  part.triangles.push_back(tri);
  part.ids.push_back(id);
  part.acq.push_back(acq);
  part.from.push_back(from);
  part.box.extend(box_of(m, tri));
}

void reserve(Part& part, std::size_t n) {
  part.triangles.reserve(n);
  part.ids.reserve(n);
  part.acq.reserve(n);
  part.from.reserve(n);
}

/// Every triangle of `merged` in its part; the parts in key order (level first). Each part's
/// arrays get their exact size first: grown by doubling, or with a sorted copy of a key per
/// triangle, they were the peak of a city's block stitching.
std::vector<Part> split_into_parts(const MergedMesh& merged, const BlockStitchParams& p) {
  const Mesh& m = merged.mesh;
  std::map<PartKey, std::uint32_t> index;
  std::vector<std::uint32_t> part_of_triangle(m.triangle_count());
  std::optional<std::pair<PartKey, std::uint32_t>> last;  // neighbouring triangles mostly share a part
  for (std::size_t t = 0; t < m.triangle_count(); ++t) {
    const auto c = m.corners(t);
    const PartKey key = part_of((c[0] + c[1] + c[2]) / 3.0, p);
    if (!last || last->first != key) {
      last = {key, index.try_emplace(key, static_cast<std::uint32_t>(index.size())).first->second};
    }
    part_of_triangle[t] = last->second;
  }
  std::vector<Part> parts(index.size());
  std::vector<std::size_t> counts(parts.size(), 0);
  for (const std::uint32_t i : part_of_triangle) ++counts[i];
  for (const auto& [key, i] : index) {
    parts[i].key = key;
    reserve(parts[i], counts[i]);
  }
  for (std::size_t t = 0; t < m.triangle_count(); ++t) {
    add_triangle(parts[part_of_triangle[t]], m, m.triangles[t], m.triangle_ids[t], merged.source_acq[t],
                 merged.source_triangle[t]);
  }
  std::sort(parts.begin(), parts.end(), [](const Part& x, const Part& y) { return x.key < y.key; });
  return parts;
}

/// A part cut out of the whole with its surroundings (first), ready for stitch().
struct PartMesh {
  MergedMesh merged;
  std::vector<std::uint32_t> whole_vertex;  ///< per vertex as cut out: the whole mesh's
  std::vector<std::uint8_t> roles;          ///< per vertex as cut out: its VertexRole
  std::vector<Triangle> surroundings;       ///< the other parts' triangles, as cut out
};

/// Gathers a part's triangles and those around it; its vertices keep the whole mesh's order
/// (stitching breaks ties by vertex order: a part holding everything stitches as the whole).
class PartCutter {
 public:
  /// `uses`: per vertex of the whole mesh, the triangles using it.
  PartCutter(const Mesh& whole, std::span<const std::uint32_t> uses) : whole_(whole), uses_(uses) {
    out_.merged.mesh.origin = whole.origin;
  }

  /// Adds triangle i of `part`; its vertices take `role` unless they have a stronger one
  /// (held over done over later over free).
  void add(const Part& part, std::size_t i, VertexRole role) {
    for (const std::uint32_t v : part.triangles[i]) {
      Use& u = vertices_.try_emplace(v).first->second;
      ++u.triangles;
      u.role = std::max(u.role, role, [](VertexRole a, VertexRole b) { return strength(a) < strength(b); });
    }
    MergedMesh& m = out_.merged;
    m.mesh.triangles.push_back(part.triangles[i]);
    m.mesh.triangle_ids.push_back(part.ids[i]);
    m.source_acq.push_back(part.acq[i]);
    m.source_triangle.push_back(part.from[i]);
  }

  [[nodiscard]] std::size_t triangle_count() const { return out_.merged.mesh.triangle_count(); }

  /// The part mesh, on its own vertices.
  PartMesh take() {
    PartMesh& cut = out_;
    for (const auto& [v, use] : vertices_) cut.whole_vertex.push_back(v);
    std::sort(cut.whole_vertex.begin(), cut.whole_vertex.end());
    for (const std::uint32_t v : cut.whole_vertex) {
      Use& use = vertices_.at(v);
      use.local = static_cast<std::uint32_t>(cut.roles.size());
      // On the edge of what was cut out, the output looks open where it is not: no seam may
      // join such a vertex (this part's triangles never use it).
      const bool on_cut_edge = use.triangles < uses_[v];
      cut.roles.push_back(static_cast<std::uint8_t>(on_cut_edge ? VertexRole::held : use.role));
      append_vertex(whole_, v, cut.merged.mesh);
    }
    for (Triangle& tri : cut.merged.mesh.triangles) {
      for (std::uint32_t& v : tri) v = vertices_.at(v).local;
    }
    return std::move(out_);
  }

 private:
  static int strength(VertexRole r) {
    switch (r) {
      case VertexRole::free: return 0;
      case VertexRole::later: return 1;
      case VertexRole::done: return 2;
      case VertexRole::held: return 3;
    }
    return 3;
  }

  struct Use {
    VertexRole role = VertexRole::free;
    std::uint32_t triangles = 0;
    std::uint32_t local = 0;  ///< its index in the part mesh, once taken
  };
  const Mesh& whole_;
  std::span<const std::uint32_t> uses_;
  PartMesh out_;
  std::unordered_map<std::uint32_t, Use> vertices_;  ///< per vertex of the whole mesh used
};

/// Part `index` with every triangle of the other parts within `context` of it: those of done
/// parts as output stitched before, the others as parts stitched later.
PartMesh cut_out(const Mesh& whole, std::span<const std::uint32_t> uses, const std::vector<Part>& parts,
                 std::size_t index, double context) {
  const Box3d reach = parts[index].box.grown(context);
  PartCutter cutter(whole, uses);
  for (std::size_t q = 0; q < parts.size(); ++q) {
    const Part& other = parts[q];
    if (q == index || !other.box.intersects(reach)) continue;
    // A part of this level is stitched at the same time: where they touch, neither joins.
    const VertexRole role = other.done                                 ? VertexRole::done
                            : other.key.level == parts[index].key.level ? VertexRole::held
                                                                        : VertexRole::later;
    for (std::size_t i = 0; i < other.triangles.size(); ++i) {
      if (box_of(whole, other.triangles[i]).intersects(reach)) cutter.add(other, i, role);
    }
  }
  const std::size_t surroundings = cutter.triangle_count();
  for (std::size_t i = 0; i < parts[index].triangles.size(); ++i) cutter.add(parts[index], i, VertexRole::free);
  PartMesh cut = cutter.take();
  cut.surroundings.assign(cut.merged.mesh.triangles.begin(),
                          cut.merged.mesh.triangles.begin() + static_cast<std::ptrdiff_t>(surroundings));
  return cut;
}

/// Stitches a part cut out with its surroundings; throws ProcessingError if stitching
/// changed them (they must come out first, unchanged, for the part to be spliced back).
StitchStats stitch_part(PartMesh& cut, const StitchParams& params, std::span<const std::uint64_t> sizes) {
  const StitchStats stats = stitch(
      cut.merged, params,
      {.vertex_roles = cut.roles, .source_sizes = sizes, .first_own_triangle = cut.surroundings.size()});
  const std::vector<Triangle>& out = cut.merged.mesh.triangles;
  if (out.size() < cut.surroundings.size() ||
      !std::equal(cut.surroundings.begin(), cut.surroundings.end(), out.begin())) {
    throw ProcessingError("stitching block by block: a part's stitching changed the output around it");
  }
  return stats;
}

/// Adds `step` to the uses of every corner of `triangles`.
void count_uses(std::span<const Triangle> triangles, int step, std::vector<std::uint32_t>& uses) {
  for (const Triangle& tri : triangles) {
    for (const std::uint32_t v : tri) uses[v] += static_cast<std::uint32_t>(step);
  }
}

/// Puts a stitched part back: its free vertices where stitching moved them, its new
/// vertices at the end of the whole mesh, its triangles in place of its input (`uses`
/// follows: per vertex of the whole mesh, the triangles of every part using it).
void splice(Mesh& whole, std::vector<std::uint32_t>& uses, Part& part, const PartMesh& cut) {
  const Mesh& m = cut.merged.mesh;
  count_uses(part.triangles, -1, uses);
  std::vector<std::uint32_t> to_whole(m.vertex_count());
  for (std::uint32_t v = 0; v < m.vertex_count(); ++v) {
    if (v < cut.whole_vertex.size()) {
      to_whole[v] = cut.whole_vertex[v];
      if (cut.roles[v] == static_cast<std::uint8_t>(VertexRole::free)) whole.positions[to_whole[v]] = m.positions[v];
    } else {
      to_whole[v] = static_cast<std::uint32_t>(whole.vertex_count());
      append_vertex(m, v, whole);
      uses.push_back(0);
    }
  }
  const PartKey key = part.key;
  part = Part{};
  part.key = key;
  reserve(part, m.triangle_count() - cut.surroundings.size());
  for (std::size_t t = cut.surroundings.size(); t < m.triangle_count(); ++t) {
    Triangle tri = m.triangles[t];
    for (std::uint32_t& v : tri) v = to_whole[v];
    add_triangle(part, whole, tri, m.triangle_ids[t], cut.merged.source_acq[t], cut.merged.source_triangle[t]);
  }
  count_uses(part.triangles, +1, uses);
}

void add_counts(StitchStats& total, const StitchStats& s) {
  total.vertices_snapped += s.vertices_snapped;
  total.edges_split += s.edges_split;
  total.triangles_uncovered += s.triangles_uncovered;
  total.triangles_clipped += s.triangles_clipped;
  total.strips += s.strips;
  total.triangles_added += s.triangles_added;
  total.vertices_welded += s.vertices_welded;
  total.gaps_filled += s.gaps_filled;
  total.rejected += s.rejected;
}

/// What every level works on: the output (its vertices; the parts hold its triangles) and
/// per vertex, the triangles of every part using it (kept up to date as parts are spliced).
struct Output {
  Mesh& whole;
  std::vector<Part> parts;
  std::vector<std::uint32_t> uses;
};

struct LevelRun {
  const StitchParams& params;
  std::span<const std::uint64_t> sizes;
  double context;
};

/// Parts cut out and stitched at a time: their memory is what a level adds to the output's.
constexpr std::size_t kPartsInFlight = 8;

/// Stitches the parts of one level, a few at a time: cut out and stitched in parallel, then
/// spliced back in part order. They are marked done once the whole level is (until then
/// the parts of the level see each other's vertices as held), so the output is the same
/// for any thread count.
void stitch_level(Output& out, int level, const LevelRun& run, BlockStitchStats& stats) {
  std::vector<Part>& parts = out.parts;
  std::vector<std::size_t> of_level;
  for (std::size_t i = 0; i < parts.size(); ++i) {
    if (parts[i].key.level == level) of_level.push_back(i);
  }
  for (std::size_t first = 0; first < of_level.size(); first += kPartsInFlight) {
    const std::size_t count = std::min(kPartsInFlight, of_level.size() - first);
    std::vector<std::optional<PartMesh>> cuts(count);
    std::vector<StitchStats> part_stats(count);
    parallel_for_blocks(count, 1, [&](std::size_t begin, std::size_t end) {
      for (std::size_t i = begin; i < end; ++i) {
        cuts[i] = cut_out(out.whole, out.uses, parts, of_level[first + i], run.context);
        part_stats[i] = stitch_part(*cuts[i], run.params, run.sizes);
      }
    });
    for (std::size_t i = 0; i < count; ++i) {
      stats.largest_part = std::max(stats.largest_part, cuts[i]->merged.mesh.triangle_count());
      splice(out.whole, out.uses, parts[of_level[first + i]], *cuts[i]);
      cuts[i].reset();
      add_counts(stats.stitch, part_stats[i]);
    }
  }
  for (const std::size_t i : of_level) parts[i].done = true;
  stats.parts[static_cast<std::size_t>(level)] = of_level.size();
}

void check_layout(const BlockStitchParams& p, double context) {
  const bool finite = std::isfinite(p.origin_x) && std::isfinite(p.origin_y) && std::isfinite(p.size) &&
                      std::isfinite(p.band) && std::isfinite(context);
  if (!finite || !(p.size > 0) || !(p.band >= context) || !(4 * p.band < p.size)) {
    throw std::invalid_argument(fmt::format(
        "stitching block by block: blocks of {} m with bands of {} m and a context of {} m (the band must be at "
        "least the context and under a quarter of the block)",
        p.size, p.band, context));
  }
}

/// The parts' triangles, in part order, as the whole mesh's.
void gather(MergedMesh& merged, std::vector<Part>& parts) {
  Mesh& m = merged.mesh;
  std::size_t total = 0;
  for (const Part& part : parts) total += part.triangles.size();
  m.triangles.reserve(total);
  m.triangle_ids.reserve(total);
  merged.source_acq.reserve(total);
  merged.source_triangle.reserve(total);
  for (Part& part : parts) {
    m.triangles.insert(m.triangles.end(), part.triangles.begin(), part.triangles.end());
    m.triangle_ids.insert(m.triangle_ids.end(), part.ids.begin(), part.ids.end());
    merged.source_acq.insert(merged.source_acq.end(), part.acq.begin(), part.acq.end());
    merged.source_triangle.insert(merged.source_triangle.end(), part.from.begin(), part.from.end());
    part = Part{};
  }
}

}  // namespace

double block_context(const StitchParams& params) {
  const double farthest = std::max({params.snap, params.reach, params.clip,
                                    0.5 * mosaic_detail::kGapPerimeterInWidths * params.gap});
  return 1.25 * farthest;  // a margin: what is looked for near a vertex may lie a little farther
}

BlockStitchStats stitch_in_blocks(MergedMesh& mesh, const StitchParams& params, const BlockStitchParams& blocks) {
  Stopwatch clock;
  const double context = blocks.context > 0 ? blocks.context : block_context(params);
  check_layout(blocks, context);
  BlockStitchStats stats;
  stats.stitch.open_boundary_before = mosaic_detail::MeshTopology(mesh).boundary_length();
  const std::vector<std::uint64_t> sizes = source_sizes(mesh);
  Output out{mesh.mesh, split_into_parts(mesh, blocks), std::vector<std::uint32_t>(mesh.mesh.vertex_count(), 0)};
  count_uses(mesh.mesh.triangles, +1, out.uses);
  // The parts hold the triangles now (the output is gathered from them at the end).
  mesh.mesh.triangles = {};
  mesh.mesh.triangle_ids = {};
  mesh.source_acq = {};
  mesh.source_triangle = {};
  log::debug("stitch by blocks: {} parts at {:.2f} s, {}", out.parts.size(), clock.seconds(), memory_note());
  const LevelRun run{params, sizes, context};
  for (int level = 0; level < kLevels; ++level) {
    stitch_level(out, level, run, stats);
    log::debug("stitch by blocks: level {} ({} parts) at {:.2f} s, {}", level,
               stats.parts[static_cast<std::size_t>(level)], clock.seconds(), memory_note());
  }
  gather(mesh, out.parts);
  stats.stitch.open_boundary_after = mosaic_detail::MeshTopology(mesh).boundary_length();
  stats.stitch.seconds = clock.seconds();
  return stats;
}

}  // namespace citymesh
