// SPDX-License-Identifier: MIT
#include "clip.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <span>
#include <unordered_map>

#include "citymesh/core/error.h"
#include "citymesh/core/geometry.h"
#include "citymesh/core/parallel.h"
#include "citymesh/mosaic/proximity.h"
#include "internal.h"

namespace citymesh::mosaic_detail {

namespace {

constexpr int kBisections = 12;  // 1/4096 of an edge: well under a millimetre for MLS edges

Vec3d unit_or_zero(const Vec3d& v) {
  const double n = norm(v);
  return n > 0 ? v / n : Vec3d{};
}

/// What a vertex belongs to, for the cover: the source, piece and earliest source triangle
/// (in the source's file) of its last triangle's piece at it.
struct VertexOwner {
  std::int32_t source = kNoSource, piece = kNoSource, first = INT32_MAX;
};

/// Per vertex: its owner (every vertex belongs to one, stitching not having started; no
/// source when unused) and its normal (area-weighted over its triangles).
struct VertexFrames {
  std::vector<VertexOwner> owner;
  std::vector<Vec3f> normal;
};

VertexFrames vertex_frames(const MergedMesh& merged, std::span<const std::int32_t> pieces) {
  const Mesh& m = merged.mesh;
  VertexFrames f{std::vector<VertexOwner>(m.vertex_count()), std::vector<Vec3f>(m.vertex_count())};
  for (std::size_t t = 0; t < m.triangle_count(); ++t) {
    const TriangleCorners c = m.corners(t);
    const Vec3f n(cross(c[1] - c[0], c[2] - c[0]));
    for (const std::uint32_t v : m.triangles[t]) {
      VertexOwner& o = f.owner[v];
      if (o.piece != pieces[t]) o = {merged.source_acq[t], pieces[t], INT32_MAX};
      o.first = std::min(o.first, merged.source_triangle[t]);
      f.normal[v] += n;
    }
  }
  for (Vec3f& n : f.normal) n = Vec3f(unit_or_zero(Vec3d(n)));
  return f;
}

/// Which source yields where two overlap: the one with fewer triangles in the mosaic (the
/// smaller pieces are cut back to the larger ones), on a tie the earlier acquisition.
/// `sizes`: per source, its triangles in the whole output when the mesh is only part of it.
std::vector<std::uint64_t> source_precedence(const MergedMesh& merged, std::span<const std::uint64_t> sizes) {
  const std::vector<std::uint64_t> count = sizes.empty() ? source_sizes(merged)
                                                         : std::vector<std::uint64_t>(sizes.begin(), sizes.end());
  for (const std::int32_t s : merged.source_acq) {
    if (s >= 0 && static_cast<std::size_t>(s) >= count.size()) {
      throw ProcessingError(fmt::format("clipping: source {} has no size among the {} given", s, sizes.size()));
    }
  }
  std::vector<std::uint64_t> precedence(count.size());
  for (std::size_t k = 0; k < count.size(); ++k) precedence[k] = count[k] * count.size() + k;
  return precedence;
}

enum class Coverage : std::uint8_t { none, other_source, own_piece };

/// "Does the surface of a source of higher precedence (or of an earlier piece of the same
/// source, within own_tolerance) lie over p?" for a point of `owner` with normal `n`.
class Cover {
 public:
  Cover(const MergedMesh& merged, const ClipParams& params, std::span<const std::uint64_t> sizes,
        std::span<const std::int32_t> pieces)
      : merged_(merged),
        near_(merged.mesh, params.tolerance),
        params_(params),
        min_cos_(std::cos(params.max_angle_deg * std::numbers::pi / 180.0)),
        precedence_(source_precedence(merged, sizes)),
        pieces_(pieces) {
    normal_.resize(merged.mesh.triangle_count());
    parallel_for_blocks(normal_.size(), 16384, [&](std::size_t begin, std::size_t end) {
      for (std::size_t t = begin; t < end; ++t) {
        const TriangleCorners c = merged.mesh.corners(t);
        normal_[t] = Vec3f(unit_or_zero(cross(c[1] - c[0], c[2] - c[0])));
      }
    });
  }

