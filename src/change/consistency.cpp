// SPDX-License-Identifier: MIT
#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <mutex>
#include <numbers>
#include <utility>

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

/// Only triangles reaching farther than this many thresholds are subdivided into samples:
/// a triangle whose corners lie within reach r of its centroid is cut into n x n sub-triangles
/// so that r / n <= the spacing.
constexpr double kSpacingInThresholds = 8.0;
constexpr std::uint32_t kMaxSubdivision = 64;
/// Samples are grouped by how far their sub-triangle reaches (each class at most twice the
/// next one), and each class is searched with its own radius (threshold + its largest reach):
/// dense small triangles near the van are then searched with a small radius.
constexpr int kReachClasses = 6;

/// One kd-tree of samples with a common bound on their reach.
struct SampleClass {
  std::vector<Vec3f> points;
  std::vector<std::uint32_t> owner;  ///< global triangle of each sample
  double reach = 0;                  ///< every point of an owner lies within this of one of its samples
};

/// Centroids of the n x n sub-triangles of a barycentric subdivision (upright and inverted).
void add_samples(const TriangleCorners& c, std::uint32_t n, std::uint32_t owner, SampleClass& s) {
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

struct Samples {
  std::array<SampleClass, kReachClasses> classes;
  std::vector<float> triangle_reach;  ///< per triangle: its corners' largest distance from its centroid
};

Samples sample_triangles(const TriangleFrames& f, double threshold) {
  std::vector<double> reach(f.size());
  Samples s;
  s.triangle_reach.resize(f.size());
  parallel_for_blocks(f.size(), 16384, [&](std::size_t b, std::size_t e) {
    for (std::size_t g = b; g < e; ++g) {
      reach[g] = centroid_reach(f, g);
      s.triangle_reach[g] = static_cast<float>(reach[g] * (1 + 1e-6) + 1e-6);  // rounded up
    }
  });
  const double spacing = kSpacingInThresholds * threshold;
  for (std::size_t g = 0; g < f.size(); ++g) {
    const auto n =
        std::clamp<std::uint32_t>(static_cast<std::uint32_t>(std::ceil(reach[g] / spacing)), 1, kMaxSubdivision);
    const double sample_reach = reach[g] / n;
    // Class k holds reaches in (spacing / 2^(k+1), spacing / 2^k]; the last takes the rest.
    int k = 0;
    while (k + 1 < kReachClasses && sample_reach <= spacing / double(2 << k)) ++k;
    SampleClass& c = s.classes[static_cast<std::size_t>(k)];
    if (n == 1) {
      c.points.push_back(f.centroid[g]);
      c.owner.push_back(static_cast<std::uint32_t>(g));
    } else {
      add_samples(f.corners(g), n, static_cast<std::uint32_t>(g), c);
    }
    c.reach = std::max(c.reach, sample_reach);
  }
  return s;
}

/// T (centroid c) overlaps U: c lies within `threshold` of U's plane and its projection on
/// that plane falls inside U (edges included), i.e. the point-to-triangle distance is at most
/// the threshold and is reached inside U.
bool overlaps(const Vec3d& c, const TriangleFrames& f, std::uint32_t u, double threshold) {
  const TriangleCorners q = f.corners(u);
  const Vec3d n(f.normal[u]);
  const double h = dot(c - q[0], n);
  if (std::abs(h) > threshold) return false;
  const Vec3d p = c - n * h;
  // Inside when p is on the inner side of every edge, measured about the corners' own winding
  // (the stored normal was turned towards the viewpoint, so its sign says nothing of it).
  const Vec3d winding = cross(q[1] - q[0], q[2] - q[0]);
  for (int k = 0; k < 3; ++k) {
    if (dot(cross(q[(k + 1) % 3] - q[k], p - q[k]), winding) < 0) return false;
  }
  return true;
}

/// Arrays of per-triangle marks lent to the blocks running at a time (one per thread at most).
class StampPool {
 public:
  explicit StampPool(std::size_t size) : size_(size) {}
  std::unique_ptr<std::vector<std::uint32_t>> take() {
    const std::lock_guard lock(mutex_);
    if (free_.empty()) return std::make_unique<std::vector<std::uint32_t>>(size_, UINT32_MAX);
    auto s = std::move(free_.back());
    free_.pop_back();
    return s;
  }
  void give(std::unique_ptr<std::vector<std::uint32_t>> s) {
    const std::lock_guard lock(mutex_);
    free_.push_back(std::move(s));
  }

 private:
  std::size_t size_;
  std::mutex mutex_;
  std::vector<std::unique_ptr<std::vector<std::uint32_t>>> free_;
};

}  // namespace

std::vector<TrianglePair> find_consistent_pairs(const TriangleFrames& f, const ChangeParams& params,
                                                ChangeStats& stats) {
  Samples samples = sample_triangles(f, params.distance_threshold);
  std::vector<std::unique_ptr<PointKdTree>> trees;
  std::vector<float> radii;
  for (SampleClass& c : samples.classes) {
    stats.samples += c.points.size();
    radii.push_back(static_cast<float>((params.distance_threshold + c.reach) * (1 + 1e-6) + 1e-6));
    trees.push_back(std::make_unique<PointKdTree>(std::move(c.points)));
  }
  // Per thread: the query that last met each triangle, to test a triangle once per query
  // however many of its samples are hit (the marks are per query, so any thread mapping
  // gives the same pairs).
  StampPool stamps(f.size());
  const auto threshold = static_cast<float>(params.distance_threshold * (1 + 1e-6) + 1e-6);
  const auto cos_min = static_cast<float>(std::cos(params.normal_angle * std::numbers::pi / 180.0) - 1e-6);

  constexpr std::size_t kGrain = 4096;
  std::vector<std::vector<TrianglePair>> per_block((f.size() + kGrain - 1) / kGrain);
  parallel_for_blocks(f.size(), kGrain, [&](std::size_t begin, std::size_t end) {
    std::vector<std::uint32_t> hits;
    std::unique_ptr<std::vector<std::uint32_t>> borrowed = stamps.take();
    std::vector<std::uint32_t>& stamp = *borrowed;
    std::vector<TrianglePair>& out = per_block[begin / kGrain];
    for (std::size_t g = begin; g < end; ++g) {
      const std::uint32_t acq = f.index.acquisition_of(g);
      const std::size_t own_begin = f.index.offsets[acq], own_end = f.index.offsets[acq + 1];
      const Vec3d centroid(f.centroid[g]);
      for (std::size_t k = 0; k < trees.size(); ++k) {
        trees[k]->radius_search(f.centroid[g], radii[k], hits, /*sorted=*/false);
        for (std::uint32_t h : hits) {
          const std::uint32_t u = samples.classes[k].owner[h];
          if (u >= own_begin && u < own_end) continue;                                // same acquisition
          if (std::exchange(stamp[u], static_cast<std::uint32_t>(g)) == g) continue;  // seen through another sample
          if (dot(f.normal[g], f.normal[u]) < cos_min) continue;
          // Cheap necessary condition: the projection can fall inside U only if the centroid is
          // within the threshold plus U's own reach of U's centroid.
          const Vec3f offset = f.centroid[g] - f.centroid[u];
          const float limit = threshold + samples.triangle_reach[u];
          if (dot(offset, offset) > limit * limit) continue;
          if (!overlaps(centroid, f, u, params.distance_threshold)) continue;
          out.emplace_back(std::min<std::uint32_t>(static_cast<std::uint32_t>(g), u),
                           std::max<std::uint32_t>(static_cast<std::uint32_t>(g), u));
        }
      }
    }
    stamps.give(std::move(borrowed));
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
