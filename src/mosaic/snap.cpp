// SPDX-License-Identifier: MIT
#include "snap.h"

#include <algorithm>
#include <optional>
#include <span>

#include "citymesh/core/parallel.h"
#include "citymesh/spatial/box_tree.h"
#include "citymesh/spatial/kd_tree.h"

namespace citymesh::mosaic_detail {

namespace {

constexpr int kMaxRounds = 4;

// Every operation keeps each directed edge used by at most one triangle (MeshTopology's
// edges_free before any change).

Vec3d normal_of(const Vec3d& a, const Vec3d& b, const Vec3d& c) { return cross(b - a, c - a); }

/// A changed triangle is acceptable when it turned by less than a right angle and kept a
/// twentieth of its area: no flip, no sliver made from a sound triangle.
bool acceptable(const Vec3d& before, const Vec3d& after) {
  return dot(before, after) > 0 && norm(after) >= 0.05 * norm(before);
}

/// Every vertex that starts or ends one of the boundary edges, in increasing order.
std::vector<std::uint32_t> vertices_of(std::span<const DirectedEdge> edges) {
  std::vector<std::uint32_t> out;
  for (const DirectedEdge& e : edges) {
    out.push_back(e.from);
    out.push_back(e.to);
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

/// Whether every triangle around `movers` stays acceptable when all of them move to q.
bool moves_acceptable(const MeshTopology& topo, std::initializer_list<std::uint32_t> movers, const Vec3d& q) {
  const auto moved = [&](std::uint32_t u) {
    return std::find(movers.begin(), movers.end(), u) != movers.end() ? q : topo.position(u);
  };
  for (const std::uint32_t u : movers) {
    for (const std::uint32_t t : topo.triangles_of(u)) {
      const Triangle& tri = topo.triangle(t);
      if (!acceptable(topo.winding(tri), normal_of(moved(tri[0]), moved(tri[1]), moved(tri[2])))) return false;
    }
  }
  return true;
}

/// Makes w one with v at their midpoint, unless a triangle of either would flip or
/// degenerate or a directed edge would be used twice.
bool try_merge(MeshTopology& topo, std::uint32_t v, std::uint32_t w) {
  if (topo.frozen(w)) std::swap(v, w);  // a frozen vertex stays where it is: the other comes to it
  if (topo.frozen(w)) return false;
  const Vec3d mid = topo.frozen(v) ? topo.position(v) : (topo.position(v) + topo.position(w)) * 0.5;
  std::vector<Triangle> renamed;
  const std::vector<std::uint32_t> around_w(topo.triangles_of(w).begin(), topo.triangles_of(w).end());
  for (const std::uint32_t t : around_w) {
    Triangle tri = topo.triangle(t);
    for (std::uint32_t& u : tri) u = u == w ? v : u;
    if (tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2]) return false;  // v and w share it
    renamed.push_back(tri);
  }
  if (!moves_acceptable(topo, {v, w}, mid) || !topo.edges_free(renamed, around_w)) return false;
  std::vector<std::uint32_t>& around_v = topo.edit(v);
  for (std::size_t i = 0; i < renamed.size(); ++i) {
    topo.merged().mesh.triangles[around_w[i]] = renamed[i];
    around_v.push_back(around_w[i]);
  }
  topo.edit(w).clear();
  topo.merged().mesh.positions[v] = Vec3f(mid);
  return true;
}

/// For each of `vertices`, the others within the tolerance that belong to another piece,
/// in index order. The searches run on the pool: nothing moves before the merges.
std::vector<std::vector<std::uint32_t>> close_partners(const MeshTopology& topo,
                                                       const std::vector<std::uint32_t>& vertices,
                                                       const std::vector<Vec3f>& points, double tolerance) {
  const PointKdTree tree(points);
  std::vector<std::vector<std::uint32_t>> partners(vertices.size());
  parallel_for_blocks(vertices.size(), 1024, [&](std::size_t begin, std::size_t end) {
    std::vector<std::uint32_t> near;
    for (std::size_t i = begin; i < end; ++i) {
      if (!topo.joinable(vertices[i])) continue;  // its own part snaps it
      tree.radius_search(points[i], static_cast<float>(tolerance), near);
      const std::int32_t piece = topo.piece_of_vertex(vertices[i]);
      for (const std::uint32_t j : near) {
        // Two frozen vertices stay two: neither may move.
        const bool both_frozen = topo.frozen(vertices[i]) && topo.frozen(vertices[j]);
        if (topo.piece_of_vertex(vertices[j]) != piece && !both_frozen && topo.joinable(vertices[j])) {
          partners[i].push_back(j);
        }
      }
    }
  });
  return partners;
}

/// Stage 1: boundary vertices of different pieces (MeshTopology::piece()) within the tolerance
/// become one.
void merge_close_vertices(MeshTopology& topo, double tolerance, SnapStats& stats) {
  const std::vector<std::uint32_t> vertices = vertices_of(topo.boundary_half_edges());
  std::vector<Vec3f> points;
  for (const std::uint32_t v : vertices) points.push_back(topo.merged().mesh.positions[v]);
  const std::vector<std::vector<std::uint32_t>> partners = close_partners(topo, vertices, points, tolerance);
  // In order: each merge decides which vertices are still free for the next. Only merged
  // vertices move, and they are done, so the distances below are those of the search.
  std::vector<std::uint8_t> done(vertices.size(), 0);
  for (std::uint32_t i = 0; i < vertices.size(); ++i) {
    if (done[i] != 0) continue;
    const std::uint32_t v = vertices[i];
    std::uint32_t best = UINT32_MAX;
    bool best_own_source = true;
    double best_d2 = tolerance * tolerance;
    const std::int32_t source = topo.source_of_vertex(v);
    for (const std::uint32_t j : partners[i]) {
      const Vec3d d = topo.position(vertices[j]) - topo.position(v);
      if (done[j] != 0 || dot(d, d) > tolerance * tolerance) continue;
      // Another source's vertex before another piece of v's own source; then the nearer, and
      // on equal distances the smaller index (partners are in index order).
      const bool own_source = topo.own_pieces_apart() && topo.source_of_vertex(vertices[j]) == source;
      if (best == UINT32_MAX || own_source < best_own_source ||
          (own_source == best_own_source && dot(d, d) < best_d2)) {
        best = j;
        best_own_source = own_source;
        best_d2 = dot(d, d);
      }
    }
    if (best == UINT32_MAX) continue;
    if (try_merge(topo, v, vertices[best])) {
      done[i] = done[best] = 1;
      ++stats.vertices_merged;
    } else {
      ++stats.rejected;
    }
  }
}

/// A vertex to insert into a boundary edge, at parameter t along it.
struct Insertion {
  std::size_t edge;
  double t;
  std::uint32_t vertex;
  auto operator<=>(const Insertion&) const = default;
};

/// True when a triangle around v is of `piece` (MeshTopology::piece()).
bool touches_piece(const MeshTopology& topo, std::uint32_t v, std::int32_t piece) {
  const std::span<const std::uint32_t> around = topo.triangles_of(v);
  return std::any_of(around.begin(), around.end(), [&](std::uint32_t t) { return topo.piece(t) == piece; });
}

/// The nearest boundary edge (of `tree`, over `edges`) of another piece passing within the
/// tolerance of boundary vertex v, where v projects well inside the edge; edge SIZE_MAX when
/// there is none.
Insertion nearest_insertion(const MeshTopology& topo, std::span<const DirectedEdge> edges, const BoxTree& tree,
                            std::uint32_t v, double tolerance, std::vector<std::uint32_t>& hits) {
  Insertion best{SIZE_MAX, 0, v};
  if (!topo.joinable(v)) return best;  // its own part snaps it
  tree.containing(topo.merged().mesh.positions[v], hits);
  std::sort(hits.begin(), hits.end());
  const Vec3d p = topo.position(v);
  double best_d2 = tolerance * tolerance;
  for (const std::uint32_t h : hits) {
    const DirectedEdge& e = edges[h];
    if (e.from == v || e.to == v || touches_piece(topo, v, topo.piece(e.triangle)) ||
        topo.frozen_triangle(e.triangle)) {
      continue;
    }
    const Vec3d a = topo.position(e.from), ab = topo.position(e.to) - a;
    const double len2 = dot(ab, ab);
    if (!(len2 > 0)) continue;
    const double t = dot(p - a, ab) / len2;
    if (t < 0.05 || t > 0.95) continue;  // near an end: a merge's business, or a sliver
    const Vec3d d = a + ab * t - p;
    if (dot(d, d) < best_d2) {
      best_d2 = dot(d, d);
      best = {h, t, v};
    }
  }
  return best;
}

/// For every boundary vertex, its nearest_insertion, sorted by edge. The searches only read
/// the mesh: they run on the pool, and the result does not depend on the thread count.
std::vector<Insertion> find_insertions(const MeshTopology& topo, std::span<const DirectedEdge> edges, double tolerance) {
  std::vector<Box3f> boxes(edges.size());
  const auto pad = static_cast<float>(tolerance);
  parallel_for_blocks(edges.size(), 4096, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      const Vec3f a = topo.merged().mesh.positions[edges[i].from], b = topo.merged().mesh.positions[edges[i].to];
      boxes[i] = {Vec3f{std::min(a.x, b.x) - pad, std::min(a.y, b.y) - pad, std::min(a.z, b.z) - pad},
                  Vec3f{std::max(a.x, b.x) + pad, std::max(a.y, b.y) + pad, std::max(a.z, b.z) + pad}};
    }
  });
  const BoxTree tree(std::move(boxes));
  const std::vector<std::uint32_t> vertices = vertices_of(edges);
  std::vector<Insertion> nearest(vertices.size());
  parallel_for_blocks(vertices.size(), 1024, [&](std::size_t begin, std::size_t end) {
    std::vector<std::uint32_t> hits;
    for (std::size_t i = begin; i < end; ++i) nearest[i] = nearest_insertion(topo, edges, tree, vertices[i], tolerance, hits);
  });
  std::vector<Insertion> out;
  for (const Insertion& x : nearest) {
    if (x.edge != SIZE_MAX) out.push_back(x);
  }
  std::sort(out.begin(), out.end());
  return out;
}

/// Moves v to q unless one of its triangles would flip or degenerate.
bool try_move(MeshTopology& topo, std::uint32_t v, const Vec3d& q) {
  if (topo.frozen(v) || !moves_acceptable(topo, {v}, q)) return false;
  topo.merged().mesh.positions[v] = Vec3f(q);
  return true;
}

/// Stage 2: boundary edges are split at the boundary vertices of other pieces lying on them.
void split_edges_at_vertices(MeshTopology& topo, double tolerance, SnapStats& stats) {
  const std::vector<DirectedEdge> edges = topo.boundary_half_edges();
  const std::vector<Insertion> insertions = find_insertions(topo, edges, tolerance);
  for (std::size_t i = 0; i < insertions.size();) {
    std::size_t j = i;
    std::vector<std::uint32_t> inserted;
    for (; j < insertions.size() && insertions[j].edge == insertions[i].edge; ++j) inserted.push_back(insertions[j].vertex);
    const DirectedEdge& e = edges[insertions[i].edge];
    if (split_boundary_edge_onto(topo, e.from, e.to, inserted, tolerance)) {
      ++stats.edges_split;
    } else {
      ++stats.rejected;
    }
    i = j;
  }
}

}  // namespace