  /// Whether p is covered, and by what: another source's surface is looked for first.
  [[nodiscard]] Coverage coverage(const Vec3d& p, const VertexOwner& owner, const Vec3d& n) const {
    if (owner.source < 0) return Coverage::none;
    const std::uint64_t own = precedence_[static_cast<std::size_t>(owner.source)];
    bool by_own_piece = false;
    const bool by_other_source = near_.any_over(p, params_.tolerance, [&](std::uint32_t u) {
      const std::int32_t other = merged_.source_acq[u];
      if (other < 0 || dot(Vec3d(normal_[u]), n) < min_cos_) return false;
      if (other != owner.source) return precedence_[static_cast<std::size_t>(other)] > own;
      // An earlier piece of the point's own source, within the tolerance for its own: noted,
      // and the search goes on for another source.
      by_own_piece = by_own_piece || (pieces_[u] != owner.piece && merged_.source_triangle[u] < owner.first &&
                                      lies_over(p, merged_.mesh.corners(u), params_.own_tolerance));
      return false;
    });
    return by_other_source ? Coverage::other_source : by_own_piece ? Coverage::own_piece : Coverage::none;
  }
  [[nodiscard]] bool over(const Vec3d& p, const VertexOwner& owner, const Vec3d& n) const {
    return coverage(p, owner, n) != Coverage::none;
  }

 private:
  const MergedMesh& merged_;
  MeshProximity near_;
  const ClipParams& params_;
  double min_cos_;
  std::vector<std::uint64_t> precedence_;
  std::span<const std::int32_t> pieces_;  ///< per triangle: its piece, or its source (no own tolerance)
  std::vector<Vec3f> normal_;             ///< per triangle, unit
};

std::uint64_t edge_key(std::uint32_t a, std::uint32_t b) {
  return (std::uint64_t{std::min(a, b)} << 32) | std::max(a, b);
}

/// Where the edge from covered vertex c to uncovered vertex u leaves the cover, as a fraction
/// of the way from c, kept away from both ends so that no part degenerates.
double cut_fraction(const Mesh& m, const Cover& cover, const VertexFrames& f, std::uint32_t c, std::uint32_t u,
                    const ClipParams& params) {
  const Vec3d pc(m.positions[c]), pu(m.positions[u]);
  const Vec3d n = unit_or_zero(Vec3d(f.normal[c]) + Vec3d(f.normal[u]));
  double lo = 0, hi = 1;
  for (int i = 0; i < kBisections; ++i) {
    const double mid = 0.5 * (lo + hi);
    (cover.over(pc + (pu - pc) * mid, f.owner[c], n) ? lo : hi) = mid;
  }
  return std::clamp(0.5 * (lo + hi), params.min_edge_fraction, 1.0 - params.min_edge_fraction);
}

/// Appends a vertex whose every per-vertex attribute is mix(get), get(v) giving the
/// attribute's value at vertex v (a Vec3d for positions, a double otherwise).
template <class Mix>
std::uint32_t append_mixed(Mesh& m, Mix mix) {
  const auto v = static_cast<std::uint32_t>(m.positions.size());
  const auto position = mix([&](std::uint32_t i) { return Vec3d(m.positions[i]); });
  m.positions.push_back(Vec3f(position));
  if (!m.sensor_positions.empty()) {
    const auto sensor = mix([&](std::uint32_t i) { return Vec3d(m.sensor_positions[i]); });
    m.sensor_positions.push_back(Vec3f(sensor));
  }
  if (!m.times.empty()) {
    const double time = mix([&](std::uint32_t i) { return m.times[i]; });
    m.times.push_back(time);
  }
  if (!m.intensities.empty()) {
    const double intensity = mix([&](std::uint32_t i) { return double(m.intensities[i]); });
    m.intensities.push_back(static_cast<float>(intensity));
  }
  if (!m.colors.empty()) {
    const auto channel = [&](std::uint8_t Rgb8::*c) {
      return static_cast<std::uint8_t>(std::lround(mix([&](std::uint32_t i) { return double(m.colors[i].*c); })));
    };
    const Rgb8 color{channel(&Rgb8::r), channel(&Rgb8::g), channel(&Rgb8::b)};
    m.colors.push_back(color);
  }
  return v;
}

/// Appends the point a fraction s of the way from vertex a to vertex b, with every per-vertex
/// attribute interpolated.
std::uint32_t append_between(Mesh& m, std::uint32_t a, std::uint32_t b, double s) {
  return append_mixed(m, [&](auto get) {
    const auto x = get(a);
    return x + (get(b) - x) * s;
  });
}

/// Appends the centroid of triangle `tri`, with every per-vertex attribute averaged.
std::uint32_t append_centroid(Mesh& m, const Triangle& tri) {
  return append_mixed(m, [&](auto get) { return (get(tri[0]) + get(tri[1]) + get(tri[2])) / 3.0; });
}

/// A cut: the edge from covered vertex c to uncovered vertex u leaves the cover at `fraction`.
struct Cut {
  std::uint32_t c, u;
  double fraction;
};

/// One cut per edge with one covered end, in edge-key order.
std::vector<Cut> find_cuts(const Mesh& m, const Cover& cover, const VertexFrames& f,
                           const std::vector<std::uint8_t>& covered, const ClipParams& params,
                           std::span<const std::uint8_t> roles) {
  std::vector<std::uint64_t> keys;
  for (const Triangle& tri : m.triangles) {
    if (all_corners_frozen(tri, roles)) continue;
    for (std::size_t k = 0; k < 3; ++k) {
      const std::uint32_t a = tri[k], b = tri[(k + 1) % 3];
      if (covered[a] != covered[b]) keys.push_back(edge_key(a, b));
    }
  }
  std::sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  std::vector<Cut> cuts(keys.size());
  parallel_for_blocks(keys.size(), 256, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      auto c = static_cast<std::uint32_t>(keys[i] >> 32), u = static_cast<std::uint32_t>(keys[i]);
      if (covered[c] == 0) std::swap(c, u);
      cuts[i] = {c, u, cut_fraction(m, cover, f, c, u, params)};
    }
  });
  return cuts;
}

