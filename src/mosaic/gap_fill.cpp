// SPDX-License-Identifier: MIT
#include "gap_fill.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <unordered_map>
#include <unordered_set>

#include "snap.h"

namespace citymesh::mosaic_detail {

namespace {

/// The boundary half-edges leaving each vertex (as their triangles run them): more than one
/// at a pinched vertex, where pieces touch at a corner (often a vertex snapping merged).
using Successors = std::unordered_map<std::uint32_t, std::vector<DirectedEdge>>;

Successors boundary_successors(const MeshTopology& topo) {
  Successors next;
  for (const DirectedEdge& e : topo.boundary_half_edges()) next[e.from].push_back(e);
  return next;
}

std::uint64_t directed_key(std::uint32_t from, std::uint32_t to) { return (std::uint64_t{from} << 32) | to; }
std::uint64_t half_edge_key(const DirectedEdge& e) { return directed_key(e.from, e.to); }

/// Unit area-weighted normal of the triangles around v (zero when they have no area).
Vec3d vertex_normal(const MeshTopology& topo, std::uint32_t v) {
  Vec3d n{};
  for (const std::uint32_t t : topo.triangles_of(v)) n += topo.winding(topo.triangle(t));
  const double length = norm(n);
  return length > 0 ? n / length : n;
}

/// At a pinched vertex v reached from `from`, the boundary half-edge that bounds the same
/// hole: the hole lies right of the incoming edge, so it is the first outgoing edge met
/// turning counter-clockwise (about v's normal) from the ray back to `from`.
const DirectedEdge& continue_hole(const MeshTopology& topo, std::uint32_t from, std::uint32_t v,
                                  const std::vector<DirectedEdge>& out) {
  const Vec3d n = vertex_normal(topo, v);
  const auto in_plane = [&](const Vec3d& d) { return d - n * dot(d, n); };
  const Vec3d back = in_plane(topo.position(from) - topo.position(v));
  const DirectedEdge* best = &out.front();
  double best_angle = 10;
  for (const DirectedEdge& e : out) {
    const Vec3d w = in_plane(topo.position(e.to) - topo.position(v));
    double angle = std::atan2(dot(cross(back, w), n), dot(back, w));
    if (angle <= 0) angle += 2 * std::numbers::pi;
    if (angle < best_angle) {
      best_angle = angle;
      best = &e;
    }
  }
  return *best;
}

/// A loop of boundary half-edges: vertices[i] -> vertices[i + 1] belongs to triangles[i].
struct Loop {
  std::vector<std::uint32_t> vertices, triangles;
};

/// The closed loop of boundary half-edges from `first`, empty when it is longer than
/// `limit`, open or not simple. At a pinched vertex the loop follows the hole it is on.
/// Its half-edges are marked `used` either way.
Loop trace_loop(const MeshTopology& topo, const Successors& next, const DirectedEdge& first, std::size_t limit,
                std::unordered_set<std::uint64_t>& used) {
  Loop loop;
  std::unordered_set<std::uint32_t> on_loop;
  const DirectedEdge* e = &first;
  for (;;) {
    if (loop.vertices.size() >= limit || !on_loop.insert(e->from).second || !used.insert(half_edge_key(*e)).second) {
      return {};
    }
    loop.vertices.push_back(e->from);
    loop.triangles.push_back(e->triangle);
    const auto it = next.find(e->to);
    if (it == next.end()) return {};
    e = it->second.size() == 1 ? &it->second.front() : &continue_hole(topo, e->from, e->to, it->second);
    if (e->from == first.from && e->to == first.to) return loop;
  }
}

/// True when the loop is small enough and runs along more than one source (or piece, with own
/// pieces apart).
bool is_seam_gap(const MeshTopology& topo, const Loop& loop, const Vec3d& newell, const GapFillParams& params) {
  double perimeter = 0;
  for (std::size_t i = 0; i < loop.vertices.size(); ++i) {
    perimeter += norm(topo.position(loop.vertices[(i + 1) % loop.vertices.size()]) - topo.position(loop.vertices[i]));
  }
  const double area = 0.5 * norm(newell);
  if (perimeter > params.max_perimeter || 2 * area > params.max_width * perimeter) return false;
  const std::int32_t first = topo.piece(loop.triangles.front());
  return std::any_of(loop.triangles.begin(), loop.triangles.end(),
                     [&](std::uint32_t t) { return topo.piece(t) != first; });
}

/// Ear clipping of `polygon` (counter-clockwise about `axis`), shortest diagonal first;
/// empty when some step finds no ear.
std::vector<Triangle> ear_clip(const MeshTopology& topo, std::vector<std::uint32_t> polygon, const Vec3d& axis) {
  const Vec3d helper = std::abs(axis.x) < 0.9 ? Vec3d{1, 0, 0} : Vec3d{0, 1, 0};
  const Vec3d e1 = cross(helper, axis) / norm(cross(helper, axis)), e2 = cross(axis, e1);
  const auto flat = [&](std::uint32_t v) {
    const Vec3d p = topo.position(v);
    return std::pair{dot(p, e1), dot(p, e2)};
  };
  const auto turn = [](std::pair<double, double> a, std::pair<double, double> b, std::pair<double, double> c) {
    return (b.first - a.first) * (c.second - a.second) - (b.second - a.second) * (c.first - a.first);
  };
  std::vector<Triangle> out;
  while (polygon.size() > 3) {
    const std::size_t n = polygon.size();
    std::size_t best = n;
    double best_diagonal = 0;
    for (std::size_t i = 0; i < n; ++i) {
      const std::uint32_t a = polygon[(i + n - 1) % n], b = polygon[i], c = polygon[(i + 1) % n];
      const auto pa = flat(a), pb = flat(b), pc = flat(c);
      if (!(turn(pa, pb, pc) > 0)) continue;  // reflex or flat: not an ear
      const bool holds_another = std::any_of(polygon.begin(), polygon.end(), [&](std::uint32_t v) {
        if (v == a || v == b || v == c) return false;
        const auto p = flat(v);
        return turn(pa, pb, p) >= 0 && turn(pb, pc, p) >= 0 && turn(pc, pa, p) >= 0;
      });
      if (holds_another) continue;
      const double diagonal = norm(topo.position(c) - topo.position(a));
      if (best == n || diagonal < best_diagonal) {
        best = i;
        best_diagonal = diagonal;
      }
    }
    if (best == n) return {};
    out.push_back({polygon[(best + n - 1) % n], polygon[best], polygon[(best + 1) % n]});
    polygon.erase(polygon.begin() + static_cast<std::ptrdiff_t>(best));
  }
  out.push_back({polygon[0], polygon[1], polygon[2]});
  return out;
}

/// The fill of one loop, empty when a triangle would degenerate, turn against the triangle
/// across a loop edge, or reuse a directed edge.
std::vector<Triangle> triangulate(const MeshTopology& topo, const Loop& loop, const Vec3d& newell) {
  // The fill runs the loop backwards: its triangles use the loop's edges reversed.
  std::vector<std::uint32_t> polygon(loop.vertices.rbegin(), loop.vertices.rend());
  const std::vector<Triangle> fill = ear_clip(topo, polygon, newell / norm(newell));
  if (fill.empty()) return {};
  std::unordered_map<std::uint64_t, std::uint32_t> across;  ///< reversed loop edge -> its triangle
  for (std::size_t i = 0; i < loop.vertices.size(); ++i) {
    across[directed_key(loop.vertices[(i + 1) % loop.vertices.size()], loop.vertices[i])] = loop.triangles[i];
  }
  for (const Triangle& t : fill) {
    const Vec3d n = topo.winding(t);
    if (!(norm(n) > 1e-10)) return {};
    for (int k = 0; k < 3; ++k) {
      const auto it = across.find(directed_key(t[k], t[(k + 1) % 3]));
      if (it != across.end() && dot(n, topo.winding(topo.triangle(it->second))) <= 0) return {};
    }
  }
  if (!topo.edges_free(fill, {})) return {};
  return fill;
}

/// Closes the loop by splitting its longest edge at the loop's other vertices, so that the
/// triangle on that edge takes the loop's other edges (reversed) as its own. This closes the
/// loops no fill can: the slivers where two sources' boundaries cross, so that the loop
/// winds the wrong way round (an overlap, not a hole) and any fill would face backwards.
bool close_by_split(MeshTopology& topo, const Loop& loop, double max_move) {
  const std::size_t n = loop.vertices.size();
  std::size_t longest = 0;
  double longest_length = -1;
  for (std::size_t i = 0; i < n; ++i) {
    const double length = norm(topo.position(loop.vertices[(i + 1) % n]) - topo.position(loop.vertices[i]));
    if (length > longest_length) {
      longest = i;
      longest_length = length;
    }
  }
  // The loop runs from -> to along the longest edge, then back through the others: in the
  // edge's own order they come reversed.
  const std::uint32_t from = loop.vertices[longest], to = loop.vertices[(longest + 1) % n];
  std::vector<std::uint32_t> inserted;
  for (std::size_t k = n - 1; k >= 2; --k) inserted.push_back(loop.vertices[(longest + k) % n]);
  // The split moves the edge to -> apex to a new triangle, while the successor lists still
  // name the old one. Only its source and facing are read later, and the fan keeps both.
  return split_boundary_edge_onto(topo, from, to, inserted, max_move);
}

}  // namespace

GapFillStats fill_seam_gaps(MeshTopology& topo, const GapFillParams& params) {
  GapFillStats stats;
  const Successors next = boundary_successors(topo);
  std::vector<DirectedEdge> starts;
  for (const auto& [v, out] : next) starts.insert(starts.end(), out.begin(), out.end());
  std::sort(starts.begin(), starts.end(), [](const DirectedEdge& a, const DirectedEdge& b) {
    return half_edge_key(a) < half_edge_key(b);
  });
  std::unordered_set<std::uint64_t> used;
  MergedMesh& m = topo.merged();
  for (const DirectedEdge& start : starts) {
    if (used.contains(half_edge_key(start))) continue;
    const Loop loop = trace_loop(topo, next, start, params.max_vertices, used);
    const auto unjoinable = [&](std::uint32_t v) { return !topo.joinable(v); };
    if (loop.vertices.size() < 3 || std::any_of(loop.vertices.begin(), loop.vertices.end(), unjoinable)) continue;
    // Of the fill (the loop reversed), about the first vertex: small loops far from the
    // frame's origin would lose the area to cancellation.
    const Vec3d origin = topo.position(loop.vertices.front());
    Vec3d newell{};
    for (std::size_t i = 0; i < loop.vertices.size(); ++i) {
      newell += cross(topo.position(loop.vertices[(i + 1) % loop.vertices.size()]) - origin, topo.position(loop.vertices[i]) - origin);
    }
    if (!(norm(newell) > 0) || !is_seam_gap(topo, loop, newell, params)) continue;
    const std::vector<Triangle> fill = triangulate(topo, loop, newell);
    if (fill.empty()) {
      if (close_by_split(topo, loop, params.max_width)) {
        ++stats.gaps_split;
      } else {
        ++stats.gaps_refused;
      }
      continue;
    }
    for (const Triangle& t : fill) {
      m.mesh.triangles.push_back(t);
      m.mesh.triangle_ids.push_back({});
      m.source_acq.push_back(kNoSource);
      m.source_triangle.push_back(kNoSource);
      topo.add_triangle(static_cast<std::uint32_t>(m.mesh.triangle_count() - 1));
    }
    ++stats.gaps_filled;
    stats.triangles_added += fill.size();
  }
  return stats;
}

}  // namespace citymesh::mosaic_detail
