// SPDX-License-Identifier: MIT
// The rasteriser against ray casting through every pixel centre (Embree, which drew the
// pictures before), on random overlapping triangles seen from above; shared edges leave no
// gaps; the picture does not depend on the thread count.
#include "citymesh/render/render.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "citymesh/core/parallel.h"
#include "citymesh/spatial/ray_scene.h"

namespace citymesh {
namespace {

/// Random triangles of many sizes, tilted, at random heights, overlapping, far from the origin
/// of the CRS as a city's are.
Mesh random_triangles(std::uint32_t count, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> where(0.0f, 10.0f), size(0.02f, 2.0f), height(0.0f, 5.0f);
  Mesh m;
  m.origin = {651234.5, 6862345.25, 40.0};
  for (std::uint32_t t = 0; t < count; ++t) {
    const float x = where(rng), y = where(rng), s = size(rng);
    const auto base = static_cast<std::uint32_t>(m.positions.size());
    for (int k = 0; k < 3; ++k) {
      m.positions.push_back({x + s * (where(rng) / 10 - 0.5f), y + s * (where(rng) / 10 - 0.5f), height(rng)});
    }
    m.triangles.push_back({base, base + 1, base + 2});
  }
  return m;
}

std::vector<Rgb8> distinct_colors(std::size_t n) {
  std::vector<Rgb8> c(n);
  for (std::size_t t = 0; t < n; ++t) {
    c[t] = {static_cast<std::uint8_t>(40 + t % 200), static_cast<std::uint8_t>(40 + (t / 200) % 200),
            static_cast<std::uint8_t>(100 + t % 7)};
  }
  return c;
}

/// The picture seen from straight above, by a ray down through each pixel centre.
Image ray_cast_from_above(const Mesh& m, const std::vector<Rgb8>& colors, double pixel) {
  Box3d box;
  for (const Vec3f& p : m.positions) box.extend(Vec3d(p));
  const RayScene scene(m.positions, m.triangles);
  Image image;
  image.width = static_cast<std::uint32_t>(std::ceil((box.max.x - box.min.x) / pixel)) + 1;
  image.height = static_cast<std::uint32_t>(std::ceil((box.max.y - box.min.y) / pixel)) + 1;
  image.pixels.assign(std::size_t(image.width) * image.height, Rgb8{255, 255, 255});
  for (std::uint32_t row = 0; row < image.height; ++row) {
    for (std::uint32_t col = 0; col < image.width; ++col) {
      const Vec3f origin(Vec3d{box.min.x + (col + 0.5) * pixel, box.max.y - (row + 0.5) * pixel, box.max.z + 2});
      const RayHit hit = scene.intersect(origin, {0, 0, -1}, 100.0f);
      if (!hit.hit) continue;
      const std::array<Vec3d, 3> c = m.corners(hit.triangle);
      const Vec3d n = cross(c[1] - c[0], c[2] - c[0]);
      const double k = 0.35 + 0.65 * std::abs(n.z) / std::max(norm(n), 1e-12);  // as render.h describes
      const Rgb8 base = colors[hit.triangle];
      image.pixels[std::size_t(row) * image.width + col] = {static_cast<std::uint8_t>(base.r * k),
                                                            static_cast<std::uint8_t>(base.g * k),
                                                            static_cast<std::uint8_t>(base.b * k)};
    }
  }
  return image;
}

std::size_t differing_pixels(const Image& a, const Image& b) {
  std::size_t n = 0;
  for (std::size_t i = 0; i < a.pixels.size(); ++i) {
    n += a.pixels[i].r != b.pixels[i].r || a.pixels[i].g != b.pixels[i].g || a.pixels[i].b != b.pixels[i].b;
  }
  return n;
}

TEST(Render, FromAboveShowsWhatARayThroughEachPixelCentreHitsFirst) {
  for (const std::uint32_t seed : {1u, 2u, 3u}) {
    const Mesh m = random_triangles(1500, seed);
    RenderLayer layer{&m, distinct_colors(m.triangle_count())};
    ViewParams view;
    view.pixel_size = 0.02;
    const Image drawn = render_orthographic(std::span<const RenderLayer>(&layer, 1), view);
    const Image expected = ray_cast_from_above(m, layer.face_colors, view.pixel_size);
    ASSERT_EQ(drawn.width, expected.width);
    ASSERT_EQ(drawn.height, expected.height);
    std::size_t covered = 0;
    for (const Rgb8& p : expected.pixels) covered += !(p.r == 255 && p.g == 255 && p.b == 255);
    EXPECT_GT(covered, expected.pixels.size() / 2) << "the scene covers most of the picture";
    // Only pixel centres within float rounding of an edge may differ (the ray caster works in
    // floats): a few in a million.
    EXPECT_LE(differing_pixels(drawn, expected), expected.pixels.size() / 10000) << "seed " << seed;
  }
}

/// A tilted grid of triangles sharing edges over [0, n] x [0, n] metres, its inner vertices
/// moved by up to `amplitude` (none: pixel centres fall exactly on the diagonals).
Mesh jittered_grid(int n, float amplitude) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> jitter(-amplitude, amplitude);
  Mesh m;
  m.origin = {500000.0, 5000000.0, 0.0};
  for (int j = 0; j <= n; ++j) {
    for (int i = 0; i <= n; ++i) {
      const bool border = i == 0 || j == 0 || i == n || j == n;
      const float x = float(i) + (border ? 0.0f : jitter(rng)), y = float(j) + (border ? 0.0f : jitter(rng));
      m.positions.push_back({x, y, 0.3f * x + 0.1f * y});
    }
  }
  const auto at = [&](int i, int j) { return static_cast<std::uint32_t>(j * (n + 1) + i); };
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      m.triangles.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
      m.triangles.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
    }
  }
  return m;
}