/// Appends the cuts' vertices; returns edge key -> new vertex.
std::unordered_map<std::uint64_t, std::uint32_t> add_cut_vertices(Mesh& m, const std::vector<Cut>& cuts) {
  // Room for the cut vertices at once: growing by doubling left half of every per-vertex
  // array of a city's output unused.
  const std::size_t room = m.vertex_count() + cuts.size();
  m.positions.reserve(room);
  if (!m.sensor_positions.empty()) m.sensor_positions.reserve(room);
  if (!m.times.empty()) m.times.reserve(room);
  if (!m.intensities.empty()) m.intensities.reserve(room);
  if (!m.colors.empty()) m.colors.reserve(room);
  std::unordered_map<std::uint64_t, std::uint32_t> vertex_of;
  for (const Cut& cut : cuts) vertex_of[edge_key(cut.c, cut.u)] = append_between(m, cut.c, cut.u, cut.fraction);
  return vertex_of;
}

/// The uncovered part of a triangle, as a polygon in the triangle's winding: its uncovered
/// corners and, on each edge with one covered end, the cut.
std::vector<std::uint32_t> uncovered_part(const Triangle& tri, const std::vector<std::uint8_t>& covered,
                                          const std::unordered_map<std::uint64_t, std::uint32_t>& cut) {
  std::vector<std::uint32_t> polygon;
  for (std::size_t k = 0; k < 3; ++k) {
    const std::uint32_t a = tri[k], b = tri[(k + 1) % 3];
    if (covered[a] == 0) polygon.push_back(a);
    if (covered[a] != covered[b]) polygon.push_back(cut.at(edge_key(a, b)));
  }
  return polygon;
}

double distance_sq(const Mesh& m, std::uint32_t a, std::uint32_t b) {
  const Vec3d d = Vec3d(m.positions[a]) - Vec3d(m.positions[b]);
  return dot(d, d);
}

/// Triangles of a convex polygon of 3 or 4 vertices (the shorter diagonal for 4).
std::vector<Triangle> triangulate(const Mesh& m, const std::vector<std::uint32_t>& p) {
  if (p.size() == 3) return {{p[0], p[1], p[2]}};
  if (distance_sq(m, p[0], p[2]) <= distance_sq(m, p[1], p[3])) return {{p[0], p[1], p[2]}, {p[0], p[2], p[3]}};
  return {{p[0], p[1], p[3]}, {p[1], p[2], p[3]}};
}

