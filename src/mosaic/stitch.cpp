// SPDX-License-Identifier: MIT
#include "citymesh/mosaic/stitch.h"

#include <algorithm>
#include <numeric>
#include <optional>
#include <string_view>
#include <unordered_map>
#include <unordered_set>

#include "citymesh/core/log.h"
#include "citymesh/core/process_memory.h"
#include "citymesh/core/stopwatch.h"
#include "citymesh/mosaic/edges.h"
#include "citymesh/spatial/kd_tree.h"
#include "clip.h"
#include "gap_fill.h"
#include "snap.h"

namespace citymesh {

namespace {

Vec3d position(const Mesh& m, std::uint32_t v) { return Vec3d(m.positions[v]); }

Vec3d face_normal(const Mesh& m, std::uint32_t a, std::uint32_t b, std::uint32_t c) {
  return cross(position(m, b) - position(m, a), position(m, c) - position(m, a));
}

/// The boundary of the pieces: for each vertex, the boundary half-edge leaving it (the
/// direction of its triangle), and the triangle it belongs to.
struct Boundary {
  std::unordered_map<std::uint32_t, std::uint32_t> next, prev;  ///< vertex -> vertex along the boundary
  std::unordered_map<std::uint32_t, std::uint32_t> triangle_of;  ///< boundary vertex -> triangle of its outgoing edge
  std::vector<std::uint32_t> vertices;                          ///< in increasing order
};

Boundary find_boundary(const mosaic_detail::MeshTopology& topo) {
  const Mesh& m = topo.merged().mesh;
  Boundary b;
  std::unordered_map<std::uint32_t, int> outgoing;
  for (const EdgeUse& e : topo.boundary_edges()) {
    const Triangle& tri = m.triangles[e.triangle];
    // Orient as in the triangle: the half-edge u -> v whose reverse no triangle has.
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t u = tri[k], v = tri[(k + 1) % 3];
      if (std::min(u, v) != e.lo || std::max(u, v) != e.hi) continue;
      if (++outgoing[u] == 1 && !b.prev.contains(v)) {
        b.next[u] = v;
        b.prev[v] = u;
        b.triangle_of[u] = e.triangle;
      }
    }
  }
  for (const auto& [v, n] : b.next) b.vertices.push_back(v);
  std::sort(b.vertices.begin(), b.vertices.end());
  return b;
}

struct StitchContext {
  const StitchParams& params;
  mosaic_detail::MeshTopology& topo;  ///< the mesh, and which directed edges are in use
  Boundary boundary;
  std::unordered_map<std::uint32_t, std::uint32_t> partner;   ///< boundary vertex -> matched vertex of another piece
  std::unordered_set<std::uint32_t> consumed;                 ///< boundary half-edges (by their start) joined
  StitchStats stats;

