// SPDX-License-Identifier: MIT
// The only source that includes nanoflann.
#include "citymesh/spatial/kd_tree.h"

#include <algorithm>
#include <cmath>
#include <nanoflann.hpp>

namespace citymesh {

namespace {
struct PointCloud {
  std::vector<Vec3f> points;
  [[nodiscard]] std::size_t kdtree_get_point_count() const { return points.size(); }
  [[nodiscard]] float kdtree_get_pt(std::size_t i, std::size_t dim) const { return points[i][static_cast<int>(dim)]; }
  template <class Box>
  bool kdtree_get_bbox(Box& /*box*/) const { return false; }
};
using Tree = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<float, PointCloud>, PointCloud, 3,
                                                 std::uint32_t>;
}  // namespace

struct PointKdTree::Impl {
  explicit Impl(std::vector<Vec3f> points)
      : cloud{std::move(points)}, tree(3, cloud, nanoflann::KDTreeSingleIndexAdaptorParams(16)) {
    tree.buildIndex();
  }
  PointCloud cloud;
  Tree tree;
};

PointKdTree::PointKdTree(std::vector<Vec3f> points) : impl_(std::make_unique<Impl>(std::move(points))) {}
PointKdTree::~PointKdTree() = default;

std::size_t PointKdTree::size() const { return impl_->cloud.points.size(); }

namespace {
/// Collects indices straight into the caller's vector (no pairs, no per-query allocation).
struct IndexCollector {
  float radius_sq;
  std::vector<std::uint32_t>& out;
  [[nodiscard]] std::size_t size() const { return out.size(); }
  [[nodiscard]] bool full() const { return true; }
  bool addPoint(float dist_sq, std::uint32_t index) {
    if (dist_sq <= radius_sq) out.push_back(index);
    return true;
  }
  [[nodiscard]] float worstDist() const { return radius_sq; }
};
}  // namespace

void PointKdTree::radius_search(const Vec3f& query, float radius, std::vector<std::uint32_t>& out, bool sorted) const {
  out.clear();
  if (size() == 0) return;
  const float q[3] = {query.x, query.y, query.z};
  nanoflann::SearchParams params;
  params.sorted = false;
  // The search prunes cells farther than worstDist(); nudged up so the bound is inclusive.
  IndexCollector collect{std::nextafter(radius * radius, INFINITY), out};
  impl_->tree.radiusSearchCustomCallback(q, collect, params);
  if (sorted) std::sort(out.begin(), out.end());
}

std::vector<std::uint32_t> PointKdTree::nearest(const Vec3f& query, std::size_t k) const {
  k = std::min(k, size());
  std::vector<std::uint32_t> indices(k);
  std::vector<float> distances(k);
  const float q[3] = {query.x, query.y, query.z};
  k = impl_->tree.knnSearch(q, k, indices.data(), distances.data());
  std::vector<std::pair<float, std::uint32_t>> order;
  for (std::size_t i = 0; i < k; ++i) order.emplace_back(distances[i], indices[i]);
  std::sort(order.begin(), order.end());
  for (std::size_t i = 0; i < k; ++i) indices[i] = order[i].second;
  indices.resize(k);
  return indices;
}

}  // namespace citymesh