/// v[from[i]] for every i: one array rebuilt at a time, so that only it is ever held twice.
template <class T>
void gather(std::vector<T>& v, std::span<const std::uint32_t> from) {
  std::vector<T> out(from.size());
  for (std::size_t i = 0; i < from.size(); ++i) out[i] = v[from[i]];
  v = std::move(out);
}

/// Replaces each triangle in place by its uncovered part (nothing when covered whole).
ClipStats replace_covered(MergedMesh& merged, const std::vector<std::uint8_t>& covered,
                          const std::unordered_map<std::uint64_t, std::uint32_t>& cut, const StitchSurroundings& around) {
  Mesh& m = merged.mesh;
  ClipStats stats;
  std::vector<Triangle> triangles;
  std::vector<std::uint32_t> from;  ///< per new triangle, the triangle it is (part of)
  triangles.reserve(m.triangle_count());
  from.reserve(m.triangle_count());
  for (std::size_t t = 0; t < m.triangle_count(); ++t) {
    const Triangle& tri = m.triangles[t];
    const int corners_covered = covered[tri[0]] + covered[tri[1]] + covered[tri[2]];
    // A triangle of this part on other parts' vertices cannot be cut (its edges are theirs
    // too), but covered whole it goes: no later part would take it away.
    const bool stays_whole =
        all_corners_frozen(tri, around.vertex_roles) && !(around.told_own(t) && corners_covered == 3);
    if (corners_covered == 0 || stays_whole) {
      triangles.push_back(tri);  // nearly every triangle of a city: no polygon built
      from.push_back(static_cast<std::uint32_t>(t));
    } else if (corners_covered == 3) {
      ++stats.triangles_removed;
    } else {
      for (const Triangle& part : triangulate(m, uncovered_part(tri, covered, cut))) {
        triangles.push_back(part);
        from.push_back(static_cast<std::uint32_t>(t));
      }
      ++stats.triangles_cut;
    }
  }
  m.triangles = std::move(triangles);
  gather(m.triangle_ids, from);
  gather(merged.source_acq, from);
  gather(merged.source_triangle, from);
  return stats;
}

/// Triangles whose three corners are covered, one of them by an earlier piece of its own
/// source only, but whose centroid is not: that piece has a hole there (a later turn's
/// triangle spanning what the earlier turn lacks, its corners over the earlier turn around
/// the hole). Free triangles only, in index order. `pieces`: source_pieces(merged).
std::vector<std::uint32_t> open_in_the_middle(const MergedMesh& merged, const ClipParams& params,
                                              const StitchSurroundings& around, std::span<const std::int32_t> pieces) {
  const Mesh& m = merged.mesh;
  const VertexFrames frames = vertex_frames(merged, pieces);
  const Cover cover(merged, params, around.source_sizes, pieces);
  std::vector<Coverage> coverage(m.vertex_count(), Coverage::none);
  parallel_for_blocks(m.vertex_count(), 4096, [&](std::size_t begin, std::size_t end) {
    for (std::size_t v = begin; v < end; ++v) {
      if (role_of(around.vertex_roles, static_cast<std::uint32_t>(v)) != VertexRole::free) continue;
      coverage[v] = cover.coverage(Vec3d(m.positions[v]), frames.owner[v], Vec3d(frames.normal[v]));
    }
  });
  std::vector<std::uint8_t> open(m.triangle_count(), 0);
  parallel_for_blocks(m.triangle_count(), 4096, [&](std::size_t begin, std::size_t end) {
    for (std::size_t t = begin; t < end; ++t) {
      const Triangle& tri = m.triangles[t];
      const auto is = [&](Coverage c) {
        return coverage[tri[0]] == c || coverage[tri[1]] == c || coverage[tri[2]] == c;
      };
      if (is(Coverage::none) || !is(Coverage::own_piece)) continue;
      const TriangleCorners c = m.corners(t);
      const VertexOwner owner{merged.source_acq[t], pieces[t], merged.source_triangle[t]};
      open[t] = cover.over((c[0] + c[1] + c[2]) / 3.0, owner, unit_or_zero(cross(c[1] - c[0], c[2] - c[0]))) ? 0 : 1;
    }
  });
  std::vector<std::uint32_t> out;
  for (std::uint32_t t = 0; t < open.size(); ++t) {
    if (open[t] != 0) out.push_back(t);
  }
  return out;
}