namespace {

/// How a split went: only a fan that folds (a vertex on the wrong side of a thin triangle)
/// can be mended by moving the vertices; the other refusals depend on the topology alone.
enum class Split { done, folds, refused };

Split split_fan(MeshTopology& topo, std::uint32_t from, std::uint32_t to, const std::vector<std::uint32_t>& inserted) {
  const std::optional<std::uint32_t> found = topo.triangle_with(from, to);
  if (!found) return Split::refused;
  const std::uint32_t t = *found;
  if (topo.frozen_triangle(t)) return Split::refused;
  const Triangle old = topo.triangle(t);
  int k = 0;
  while (old[k] != from) ++k;
  const std::uint32_t apex = old[(k + 2) % 3];
  const Vec3d before = topo.winding(old);
  std::vector<std::uint32_t> chain{from};
  chain.insert(chain.end(), inserted.begin(), inserted.end());
  chain.push_back(to);
  std::vector<Triangle> fan;
  for (std::size_t i = 0; i + 1 < chain.size(); ++i) {
    if (chain[i + 1] == apex) return Split::refused;
    fan.push_back({chain[i], chain[i + 1], apex});
    const Vec3d after = topo.winding(fan.back());
    if (dot(before, after) <= 0 || norm(after) < 1e-3 * norm(before)) return Split::folds;
  }
  if (!topo.edges_free(fan, std::span(&t, 1))) return Split::refused;
  MergedMesh& m = topo.merged();
  for (std::size_t i = 0; i < fan.size(); ++i) {
    const std::uint32_t slot = i == 0 ? t : static_cast<std::uint32_t>(m.mesh.triangle_count());
    if (i == 0) {
      m.mesh.triangles[t] = fan[0];
    } else {
      m.mesh.triangles.push_back(fan[i]);
      m.mesh.triangle_ids.push_back(m.mesh.triangle_ids[t]);
      m.source_acq.push_back(m.source_acq[t]);
      m.source_triangle.push_back(m.source_triangle[t]);
    }
    if (i > 0) topo.add_triangle(slot, topo.piece(t));
  }
  // Triangle t now spans from, the first inserted vertex and the apex.
  topo.edit(chain[1]).push_back(t);
  std::erase(topo.edit(to), t);
  return Split::done;
}

}  // namespace