  [[nodiscard]] MergedMesh& merged() const { return topo.merged(); }
  /// The side of the seams boundary vertex v is on (MeshTopology::piece()).
  [[nodiscard]] std::int32_t piece(std::uint32_t v) const { return topo.piece(boundary.triangle_of.at(v)); }
};

/// For every boundary vertex, the nearest boundary vertex of another source within reach, or
/// failing one, of another piece of its own source (a seam between sources is not left open
/// for a join within one pass).
void match_vertices(StitchContext& c) {
  const Mesh& m = c.merged().mesh;
  std::vector<Vec3f> points;
  for (const std::uint32_t v : c.boundary.vertices) points.push_back(m.positions[v]);
  const PointKdTree tree(points);
  std::vector<std::uint32_t> near;
  for (std::uint32_t i = 0; i < points.size(); ++i) {
    const std::uint32_t v = c.boundary.vertices[i];
    if (!c.topo.joinable(v)) continue;  // its own part joins it
    tree.radius_search(points[i], static_cast<float>(c.params.reach), near);
    const std::uint32_t tv = c.boundary.triangle_of.at(v);
    bool found = false, best_own_source = true;
    double best = c.params.reach * c.params.reach;
    for (const std::uint32_t j : near) {
      const std::uint32_t w = c.boundary.vertices[j];
      const std::uint32_t tw = c.boundary.triangle_of.at(w);
      const Vec3d d = position(m, w) - position(m, v);
      if (c.topo.piece(tw) == c.topo.piece(tv) || !c.topo.joinable(w) || dot(d, d) > c.params.reach * c.params.reach) {
        continue;
      }
      // Another source before another piece of v's own; then the nearer (the later on a tie).
      const bool own_source = c.topo.own_pieces_apart() && c.merged().source_acq[tw] == c.merged().source_acq[tv];
      if (!found || own_source < best_own_source || (own_source == best_own_source && dot(d, d) <= best)) {
        found = true;
        best_own_source = own_source;
        best = dot(d, d);
        c.partner[v] = w;
      }
    }
  }
}

/// The matched vertex of another piece, UINT32_MAX for none (or when v starts no boundary
/// half-edge, at a pinched vertex).
std::uint32_t partner_of(const StitchContext& c, std::uint32_t v) {
  const auto it = c.partner.find(v);
  return it == c.partner.end() ? UINT32_MAX : it->second;
}

/// Q's boundary from `from` to `to` walking backwards (against Q's orientation, which faces
/// P's), at most `limit` steps; empty when `to` is not reached or an edge is taken.
std::vector<std::uint32_t> facing_run(const StitchContext& c, std::uint32_t from, std::uint32_t to, std::size_t limit) {
  std::vector<std::uint32_t> run{from};
  for (std::uint32_t v = from; v != to;) {
    const auto it = c.boundary.prev.find(v);
    if (it == c.boundary.prev.end() || run.size() > limit || c.consumed.contains(it->second) ||
        !c.topo.joinable(it->second)) {
      return {};
    }
    v = it->second;
    run.push_back(v);
  }
  return run;
}

/// Adds the strip triangle (a, b, c) unless it is degenerate, faces against `reference` or
/// uses a directed edge already in use (which would fold the mesh or break its manifoldness).
bool add_strip_triangle(StitchContext& c, std::uint32_t a, std::uint32_t b, std::uint32_t d, const Vec3d& reference) {
  const Mesh& m = c.merged().mesh;
  const Vec3d n = face_normal(m, a, b, d);
  const double len = norm(n);
  if (!(len > 1e-10) || dot(n, reference) <= 0 || c.topo.has(a, b) || c.topo.has(b, d) || c.topo.has(d, a)) {
    ++c.stats.rejected;
    return false;
  }
  c.merged().mesh.triangles.push_back({a, b, d});
  c.merged().mesh.triangle_ids.push_back({});
  c.merged().source_acq.push_back(kNoSource);
  c.merged().source_triangle.push_back(kNoSource);
  c.topo.add_triangle(static_cast<std::uint32_t>(c.merged().mesh.triangle_count() - 1));
  ++c.stats.triangles_added;
  return true;
}

/// Zippers P's run a (oriented as P's boundary) with Q's facing run b (oriented the same way
/// along the seam): one new triangle per step, advancing the side with the shorter diagonal.
void zip(StitchContext& c, const std::vector<std::uint32_t>& a, const std::vector<std::uint32_t>& b) {
  const Mesh& m = c.merged().mesh;
  std::size_t i = 0, j = 0;
  while (i + 1 < a.size() || j + 1 < b.size()) {
    const bool advance_a =
        j + 1 >= b.size() ||
        (i + 1 < a.size() && norm(position(m, a[i + 1]) - position(m, b[j])) <= norm(position(m, a[i]) - position(m, b[j + 1])));
    // Reference: the piece triangle beside the boundary edge the new triangle takes.
    // (A value, not a reference: adding the strip triangle may move the triangle array.)
    const Triangle beside = m.triangles[c.boundary.triangle_of.at(advance_a ? a[i] : b[j + 1])];
    const Vec3d reference = face_normal(m, beside[0], beside[1], beside[2]);
    if (advance_a) {
      add_strip_triangle(c, a[i + 1], a[i], b[j], reference);
      ++i;
    } else {
      add_strip_triangle(c, a[i], b[j], b[j + 1], reference);
      ++j;
    }
  }
  for (std::size_t k = 0; k + 1 < a.size(); ++k) c.consumed.insert(a[k]);
  for (std::size_t k = 0; k + 1 < b.size(); ++k) c.consumed.insert(b[k + 1]);  // Q's half-edge b[k+1] -> b[k]
  ++c.stats.strips;
}

/// Walks one boundary loop from `start`: runs of consecutive vertices facing the same other
/// piece, along half-edges not joined yet, are zipped to that piece's facing run.
void stitch_loop(StitchContext& c, std::uint32_t start, std::unordered_set<std::uint32_t>& visited) {
  std::vector<std::uint32_t> run;
  std::int32_t facing = kNoSource;
  const auto flush = [&] {
    if (run.size() >= 2) {
      const std::vector<std::uint32_t> b =
          facing_run(c, partner_of(c, run.front()), partner_of(c, run.back()), 4 * run.size() + 8);
      if (!b.empty()) zip(c, run, b);
    }
    run.clear();
    facing = kNoSource;
  };
  std::uint32_t v = start;
  for (;;) {
    visited.insert(v);
    const std::uint32_t p = partner_of(c, v);
    const std::int32_t q = p == UINT32_MAX ? kNoSource : c.piece(p);
    if (!run.empty() && (q != facing || c.consumed.contains(run.back()))) flush();
    if (q != kNoSource) {
      facing = q;
      run.push_back(v);
    }
    const auto it = c.boundary.next.find(v);
    if (it == c.boundary.next.end() || it->second == start || visited.contains(it->second)) break;
    v = it->second;
  }
  flush();
}

/// Merges strip corners closer than the weld tolerance and drops the triangles that collapse.
void weld(StitchContext& c) {
  Mesh& m = c.merged().mesh;
  std::vector<std::uint32_t> target(m.vertex_count());
  std::iota(target.begin(), target.end(), 0);
  const double tol_sq = c.params.weld * c.params.weld;
  for (std::size_t t = 0; t < m.triangle_count(); ++t) {
    if (c.merged().source_acq[t] != kNoSource) continue;
    for (int k = 0; k < 3; ++k) {
      std::uint32_t u = m.triangles[t][k], v = m.triangles[t][(k + 1) % 3];
      while (target[u] != u) u = target[u];
      while (target[v] != v) v = target[v];
      if (u == v) continue;
      const Vec3d d = position(m, u) - position(m, v);
      const bool u_frozen = c.topo.frozen(u), v_frozen = c.topo.frozen(v);
      if (dot(d, d) <= tol_sq && !(u_frozen && v_frozen)) {
        // The frozen one stays; otherwise the smaller index.
        const bool keep_u = u_frozen || (!v_frozen && u < v);
        target[keep_u ? v : u] = keep_u ? u : v;
        ++c.stats.vertices_welded;
      }
    }
  }
  std::size_t kept = 0;
  for (std::size_t t = 0; t < m.triangle_count(); ++t) {
    Triangle tri = m.triangles[t];
    for (std::uint32_t& v : tri) {
      while (target[v] != v) v = target[v];
    }
    if (tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2]) continue;
    m.triangles[kept] = tri;
    m.triangle_ids[kept] = m.triangle_ids[t];
    c.merged().source_acq[kept] = c.merged().source_acq[t];
    c.merged().source_triangle[kept] = c.merged().source_triangle[t];
    ++kept;
  }
  m.triangles.resize(kept);
  m.triangle_ids.resize(kept);
  c.merged().source_acq.resize(kept);
  c.merged().source_triangle.resize(kept);
}

}  // namespace

