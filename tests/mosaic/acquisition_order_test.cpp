// SPDX-License-Identifier: MIT
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <numeric>
#include <random>

#include "citymesh/mosaic/mosaic.h"
#include "grid_triangles.h"

namespace citymesh {
namespace {

/// Overlapping flat patches of random extent and resolution, a few millimetres apart in
/// height: every place is offered by several meshes, so the energy must choose.
std::vector<Mesh> random_patches(std::mt19937& rng, int count) {
  std::uniform_real_distribution<float> start(0.0f, 0.8f), step(0.1f, 0.3f);
  std::uniform_int_distribution<int> cells(4, 9);
  std::vector<Mesh> meshes;
  for (int k = 0; k < count; ++k) {
    const float x0 = start(rng), y0 = start(rng), s = step(rng), z = 0.004f * float(k);
    meshes.push_back(test::placed_grid(cells(rng), cells(rng), [=](int i, int j) {
      return Vec3f{x0 + float(i) * s, y0 + float(j) * s, z};
    }));
  }
  return meshes;
}

/// Consistent pairs as the change step lists them, (smaller, larger) global id in ascending
/// order: here, triangles of different meshes whose centroids are within 12 cm.
std::vector<TrianglePair> centroid_pairs(std::span<const Mesh> meshes, const GlobalTriangles& index) {
  std::vector<Vec3d> centroid;
  for (const Mesh& m : meshes) {
    for (std::size_t t = 0; t < m.triangle_count(); ++t) {
      const auto [a, b, c] = m.corners(t);
      centroid.push_back((a + b + c) / 3.0);
    }
  }
  std::vector<TrianglePair> pairs;
  for (std::uint32_t g = 0; g < centroid.size(); ++g) {
    for (std::uint32_t u = g + 1; u < centroid.size(); ++u) {
      if (index.acquisition_of(g) != index.acquisition_of(u) && norm(centroid[g] - centroid[u]) < 0.12) {
        pairs.emplace_back(g, u);
      }
    }
  }
  return pairs;
}

/// The mosaic's selection of `meshes` taken at `dates`, every triangle kept by the change step.
std::vector<std::uint8_t> selection(std::span<const Mesh> meshes, std::span<const TimePoint> dates) {
  ChangeResult change;
  change.index.offsets = {0};
  for (const Mesh& m : meshes) change.index.offsets.push_back(change.index.offsets.back() + m.triangle_count());
  change.kept.assign(change.index.size(), 1);
  change.consistent_pairs = centroid_pairs(meshes, change.index);
  MosaicParams params;
  params.fill_holes = false;  // the fill follows the dates anyway; the solver is what is tested
  return select_mosaic({meshes, dates, &change, 0.1, {}}, params).selected;
}

TEST(MosaicSelection, DoesNotDependOnTheOrderInWhichAcquisitionsAreListed) {
  // A pass delivered late is appended after newer ones in the config: the selection must be
  // the one the date order gives, triangle for triangle. Four meshes, so that the solver
  // makes group moves (two meshes are solved by one exact cut in any order).
  std::mt19937 rng(64);
  int chose_between_meshes = 0;
  for (int scene = 0; scene < 12; ++scene) {
    const std::vector<Mesh> meshes = random_patches(rng, 4);
    std::vector<TimePoint> dates;
    for (int k = 0; k < 4; ++k) dates.emplace_back(std::chrono::days(10 * k + scene));
    std::vector<std::size_t> listed(4);
    std::iota(listed.begin(), listed.end(), 0);
    std::shuffle(listed.begin(), listed.end(), rng);
    if (std::is_sorted(listed.begin(), listed.end())) std::swap(listed[0], listed[3]);
    std::vector<Mesh> shuffled_meshes;
    std::vector<TimePoint> shuffled_dates;
    for (const std::size_t k : listed) {
      shuffled_meshes.push_back(meshes[k]);
      shuffled_dates.push_back(dates[k]);
    }
    const std::vector<std::uint8_t> in_date_order = selection(meshes, dates);
    const std::vector<std::uint8_t> shuffled = selection(shuffled_meshes, shuffled_dates);

    // Global ids of mesh k in date order, and where the shuffled listing put them.
    std::vector<std::size_t> offset(5, 0), shuffled_offset(5, 0);
    for (std::size_t k = 0; k < 4; ++k) offset[k + 1] = offset[k] + meshes[k].triangle_count();
    for (std::size_t k = 0; k < 4; ++k)
      shuffled_offset[k + 1] = shuffled_offset[k] + shuffled_meshes[k].triangle_count();
    std::vector<int> meshes_used(4, 0);
    for (std::size_t place = 0; place < 4; ++place) {
      const std::size_t k = listed[place];
      for (std::size_t t = 0; t < meshes[k].triangle_count(); ++t) {
        ASSERT_EQ(shuffled[shuffled_offset[place] + t], in_date_order[offset[k] + t])
            << "scene " << scene << ", mesh " << k << " listed at " << place << ", triangle " << t;
        meshes_used[k] |= in_date_order[offset[k] + t];
      }
    }
    chose_between_meshes += std::count(meshes_used.begin(), meshes_used.end(), 1) >= 2 ? 1 : 0;
  }
  EXPECT_GE(chose_between_meshes, 6) << "most scenes must mix meshes, or the order could not matter";
}

}  // namespace
}  // namespace citymesh
