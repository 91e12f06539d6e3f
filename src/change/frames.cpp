// SPDX-License-Identifier: MIT
#include "frames.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "citymesh/core/error.h"
#include "citymesh/core/parallel.h"

namespace citymesh {

std::string_view unconfirmed_policy_name(UnconfirmedPolicy p) {
  switch (p) {
    case UnconfirmedPolicy::drop:
      return "drop";
    case UnconfirmedPolicy::keep:
      return "keep";
    default:
      return "keep-unobserved";
  }
}

std::string_view empty_space_reach_name(EmptySpaceReach r) {
  return r == EmptySpaceReach::nearest_sample ? "nearest-sample" : "tetrahedron";
}

std::string_view triangle_state_name(TriangleState s) {
  switch (s) {
    case TriangleState::consistent:
      return "consistent";
    case TriangleState::conflicting:
      return "conflicting";
    default:
      return "single";
  }
}

namespace change_detail {

namespace {

void check_input(const ChangeInput& input) {
  if (input.meshes.size() != input.dates.size()) {
    throw ProcessingError(
        fmt::format("change detection: {} meshes but {} dates", input.meshes.size(), input.dates.size()));
  }
  for (std::size_t a = 0; a < input.meshes.size(); ++a) {
    const Mesh& m = input.meshes[a];
    m.check_invariants();
    if (m.triangle_count() > 0 && !m.has_sensor_positions()) {
      throw ProcessingError(fmt::format("change detection: acquisition {} has no sensor positions", a));
    }
    if (!(m.origin == input.meshes.front().origin)) {
      throw ProcessingError(fmt::format("change detection: acquisition {} has another local origin", a));
    }
  }
  std::size_t total = 0;
  for (const Mesh& m : input.meshes) total += m.triangle_count();
  if (total >= (std::size_t{1} << 32)) {
    throw ProcessingError(
        fmt::format("change detection: {} triangles in one set (at most 2^32 - 1; use tiles)", total));
  }
  if (!input.uses.empty() && input.uses.size() != total) {
    throw ProcessingError(fmt::format("change detection: {} triangle uses for {} triangles", input.uses.size(), total));
  }
}

}  // namespace

TriangleCorners TriangleFrames::corners(std::size_t g) const {
  const std::array<Vec3f, 3>& c = corner[g];
  return {Vec3d(c[0]), Vec3d(c[1]), Vec3d(c[2])};
}

TetrahedronCorners TriangleFrames::empty_space(std::size_t g) const {
  const TriangleCorners c = corners(g);
  const Vec3d v(viewpoint[g]);
  const double s = empty_scale[g];
  return {v, v + (c[0] - v) * s, v + (c[1] - v) * s, v + (c[2] - v) * s};
}

namespace {
/// b padded by a hair so that rounding to float never loses a touching pair.
Box3f padded(Box3d b) {
  const double pad = 1e-5 + 1e-6 * std::max({std::abs(b.min.x), std::abs(b.min.y), std::abs(b.min.z), std::abs(b.max.x),
                                             std::abs(b.max.y), std::abs(b.max.z)});
  b = b.grown(pad);
  return {Vec3f(b.min), Vec3f(b.max)};
}
}  // namespace

double empty_space_scale(const TriangleCorners& c, const Vec3d& viewpoint, double height, const ChangeParams& params) {
  const double margin = params.conflict_margin;
  if (!(height > margin)) return 0.0;
  double scale = (height - margin) / height;
  if (params.empty_space == EmptySpaceReach::nearest_sample) {
    const double r0 = norm(c[0] - viewpoint), r1 = norm(c[1] - viewpoint), r2 = norm(c[2] - viewpoint);
    // Every point of the tetrahedron scaled by s lies within s * (farthest corner's range).
    scale = std::min(scale, std::max(0.0, (std::min({r0, r1, r2}) - margin) / std::max({r0, r1, r2})));
  }
  return scale;
}

int slab_count(const TetrahedronCorners& q, double length) {
  const double reach = std::max({norm(q[1] - q[0]), norm(q[2] - q[0]), norm(q[3] - q[0])});
  return static_cast<int>(std::clamp(std::ceil(reach / length), 1.0, 100000.0));
}

EmptySpaceSlabs::EmptySpaceSlabs(const TetrahedronCorners& q) : apex_(q[0]), low_(q[1] - q[0]), high_(low_) {
  for (std::size_t i = 2; i < 4; ++i) {
    const Vec3d d = q[i] - q[0];
    low_ = {std::min(low_.x, d.x), std::min(low_.y, d.y), std::min(low_.z, d.z)};
    high_ = {std::max(high_.x, d.x), std::max(high_.y, d.y), std::max(high_.z, d.z)};
  }
}

Box3f EmptySpaceSlabs::between(double s0, double s1) const {
  Box3d b;
  for (int a = 0; a < 3; ++a) {
    b.min[a] = std::min(apex_[a] + low_[a] * s0, apex_[a] + low_[a] * s1);
    b.max[a] = std::max(apex_[a] + high_[a] * s0, apex_[a] + high_[a] * s1);
  }
  return padded(b);
}

TriangleFrames prepare_triangles(const ChangeInput& input, const ChangeParams& params) {
  check_input(input);
  TriangleFrames f;
  f.dates.assign(input.dates.begin(), input.dates.end());
  f.index.offsets.assign(1, 0);
  for (const Mesh& m : input.meshes) f.index.offsets.push_back(f.index.offsets.back() + m.triangle_count());
  const std::size_t n = f.index.size();
  f.corner.resize(n);
  f.centroid.resize(n);
  f.normal.resize(n);
  f.viewpoint.resize(n);
  f.empty_scale.resize(n);
  f.box.resize(n);
  f.use.assign(input.uses.begin(), input.uses.end());
  for (std::size_t a = 0; a < input.meshes.size(); ++a) {
    const Mesh& m = input.meshes[a];
    const std::size_t base = f.index.offsets[a];
    parallel_for_blocks(m.triangle_count(), 8192, [&](std::size_t begin, std::size_t end) {
      for (std::size_t t = begin; t < end; ++t) {
        const Triangle& tri = m.triangles[t];
        const std::size_t g = base + t;
        f.corner[g] = {m.positions[tri[0]], m.positions[tri[1]], m.positions[tri[2]]};
        const Vec3d p0(f.corner[g][0]), p1(f.corner[g][1]), p2(f.corner[g][2]);
        const Vec3d c = (p0 + p1 + p2) / 3.0;
        const Vec3d v = m.viewpoint(t);
        Vec3d normal = cross(p1 - p0, p2 - p0);
        const double len = norm(normal);
        normal = len > 0 ? normal / len : Vec3d{0, 0, 0};
        double h = dot(v - p0, normal);  // viewpoint height above the plane
        if (h < 0) {
          normal = normal * -1.0;
          h = -h;
        }
        f.centroid[g] = Vec3f(c);
        f.normal[g] = Vec3f(normal);
        f.viewpoint[g] = Vec3f(v);
        f.empty_scale[g] = static_cast<float>(empty_space_scale({p0, p1, p2}, v, h, params));
        Box3d box;
        for (const Vec3d& p : {p0, p1, p2}) box.extend(p);
        f.box[g] = padded(box);
      }
    });
  }
  return f;
}

PartnerBits partner_bits(const TriangleFrames& frames, const PackedPairs& pairs) {
  PartnerBits p;
  p.words = (frames.acquisitions() + 63) / 64;
  p.bits.assign(frames.size() * p.words, 0);
  std::size_t ja = 0;  // a's acquisition, found by walking: the pairs come sorted by a
  for (const auto& [a, b] : pairs) {
    while (a >= frames.index.offsets[ja + 1]) ++ja;
    const std::size_t jb = frames.index.acquisition_of(b);
    p.bits[a * p.words + jb / 64] |= std::uint64_t{1} << (jb % 64);
    p.bits[b * p.words + ja / 64] |= std::uint64_t{1} << (ja % 64);
  }
  return p;
}

}  // namespace change_detail
}  // namespace citymesh
