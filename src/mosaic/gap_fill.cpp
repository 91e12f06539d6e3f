// SPDX-License-Identifier: MIT
#include "gap_fill.h"

#include <algorithm>
#include <unordered_map>
#include <unordered_set>

namespace citymesh::mosaic_detail {

namespace {

/// A boundary half-edge from -> to (as its triangle runs it) and that triangle.
struct Outgoing {
  std::uint32_t to = 0, triangle = 0;
  int count = 0;  ///< boundary half-edges leaving `from`: more than one is a pinched vertex
};

std::unordered_map<std::uint32_t, Outgoing> boundary_successors(const MeshTopology& topo) {
  std::unordered_map<std::uint32_t, Outgoing> next;
  for (const DirectedEdge& e : topo.boundary_half_edges()) {
    Outgoing& o = next[e.from];
    if (++o.count == 1) o = {e.to, e.triangle, 1};
  }
  return next;
}

/// A loop of boundary half-edges: vertices[i] -> vertices[i + 1] belongs to triangles[i].
struct Loop {
  std::vector<std::uint32_t> vertices, triangles;
};

/// The closed loop through `start`, empty when it is longer than `limit`, open or pinched.
Loop trace_loop(const std::unordered_map<std::uint32_t, Outgoing>& next, std::uint32_t start, std::size_t limit,
                std::unordered_set<std::uint32_t>& visited) {
  Loop loop;
  std::uint32_t v = start;
  do {
    const auto it = next.find(v);
    if (it == next.end() || it->second.count != 1 || loop.vertices.size() >= limit || visited.contains(v)) {
      for (const std::uint32_t u : loop.vertices) visited.insert(u);
      return {};
    }
    loop.vertices.push_back(v);
    loop.triangles.push_back(it->second.triangle);
    v = it->second.to;
  } while (v != start);
  for (const std::uint32_t u : loop.vertices) visited.insert(u);
  return loop;
}

Vec3d normal_of(const MeshTopology& topo, const Triangle& t) {
  const Vec3d a = topo.position(t[0]);
  return cross(topo.position(t[1]) - a, topo.position(t[2]) - a);
}

/// True when the loop is small enough and runs along more than one source.
bool is_seam_gap(const MeshTopology& topo, const Loop& loop, const Vec3d& newell, const GapFillParams& params) {
  double perimeter = 0;
  for (std::size_t i = 0; i < loop.vertices.size(); ++i) {
    perimeter += norm(topo.position(loop.vertices[(i + 1) % loop.vertices.size()]) - topo.position(loop.vertices[i]));
  }
  const double area = 0.5 * norm(newell);
  if (perimeter > params.max_perimeter || 2 * area > params.max_width * perimeter) return false;
  const std::int32_t first = topo.merged().source_acq[loop.triangles.front()];
  return std::any_of(loop.triangles.begin(), loop.triangles.end(),
                     [&](std::uint32_t t) { return topo.merged().source_acq[t] != first; });
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
  const auto key = [](std::uint32_t from, std::uint32_t to) { return (std::uint64_t{from} << 32) | to; };
  for (std::size_t i = 0; i < loop.vertices.size(); ++i) {
    across[key(loop.vertices[(i + 1) % loop.vertices.size()], loop.vertices[i])] = loop.triangles[i];
  }
  for (const Triangle& t : fill) {
    const Vec3d n = normal_of(topo, t);
    if (!(norm(n) > 1e-10)) return {};
    for (int k = 0; k < 3; ++k) {
      const auto it = across.find(key(t[k], t[(k + 1) % 3]));
      if (it != across.end() && dot(n, normal_of(topo, topo.triangle(it->second))) <= 0) return {};
    }
  }
  if (!topo.edges_free(fill, {})) return {};
  return fill;
}

}  // namespace

GapFillStats fill_seam_gaps(MeshTopology& topo, const GapFillParams& params) {
  GapFillStats stats;
  const std::unordered_map<std::uint32_t, Outgoing> next = boundary_successors(topo);
  std::vector<std::uint32_t> starts;
  for (const auto& [v, o] : next) starts.push_back(v);
  std::sort(starts.begin(), starts.end());
  std::unordered_set<std::uint32_t> visited;
  MergedMesh& m = topo.merged();
  for (const std::uint32_t start : starts) {
    if (visited.contains(start)) continue;
    const Loop loop = trace_loop(next, start, params.max_vertices, visited);
    if (loop.vertices.size() < 3) continue;
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
      ++stats.gaps_refused;
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
