// SPDX-License-Identifier: MIT
// Appends simple closed shapes to an object's triangle list.
#pragma once

#include "citymesh/sim/scene.h"

namespace citymesh::sim {

/// Quad a-b-c-d (counter-clockwise seen from the side its normal points to) as two triangles.
void add_quad(SceneObject& o, const Vec3f& a, const Vec3f& b, const Vec3f& c, const Vec3f& d);
/// Axis-aligned box [lo, hi]; `bottom` false leaves the face on the ground out.
void add_box(SceneObject& o, const Vec3f& lo, const Vec3f& hi, bool bottom = false);
/// Regular-ish blob (an octahedron subdivided once) around `centre`, for tree crowns.
void add_blob(SceneObject& o, const Vec3f& centre, const Vec3f& radii);
/// A car: body box plus a narrower cabin on top, centred at (x, y), `along_x` its heading.
void add_car(SceneObject& o, float x, float y, float length, float width);

}  // namespace citymesh::sim
