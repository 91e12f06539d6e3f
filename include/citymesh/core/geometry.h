// SPDX-License-Identifier: MIT
// Exact-in-intent geometric predicates on triangles and tetrahedra, in double precision:
// the change detection's consistency (point-to-triangle distance) and conflict (triangle
// versus empty-space tetrahedron) tests.
#pragma once

#include <array>

#include "citymesh/core/vec.h"

namespace citymesh {

using TriangleCorners = std::array<Vec3d, 3>;
using TetrahedronCorners = std::array<Vec3d, 4>;

/// Squared distance from `p` to the closest point of the closed triangle `t` (its interior,
/// edges or corners). Degenerate triangles (segments, points) are handled as such.
double point_triangle_distance_sq(const Vec3d& p, const TriangleCorners& t);

/// True when the closed triangle `t` and the closed tetrahedron `q` share at least one point:
/// touching at a corner or along an edge counts, and so does a triangle lying in a face.
/// Separating-axis test over every candidate axis of the two shapes, including the in-plane
/// axes that coplanar and flattened (degenerate) configurations need, so that flat
/// tetrahedra and segment-like triangles are answered correctly too.
bool triangle_intersects_tetrahedron(const TriangleCorners& t, const TetrahedronCorners& q);

}  // namespace citymesh