TEST(Render, SharedEdgesLeaveNoGapsAndThreadsDoNotChangeThePicture) {
  for (const float amplitude : {0.0f, 0.3f}) {
    const Mesh m = jittered_grid(40, amplitude);
    RenderLayer layer{&m, std::vector<Rgb8>(m.triangle_count(), Rgb8{10, 200, 30})};
    ViewParams view;
    view.pixel_size = 0.0625;
    Image one, two;
    {
      const ThreadLimit limit(1);
      one = render_orthographic(std::span<const RenderLayer>(&layer, 1), view);
    }
    {
      const ThreadLimit limit(2);
      two = render_orthographic(std::span<const RenderLayer>(&layer, 1), view);
    }
    EXPECT_EQ(differing_pixels(one, two), 0u);
    // Every pixel centre within the grid's square [0, 40]^2 shows the grid.
    std::size_t gaps = 0, inside = 0;
    for (std::uint32_t row = 0; row < one.height; ++row) {
      for (std::uint32_t col = 0; col < one.width; ++col) {
        const double x = (col + 0.5) * view.pixel_size, y = 40 - (row + 0.5) * view.pixel_size;
        if (x <= 0 || x >= 40 || y <= 0 || y >= 40) continue;
        ++inside;
        const Rgb8 p = one.pixels[std::size_t(row) * one.width + col];
        gaps += p.r == 255 && p.g == 255 && p.b == 255;
      }
    }
    EXPECT_GT(inside, 400000u);
    EXPECT_EQ(gaps, 0u) << "jitter " << amplitude;
  }
}

TEST(Render, ObliqueViewsFrameTheSceneAndWallsShowFromTheSide) {
  // A wall (vertical square) seen from above shows nothing; seen at 30 degrees it fills a band.
  Mesh wall;
  wall.positions = {{0, 0, 0}, {10, 0, 0}, {10, 0, 10}, {0, 0, 10}};
  wall.triangles = {{0, 1, 2}, {0, 2, 3}};
  RenderLayer layer{&wall, {Rgb8{200, 0, 0}, Rgb8{200, 0, 0}}};
  ViewParams view;
  view.pixel_size = 0.1;
  const auto red_pixels = [&](const Image& image) {
    std::size_t n = 0;
    for (const Rgb8& p : image.pixels) n += p.g == 0 && p.r > 0;
    return n;
  };
  EXPECT_EQ(red_pixels(render_orthographic(std::span<const RenderLayer>(&layer, 1), view)), 0u);
  view.elevation_deg = 30;
  view.azimuth_deg = 90;  // looking along +y, at the wall's face
  const Image oblique = render_orthographic(std::span<const RenderLayer>(&layer, 1), view);
  // The wall projects to 10 m wide by 10 cos(30) = 8.66 m high: ~100 x 87 pixels.
  EXPECT_NEAR(double(red_pixels(oblique)), 100.0 * 86.6, 300.0);
}

TEST(Render, TrianglesWithANonFiniteCornerAreLeftOut) {
  Mesh m;
  m.positions = {{0, 0, 0}, {4, 0, 0}, {0, 4, 0}, {std::nanf(""), 1, 0}, {4, 4, 0}};
  m.triangles = {{0, 1, 2}, {1, 3, 4}};
  RenderLayer layer{&m, {Rgb8{0, 0, 200}, Rgb8{200, 0, 0}}};
  ViewParams view;
  view.pixel_size = 0.1;
  const Image image = render_orthographic(std::span<const RenderLayer>(&layer, 1), view);
  std::size_t blue = 0, red = 0;
  for (const Rgb8& p : image.pixels) {
    blue += p.b == 200 && p.r == 0;
    red += p.r == 200 && p.b == 0;
  }
  EXPECT_NEAR(double(blue), 40.0 * 40.0 / 2, 60.0);  // the finite triangle, 8 m^2 at 0.01 m^2 per pixel
  EXPECT_EQ(red, 0u);
}

TEST(OrthographicCanvas, AMeshDrawnInPartsInTheirOwnFramesGivesThePictureOfTheWhole) {
  const Mesh whole = random_triangles(3000, 21);
  const std::vector<Rgb8> colors = distinct_colors(whole.triangle_count());
  const RenderLayer all{&whole, colors};
  ViewParams view;
  view.pixel_size = 0.03;
  const Image expected = render_orthographic(std::span(&all, 1), view);
  // The triangles in three parts, each in a frame of its own whole metres away, drawn in order.
  Box3d box;
  for (const Vec3f& p : whole.positions) box.extend(Vec3d(p));
  OrthographicCanvas canvas(box, whole.origin, view);
  for (std::uint32_t part = 0; part < 3; ++part) {
    Mesh m;
    m.origin = whole.origin + Vec3d{-3.0 * part, 2.0 * part, 1.0};
    const Vec3f shift(whole.origin - m.origin);
    std::vector<Rgb8> c;
    for (std::uint32_t t = part * 1000; t < (part + 1) * 1000; ++t) {
      const auto base = static_cast<std::uint32_t>(m.positions.size());
      for (const std::uint32_t v : whole.triangles[t]) m.positions.push_back(whole.positions[v] + shift);
      m.triangles.push_back({base, base + 1, base + 2});
      c.push_back(colors[t]);
    }
    canvas.draw({&m, c});
  }
  const Image drawn = canvas.take();
  ASSERT_EQ(drawn.width, expected.width);
  ASSERT_EQ(drawn.height, expected.height);
  EXPECT_TRUE(drawn.pixels == expected.pixels);
}

}  // namespace
}  // namespace citymesh
