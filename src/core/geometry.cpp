// SPDX-License-Identifier: MIT
#include "citymesh/core/geometry.h"

#include <algorithm>
#include <cmath>

namespace citymesh {

namespace {

/// Closest point on segment [a, b] to p, as squared distance.
double point_segment_distance_sq(const Vec3d& p, const Vec3d& a, const Vec3d& b) {
  const Vec3d ab = b - a;
  const double len_sq = dot(ab, ab);
  double s = len_sq > 0 ? dot(p - a, ab) / len_sq : 0.0;
  s = std::clamp(s, 0.0, 1.0);
  const Vec3d d = p - (a + ab * s);
  return dot(d, d);
}

}  // namespace

double point_triangle_distance_sq(const Vec3d& p, const TriangleCorners& t) {
  const Vec3d& a = t[0];
  const Vec3d& b = t[1];
  const Vec3d& c = t[2];
  const Vec3d ab = b - a, ac = c - a;
  const Vec3d n = cross(ab, ac);
  const double n_sq = dot(n, n);
  // Degenerate (segment-like) triangles: the closest of the three edges.
  if (!(n_sq > 1e-24 * dot(ab, ab) * dot(ac, ac))) {
    return std::min({point_segment_distance_sq(p, a, b), point_segment_distance_sq(p, b, c),
                     point_segment_distance_sq(p, c, a)});
  }
  // Inside the prism over the triangle: the distance to the plane. Else: to the nearest edge.
  const Vec3d ap = p - a, bp = p - b, cp = p - c;
  const bool inside = dot(cross(ab, ap), n) >= 0 && dot(cross(c - b, bp), n) >= 0 && dot(cross(a - c, cp), n) >= 0;
  if (inside) {
    const double h = dot(ap, n);
    return h * h / n_sq;
  }
  return std::min({point_segment_distance_sq(p, a, b), point_segment_distance_sq(p, b, c),
                   point_segment_distance_sq(p, c, a)});
}

namespace {

constexpr int kTetFaces[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
constexpr int kTetEdges[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};

struct Interval {
  double lo, hi;
};

template <std::size_t N>
Interval project(const std::array<Vec3d, N>& points, const Vec3d& axis) {
  Interval r{dot(points[0], axis), dot(points[0], axis)};
  for (std::size_t i = 1; i < N; ++i) {
    const double d = dot(points[i], axis);
    r.lo = std::min(r.lo, d);
    r.hi = std::max(r.hi, d);
  }
  return r;
}

/// The shapes' shared context: corners relative to a common centre (smaller rounding) and the
/// edge vectors every axis is built from.
struct SatPair {
  TriangleCorners t;
  TetrahedronCorners q;
  std::array<Vec3d, 3> tri_edges;
  std::array<Vec3d, 6> tet_edges;
  double scale_sq = 0;  // squared length of the longest edge: the reference for "zero" axes

  /// True when `axis` separates the shapes. Axes that are (numerically) zero separate nothing.
  [[nodiscard]] bool separates(const Vec3d& axis, double reference_sq) const {
    const double len_sq = dot(axis, axis);
    if (!(len_sq > 1e-24 * reference_sq)) return false;
    const Interval a = project(t, axis), b = project(q, axis);
    return a.hi < b.lo || b.hi < a.lo;
  }
};

SatPair make_pair(const TriangleCorners& t, const TetrahedronCorners& q) {
  SatPair s;
  Vec3d centre = (q[0] + q[1] + q[2] + q[3]) * 0.25;
  for (int i = 0; i < 3; ++i) s.t[i] = t[i] - centre;
  for (int i = 0; i < 4; ++i) s.q[i] = q[i] - centre;
  for (int i = 0; i < 3; ++i) s.tri_edges[i] = s.t[(i + 1) % 3] - s.t[i];
  for (int e = 0; e < 6; ++e) s.tet_edges[e] = s.q[kTetEdges[e][1]] - s.q[kTetEdges[e][0]];
  for (const Vec3d& e : s.tri_edges) s.scale_sq = std::max(s.scale_sq, dot(e, e));
  for (const Vec3d& e : s.tet_edges) s.scale_sq = std::max(s.scale_sq, dot(e, e));
  return s;
}

}  // namespace

bool triangle_intersects_tetrahedron(const TriangleCorners& t, const TetrahedronCorners& q) {
  const SatPair s = make_pair(t, q);
  const double l2 = s.scale_sq * s.scale_sq;  // reference for products of two edges
  const double l4 = l2 * s.scale_sq;          // and of three

  // Cheapest and most often separating first: the tetrahedron's faces and the triangle's plane.
  std::array<Vec3d, 4> face_normals;
  for (int f = 0; f < 4; ++f) {
    const Vec3d& a = s.q[kTetFaces[f][0]];
    face_normals[f] = cross(s.q[kTetFaces[f][1]] - a, s.q[kTetFaces[f][2]] - a);
    if (s.separates(face_normals[f], l2)) return false;
  }
  const Vec3d tri_normal = cross(s.tri_edges[0], s.tri_edges[1]);
  if (s.separates(tri_normal, l2)) return false;
  // Edge against edge.
  for (const Vec3d& te : s.tri_edges) {
    for (const Vec3d& qe : s.tet_edges) {
      if (s.separates(cross(te, qe), l2)) return false;
    }
  }
  // In-plane axes, needed when the shapes are coplanar or flattened: each shape's edges turned
  // within its own plane, and within the other's.
  for (const Vec3d& te : s.tri_edges) {
    if (s.separates(cross(tri_normal, te), l4)) return false;
    for (const Vec3d& n : face_normals) {
      if (s.separates(cross(n, te), l4)) return false;
    }
  }
  for (const Vec3d& qe : s.tet_edges) {
    if (s.separates(cross(tri_normal, qe), l4)) return false;
  }
  for (int f = 0; f < 4; ++f) {
    for (int k = 0; k < 3; ++k) {
      const Vec3d e = s.q[kTetFaces[f][(k + 1) % 3]] - s.q[kTetFaces[f][k]];
      if (s.separates(cross(face_normals[f], e), l4)) return false;
    }
  }
  return true;
}

}  // namespace citymesh