/// Splits each of `triangles` into three about its centroid (the first part in its place,
/// the other two appended, all keeping its provenance). Its edges stay as they are, so the
/// mesh stays conforming; clipping then cuts the parts back along the spokes, and what stays
/// is the part about the centroid, over the hole, rather than nothing (the hole opened) or
/// the whole triangle (lying over the piece around the hole). `pieces` (per triangle) gets
/// the appended parts' pieces: their triangle's, as they use only its corners and centroid.
void split_about_centroids(MergedMesh& merged, std::span<const std::uint32_t> triangles,
                           std::vector<std::int32_t>& pieces) {
  Mesh& m = merged.mesh;
  for (const std::uint32_t t : triangles) {
    const Triangle tri = m.triangles[t];
    const std::uint32_t centre = append_centroid(m, tri);
    m.triangles[t] = {centre, tri[0], tri[1]};
    for (const Triangle& part : {Triangle{centre, tri[1], tri[2]}, Triangle{centre, tri[2], tri[0]}}) {
      m.triangles.push_back(part);
      m.triangle_ids.push_back(m.triangle_ids[t]);
      merged.source_acq.push_back(merged.source_acq[t]);
      merged.source_triangle.push_back(merged.source_triangle[t]);
      pieces.push_back(pieces[t]);
    }
  }
}

}  // namespace

ClipStats clip_overlaps(MergedMesh& merged, const ClipParams& params, const StitchSurroundings& around) {
  Mesh& m = merged.mesh;
  // Without a tolerance for its own, each source is one piece: never covered by itself.
  std::vector<std::int32_t> own_pieces;
  std::uint64_t split = 0;
  if (params.own_tolerance > 0) {
    own_pieces = source_pieces(merged);
    const std::vector<std::uint32_t> open = open_in_the_middle(merged, params, around, own_pieces);
    split_about_centroids(merged, open, own_pieces);
    split = open.size();
  }
  std::vector<std::uint8_t> covered(m.vertex_count(), 0);
  std::vector<Cut> cuts;
  {
    const std::span<const std::int32_t> pieces =
        params.own_tolerance > 0 ? std::span(own_pieces) : std::span(merged.source_acq);
    const VertexFrames frames = vertex_frames(merged, pieces);
    const Cover cover(merged, params, around.source_sizes, pieces);
    const std::span<const std::uint8_t> roles = around.vertex_roles;
    parallel_for_blocks(m.vertex_count(), 4096, [&](std::size_t begin, std::size_t end) {
      for (std::size_t v = begin; v < end; ++v) {
        // Output stitched before stays: its vertices are never covered. A later part's
        // vertex may be: the free triangles around it are cut now, the later part's own
        // triangles (whole, all_corners_frozen) when their turn comes, at the same place.
        if (role_of(roles, static_cast<std::uint32_t>(v)) == VertexRole::done) continue;
        covered[v] = cover.over(Vec3d(m.positions[v]), frames.owner[v], Vec3d(frames.normal[v])) ? 1 : 0;
      }
    });
    if (std::find(covered.begin(), covered.end(), 1) == covered.end()) return {.triangles_split = split};
    cuts = find_cuts(m, cover, frames, covered, params, roles);
  }  // the index and the normals go before the triangles are rebuilt (a city's peak memory)
  std::vector<std::int32_t>().swap(own_pieces);
  const std::size_t before = m.vertex_count();
  const auto vertex_of = add_cut_vertices(m, cuts);
  covered.resize(m.vertex_count(), 0);  // the cuts are where the cover ends: uncovered
  ClipStats stats = replace_covered(merged, covered, vertex_of, around);
  stats.vertices_added = m.vertex_count() - before;
  stats.triangles_split = split;
  return stats;
}

}  // namespace citymesh::mosaic_detail
