// SPDX-License-Identifier: MIT
#include "shapes.h"

#include <array>
#include <cmath>

namespace citymesh::sim {

namespace {
std::uint32_t add_vertex(SceneObject& o, const Vec3f& v) {
  o.vertices.push_back(v);
  return static_cast<std::uint32_t>(o.vertices.size() - 1);
}
}  // namespace

void add_quad(SceneObject& o, const Vec3f& a, const Vec3f& b, const Vec3f& c, const Vec3f& d) {
  const std::uint32_t ia = add_vertex(o, a), ib = add_vertex(o, b), ic = add_vertex(o, c), id = add_vertex(o, d);
  o.triangles.push_back({ia, ib, ic});
  o.triangles.push_back({ia, ic, id});
}

void add_box(SceneObject& o, const Vec3f& lo, const Vec3f& hi, bool bottom) {
  const Vec3f p[8] = {{lo.x, lo.y, lo.z}, {hi.x, lo.y, lo.z}, {hi.x, hi.y, lo.z}, {lo.x, hi.y, lo.z},
                      {lo.x, lo.y, hi.z}, {hi.x, lo.y, hi.z}, {hi.x, hi.y, hi.z}, {lo.x, hi.y, hi.z}};
  add_quad(o, p[4], p[5], p[6], p[7]);  // top
  add_quad(o, p[0], p[1], p[5], p[4]);  // -y
  add_quad(o, p[1], p[2], p[6], p[5]);  // +x
  add_quad(o, p[2], p[3], p[7], p[6]);  // +y
  add_quad(o, p[3], p[0], p[4], p[7]);  // -x
  if (bottom) add_quad(o, p[0], p[3], p[2], p[1]);
}

void add_blob(SceneObject& o, const Vec3f& c, const Vec3f& r) {
  // Octahedron faces, each split into four through its edge midpoints pushed onto the ellipsoid.
  const std::array<Vec3f, 6> axis{{{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}}};
  const int faces[8][3] = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4}, {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
  auto on_surface = [&](Vec3f d) {
    d = d / norm(d);
    return Vec3f{c.x + d.x * r.x, c.y + d.y * r.y, c.z + d.z * r.z};
  };
  for (const auto& f : faces) {
    const Vec3f a = axis[f[0]], b = axis[f[1]], d = axis[f[2]];
    const Vec3f ab = on_surface(a + b), bd = on_surface(b + d), da = on_surface(d + a);
    const Vec3f A = on_surface(a), B = on_surface(b), D = on_surface(d);
    for (const auto& t : {std::array<Vec3f, 3>{A, ab, da}, {ab, B, bd}, {da, bd, D}, {ab, bd, da}}) {
      const std::uint32_t i0 = add_vertex(o, t[0]), i1 = add_vertex(o, t[1]), i2 = add_vertex(o, t[2]);
      o.triangles.push_back({i0, i1, i2});
    }
  }
}

void add_car(SceneObject& o, float x, float y, float length, float width) {
  add_box(o, {x - length / 2, y - width / 2, 0.15f}, {x + length / 2, y + width / 2, 0.95f});
  add_box(o, {x - length / 4, y - width / 2 + 0.1f, 0.95f}, {x + length / 5, y + width / 2 - 0.1f, 1.5f});
  // wheels, so that the body is seen floating above the road like a real car's
  for (float dx : {-length / 2 + 0.7f, length / 2 - 0.7f}) {
    for (float dy : {-width / 2 + 0.1f, width / 2 - 0.3f}) {
      add_box(o, {x + dx - 0.3f, y + dy, 0.0f}, {x + dx + 0.3f, y + dy + 0.2f, 0.15f});
    }
  }
}

}  // namespace citymesh::sim
