// SPDX-License-Identifier: MIT
// "Is there a triangle of this mesh within d of that point?" - the measurements of the
// mosaic's evaluation (coverage, overlap, seams) and of stitching.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <span>

#include "citymesh/core/mesh.h"

namespace citymesh {

class BoxTree;

class MeshProximity {
 public:
  /// Indexes the triangles of `mesh` (kept by reference: it must outlive this) for queries
  /// of reach up to `max_reach` metres.
  MeshProximity(const Mesh& mesh, double max_reach);
  ~MeshProximity();
  MeshProximity(const MeshProximity&) = delete;
  MeshProximity& operator=(const MeshProximity&) = delete;

  /// True when a triangle t with accept(t) lies within `reach` (<= max_reach) of p (a point
  /// in the mesh's local frame). Thread-safe.
  [[nodiscard]] bool any_within(const Vec3d& p, double reach,
                                const std::function<bool(std::uint32_t)>& accept = {}) const;
  /// any_within(points[i], reach) into within[i] for each point, in packets of neighbouring
  /// points that share one walk down the index (pass points close together, such as a
  /// mesh's triangles in order). Thread-safe.
  void any_within_each(std::span<const Vec3d> points, double reach, std::span<std::uint8_t> within) const;
  /// True when p lies within `reach` of the plane of a triangle t with accept(t) and projects
  /// inside it (edges included): p is on that triangle, not merely beside it.
  [[nodiscard]] bool any_over(const Vec3d& p, double reach, const std::function<bool(std::uint32_t)>& accept = {}) const;

 private:
  const Mesh& mesh_;
  std::unique_ptr<BoxTree> tree_;
};

}  // namespace citymesh