double open_boundary_length(const Mesh& m) { return edges_length(m, boundary_edges(m.triangles)); }

StitchStats stitch(MergedMesh& merged, const StitchParams& params, const StitchSurroundings& around) {
  Stopwatch clock;
  // Where the time goes, at --log-level debug (the seam pass of a city runs mostly serial).
  const auto phase_done = [&clock](std::string_view phase) {
    log::debug("stitch: {} at {:.2f} s, {}", phase, clock.seconds(), memory_note());
  };
  // The unstitched boundary is measured before clipping changes it; the topology is built
  // again only when clipping changed the triangles.
  // (Its pieces are found only when it is kept: the boundary's length does not need them.)
  std::optional<mosaic_detail::MeshTopology> unclipped(std::in_place, merged, around,
                                                       params.join_own_pieces && !(params.clip > 0));
  const double before = unclipped->boundary_length();
  phase_done("topology and boundary");
  mosaic_detail::ClipStats clipped;
  if (params.clip > 0) {
    unclipped.reset();
    clipped = mosaic_detail::clip_overlaps(merged,
                                           {.tolerance = params.clip,
                                            .max_angle_deg = params.clip_angle,
                                            .own_tolerance = params.join_own_pieces ? params.own_clip : 0.0},
                                           around);
  }
  phase_done("clipped");
  mosaic_detail::MeshTopology& topo =
      unclipped ? *unclipped : unclipped.emplace(merged, around, params.join_own_pieces);
  const mosaic_detail::SnapStats snapped = mosaic_detail::snap_boundaries(topo, params.snap);
  phase_done("snapped");
  StitchContext c{params, topo, find_boundary(topo), {}, {}, {}};
  c.stats.open_boundary_before = before;
  c.stats.triangles_uncovered = clipped.triangles_removed;
  c.stats.triangles_clipped = clipped.triangles_cut;
  c.stats.triangles_split = clipped.triangles_split;
  c.stats.vertices_snapped = snapped.vertices_merged;
  c.stats.edges_split = snapped.edges_split;
  c.stats.rejected = snapped.rejected;
  match_vertices(c);
  phase_done("boundary matched");
  // Open chains (broken at pinched vertices) are walked from their head, so that each is
  // one walk; closed loops from their smallest vertex.
  std::unordered_set<std::uint32_t> visited;
  for (const std::uint32_t v : c.boundary.vertices) {
    if (!c.boundary.prev.contains(v)) stitch_loop(c, v, visited);
  }
  for (const std::uint32_t v : c.boundary.vertices) {
    if (!visited.contains(v)) stitch_loop(c, v, visited);
  }
  phase_done("zippered");
  if (params.gap > 0) {
    const mosaic_detail::GapFillStats gaps =
        mosaic_detail::fill_seam_gaps(topo, {.max_width = params.gap, .max_perimeter = mosaic_detail::kGapPerimeterInWidths * params.gap});
    c.stats.gaps_filled = gaps.gaps_filled + gaps.gaps_split;
    c.stats.triangles_added += gaps.triangles_added;
  }
  phase_done("gaps");
  weld(c);
  phase_done("welded");
  // From fresh incidence lists (the weld merged vertices and dropped collapsed triangles, so
  // topo's lists are stale): sorting every edge of a city's output instead took a third of
  // the pass. open_boundary_length() stays the sort-based reference the tests compare with.
  c.stats.open_boundary_after = mosaic_detail::MeshTopology(merged).boundary_length();
  c.stats.seconds = clock.seconds();
  return c.stats;
}

}  // namespace citymesh
