// SPDX-License-Identifier: MIT
#include <algorithm>
#include <cmath>
#include <numbers>

#include "citymesh/core/parallel.h"
#include "citymesh/spatial/kd_tree.h"
#include "frames.h"

namespace citymesh::change_detail {

namespace {

/// Largest distance from a triangle's centroid to its corners: a sample at the centroid of a
/// sub-triangle 1/n the size covers every point of it within this / n.
double centroid_reach(const TriangleFrames& f, std::size_t g) {
  const TriangleCorners c = f.corners(g);
  const Vec3d m(f.centroid[g]);
  double r = 0;
  for (const Vec3d& p : c) r = std::max(r, norm(p - m));
  return r;
}

/// The sample spacing: the reach of the coarser triangles (90th percentile), so most
/// triangles need a single sample and the few long ones are subdivided.
double sample_spacing(const std::vector<double>& reach, double threshold) {
  if (reach.empty()) return threshold;
  std::vector<double> sorted = reach;
  const auto q = sorted.begin() + static_cast<std::ptrdiff_t>(sorted.size() * 9 / 10);
  std::nth_element(sorted.begin(), q, sorted.end());
  return std::clamp(*q, threshold / 2, 2.0);
}

constexpr std::uint32_t kMaxSubdivision = 64;

struct Samples {
  std::vector<Vec3f> points;
  std::vector<std::uint32_t> owner;  ///< global triangle of each sample, non-decreasing
  double reach = 0;                  ///< every triangle point lies within this of a sample
};

/// Centroids of the n x n sub-triangles of a barycentric subdivision (upright and inverted).
void add_samples(const TriangleCorners& c, std::uint32_t n, std::uint32_t owner, Samples& s) {
  const Vec3d e1 = c[1] - c[0], e2 = c[2] - c[0];
  const double inv = 1.0 / n;
  for (std::uint32_t i = 0; i < n; ++i) {
    for (std::uint32_t j = 0; i + j < n; ++j) {
      s.points.push_back(Vec3f(c[0] + e1 * ((i + 1.0 / 3) * inv) + e2 * ((j + 1.0 / 3) * inv)));
      s.owner.push_back(owner);
      if (i + j + 2 <= n) {
        s.points.push_back(Vec3f(c[0] + e1 * ((i + 2.0 / 3) * inv) + e2 * ((j + 2.0 / 3) * inv)));
        s.owner.push_back(owner);
      }
    }
  }
}

Samples sample_triangles(const TriangleFrames& f, double threshold) {
  std::vector<double> reach(f.size());
  parallel_for_blocks(f.size(), 16384, [&](std::size_t b, std::size_t e) {
    for (std::size_t g = b; g < e; ++g) reach[g] = centroid_reach(f, g);
  });
  const double spacing = sample_spacing(reach, threshold);
  Samples s;
  s.points.reserve(f.size() + f.size() / 4);
  s.owner.reserve(f.size() + f.size() / 4);
  for (std::size_t g = 0; g < f.size(); ++g) {
    const auto n = std::clamp<std::uint32_t>(static_cast<std::uint32_t>(std::ceil(reach[g] / spacing)), 1, kMaxSubdivision);
    if (n == 1) {
      s.points.push_back(f.centroid[g]);
      s.owner.push_back(static_cast<std::uint32_t>(g));
    } else {
      add_samples(f.corners(g), n, static_cast<std::uint32_t>(g), s);
    }
    s.reach = std::max(s.reach, reach[g] / n);
  }
  return s;
}

}  // namespace

std::vector<TrianglePair> find_consistent_pairs(const TriangleFrames& f, const ChangeParams& params,
                                                ChangeStats& stats) {
  Samples samples = sample_triangles(f, params.distance_threshold);
  stats.samples = samples.points.size();
  const double reach = samples.reach;
  const PointKdTree tree(std::move(samples.points));
  const auto radius = static_cast<float>((params.distance_threshold + reach) * (1 + 1e-6) + 1e-6);
  const double d_sq = params.distance_threshold * params.distance_threshold;
  const auto cos_min = static_cast<float>(std::cos(params.normal_angle * std::numbers::pi / 180.0) - 1e-6);

  constexpr std::size_t kGrain = 4096;
  std::vector<std::vector<TrianglePair>> per_block((f.size() + kGrain - 1) / kGrain);
  parallel_for_blocks(f.size(), kGrain, [&](std::size_t begin, std::size_t end) {
    std::vector<std::uint32_t> hits;
    std::vector<TrianglePair>& out = per_block[begin / kGrain];
    for (std::size_t g = begin; g < end; ++g) {
      const std::uint32_t acq = f.index.acquisition_of(g);
      const std::size_t own_begin = f.index.offsets[acq], own_end = f.index.offsets[acq + 1];
      const Vec3d centroid(f.centroid[g]);
      tree.radius_search(f.centroid[g], radius, hits);
      std::uint32_t previous = UINT32_MAX;
      for (std::uint32_t h : hits) {
        const std::uint32_t u = samples.owner[h];
        if (u == previous || (u >= own_begin && u < own_end)) continue;  // same triangle, or same acquisition
        previous = u;
        if (dot(f.normal[g], f.normal[u]) < cos_min) continue;
        if (point_triangle_distance_sq(centroid, f.corners(u)) > d_sq) continue;
        out.emplace_back(std::min<std::uint32_t>(static_cast<std::uint32_t>(g), u),
                         std::max<std::uint32_t>(static_cast<std::uint32_t>(g), u));
      }
    }
    std::sort(out.begin(), out.end());
  });
  std::vector<TrianglePair> pairs;
  std::size_t total = 0;
  for (const auto& b : per_block) total += b.size();
  pairs.reserve(total);
  for (auto& b : per_block) {
    pairs.insert(pairs.end(), b.begin(), b.end());
    std::vector<TrianglePair>().swap(b);
  }
  std::sort(pairs.begin(), pairs.end());
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
  pairs.shrink_to_fit();
  stats.consistent_pairs = pairs.size();
  return pairs;
}

}  // namespace citymesh::change_detail