bool split_boundary_edge(MeshTopology& topo, std::uint32_t from, std::uint32_t to, const std::vector<std::uint32_t>& inserted) {
  return split_fan(topo, from, to, inserted) == Split::done;
}

bool split_boundary_edge_onto(MeshTopology& topo, std::uint32_t from, std::uint32_t to,
                              const std::vector<std::uint32_t>& inserted, double max_move) {
  // A refusal for the topology's sake (an edge in use, the apex among the vertices) would
  // come again after any move: moving is tried only for a fan that folds.
  const Split first = split_fan(topo, from, to, inserted);
  if (first != Split::folds) return first == Split::done;
  std::vector<std::pair<std::uint32_t, Vec3f>> saved;
  const Vec3d a = topo.position(from), ab = topo.position(to) - a;
  const double len2 = dot(ab, ab);
  bool moved = len2 > 0;
  for (std::size_t k = 0; k < inserted.size() && moved; ++k) {
    const std::uint32_t v = inserted[k];
    const Vec3d p = topo.position(v);
    const double t = dot(p - a, ab) / len2;
    const Vec3d q = a + ab * t;
    saved.emplace_back(v, topo.merged().mesh.positions[v]);
    moved = t > 0 && t < 1 && norm(q - p) <= max_move && try_move(topo, v, q);
  }
  if (moved && split_boundary_edge(topo, from, to, inserted)) return true;
  for (const auto& [v, p] : saved) topo.merged().mesh.positions[v] = p;
  return false;
}

SnapStats snap_boundaries(MeshTopology& topo, double tolerance) {
  SnapStats stats;
  // A vertex whose nearest partner was taken, or a vertex a split just made, gets another
  // round; the second round already finds almost everything (demo: 419 -> 401 m of open
  // seams, the same after four).
  for (int round = 0; round < kMaxRounds; ++round) {
    const std::uint64_t done = stats.vertices_merged + stats.edges_split;
    merge_close_vertices(topo, tolerance, stats);
    split_edges_at_vertices(topo, tolerance, stats);
    if (stats.vertices_merged + stats.edges_split == done) break;
  }
  return stats;
}

}  // namespace citymesh::mosaic_detail
