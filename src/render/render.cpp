// SPDX-License-Identifier: MIT
// Orthographic ray casting through the Embree-backed RayScene.
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>

#include "citymesh/core/error.h"
#include "citymesh/core/parallel.h"
#include "citymesh/render/render.h"
#include "citymesh/spatial/ray_scene.h"

namespace citymesh {

namespace {

struct Flattened {
  Vec3d origin;
  std::vector<Vec3f> vertices;
  std::vector<Triangle> triangles;
  std::vector<Rgb8> colors;
  Box3d box;  ///< relative to origin
};

Flattened flatten(std::span<const RenderLayer> layers) {
  Flattened f;
  if (!layers.empty()) f.origin = layers.front().mesh->origin;
  for (const RenderLayer& l : layers) {
    if (l.face_colors.size() != l.mesh->triangle_count()) {
      throw ProcessingError(fmt::format("render: {} colours for {} triangles", l.face_colors.size(),
                                        l.mesh->triangle_count()));
    }
    const auto base = static_cast<std::uint32_t>(f.vertices.size());
    const Vec3f shift(l.mesh->origin - f.origin);
    for (const Vec3f& p : l.mesh->positions) {
      f.vertices.push_back(p + shift);
      f.box.extend(Vec3d(p + shift));
    }
    for (const Triangle& t : l.mesh->triangles) f.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
    f.colors.insert(f.colors.end(), l.face_colors.begin(), l.face_colors.end());
  }
  return f;
}

struct Camera {
  Vec3d forward, right, up;
  double u0 = 0, v1 = 0, pixel = 0.1, depth0 = 0;
  std::uint32_t width = 1, height = 1;
};

Camera make_camera(const Box3d& box, const ViewParams& p) {
  const double el = p.elevation_deg * M_PI / 180.0, az = p.azimuth_deg * M_PI / 180.0;
  Camera c;
  c.forward = {std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), -std::sin(el)};
  const Vec3d world_up = std::abs(std::sin(el)) > 0.999 ? Vec3d{-std::sin(az), std::cos(az), 0} : Vec3d{0, 0, 1};
  c.right = cross(c.forward, world_up);
  c.right = c.right / norm(c.right);
  c.up = cross(c.right, c.forward);
  double u0 = 1e300, u1 = -1e300, v0 = 1e300, v1 = -1e300, d0 = 1e300;
  for (int corner = 0; corner < 8; ++corner) {
    const Vec3d q{corner & 1 ? box.max.x : box.min.x, corner & 2 ? box.max.y : box.min.y,
                  corner & 4 ? box.max.z : box.min.z};
    u0 = std::min(u0, dot(q, c.right));
    u1 = std::max(u1, dot(q, c.right));
    v0 = std::min(v0, dot(q, c.up));
    v1 = std::max(v1, dot(q, c.up));
    d0 = std::min(d0, dot(q, c.forward));
  }
  c.pixel = std::max({p.pixel_size, (u1 - u0) / p.max_side, (v1 - v0) / p.max_side});
  c.width = static_cast<std::uint32_t>(std::ceil((u1 - u0) / c.pixel)) + 1;
  c.height = static_cast<std::uint32_t>(std::ceil((v1 - v0) / c.pixel)) + 1;
  c.u0 = u0;
  c.v1 = v1;
  c.depth0 = d0 - 1.0;
  return c;
}

Rgb8 shade(Rgb8 color, const Flattened& f, std::uint32_t triangle, const Vec3d& forward) {
  const Triangle& t = f.triangles[triangle];
  const Vec3d n = cross(Vec3d(f.vertices[t[1]] - f.vertices[t[0]]), Vec3d(f.vertices[t[2]] - f.vertices[t[0]]));
  const double lambert = std::abs(dot(n, forward)) / std::max(norm(n), 1e-12);
  const double k = 0.35 + 0.65 * lambert;
  return {static_cast<std::uint8_t>(color.r * k), static_cast<std::uint8_t>(color.g * k),
          static_cast<std::uint8_t>(color.b * k)};
}

}  // namespace

Image render_orthographic(std::span<const RenderLayer> layers, const ViewParams& params) {
  const Flattened f = flatten(layers);
  Image image;
  if (f.triangles.empty()) return image;
  const Camera cam = make_camera(f.box, params);
  const RayScene scene(f.vertices, f.triangles);
  image.width = cam.width;
  image.height = cam.height;
  image.pixels.assign(std::size_t(cam.width) * cam.height, params.background);
  const Vec3f dir(cam.forward);
  const float far = static_cast<float>(norm(f.box.max - f.box.min) + 2.0);
  parallel_for_blocks(cam.height, 16, [&](std::size_t begin, std::size_t end) {
    for (std::size_t row = begin; row < end; ++row) {
      for (std::uint32_t col = 0; col < cam.width; ++col) {
        const double u = cam.u0 + (col + 0.5) * cam.pixel, v = cam.v1 - (static_cast<double>(row) + 0.5) * cam.pixel;
        const Vec3f origin(cam.right * u + cam.up * v + cam.forward * cam.depth0);
        const RayHit hit = scene.intersect(origin, dir, far);
        if (hit.hit) image.pixels[row * cam.width + col] = shade(f.colors[hit.triangle], f, hit.triangle, cam.forward);
      }
    }
  });
  return image;
}

Rgb8 palette_color(std::uint32_t index) {
  static constexpr std::array<Rgb8, 12> kPalette{{{141, 160, 180}, {214, 96, 77}, {90, 160, 90}, {240, 180, 60},
                                                   {120, 100, 200}, {70, 170, 200}, {230, 120, 180}, {160, 120, 70},
                                                   {40, 100, 60}, {200, 200, 80}, {120, 120, 120}, {250, 140, 40}}};
  return kPalette[index % kPalette.size()];
}

}  // namespace citymesh
