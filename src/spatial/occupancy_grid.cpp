// SPDX-License-Identifier: MIT
// The only source that includes OpenVDB (its headers cost ~13 s of compile time per file).
#include "citymesh/spatial/occupancy_grid.h"

#include <fmt/format.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/FindActiveValues.h>

#include <array>
#include <cmath>
#include <mutex>

#include "citymesh/core/error.h"

namespace citymesh {

namespace {

void initialise_openvdb() {
  static std::once_flag once;
  std::call_once(once, [] { openvdb::initialize(); });
}

/// The voxel holding p: the rounding of voxel_box, which marks and queries share.
openvdb::Coord voxel_of(const Vec3f& p, double inverse_size) {
  const VoxelBox v = voxel_box(p, p, inverse_size);
  return {v.lo[0], v.lo[1], v.lo[2]};
}

openvdb::CoordBBox coord_box(const VoxelBox& v) {
  return {openvdb::Coord(v.lo[0], v.lo[1], v.lo[2]), openvdb::Coord(v.hi[0], v.hi[1], v.hi[2])};
}

/// Up to this many voxels a box query asks each voxel through the cached accessor; above it,
/// it descends the tree's node masks.
constexpr std::int64_t kDenseQueryLimit = 4096;
/// Boxes remembered to skip marking the same box twice in a row.
constexpr std::size_t kRecentBoxes = 1024;

std::size_t box_slot(const openvdb::CoordBBox& b) {
  std::uint64_t h = 1469598103934665603ull;
  for (const openvdb::Int32 v : {b.min().x(), b.min().y(), b.min().z(), b.max().x(), b.max().y(), b.max().z()}) {
    h = (h ^ static_cast<std::uint32_t>(v)) * 1099511628211ull;
  }
  return static_cast<std::size_t>(h % kRecentBoxes);
}

/// Up to this many voxels a box is marked voxel by voxel, above it by a sparse fill.
constexpr std::int64_t kSmallBoxVoxels = 64;

}  // namespace

struct OccupancyGrid::Impl {
  double size = 1.0;
  double inverse_size = 1.0;  ///< 1 / size: voxel_of multiplies
  openvdb::BoolGrid::Ptr grid;
  openvdb::BoolGrid::Accessor accessor;  ///< caches the last nodes marked (not thread-safe, like marking)
  std::array<openvdb::CoordBBox, kRecentBoxes> recent;  ///< boxes marked lately, by box_slot
  Impl(double voxel_size, openvdb::BoolGrid::Ptr g)
      : size(voxel_size), inverse_size(inverse_of(voxel_size)), grid(std::move(g)), accessor(grid->getAccessor()) {}
};

namespace {
double checked_voxel_size(double voxel_size) {
  if (!(voxel_size > 0) || !std::isfinite(voxel_size)) {
    throw ProcessingError(fmt::format("occupancy grid: voxel size {} must be positive", voxel_size));
  }
  initialise_openvdb();
  return voxel_size;
}
}  // namespace

OccupancyGrid::OccupancyGrid(double voxel_size)
    : impl_(std::make_unique<Impl>(checked_voxel_size(voxel_size), openvdb::BoolGrid::create(false))) {}

OccupancyGrid::~OccupancyGrid() = default;
OccupancyGrid::OccupancyGrid(OccupancyGrid&&) noexcept = default;
OccupancyGrid& OccupancyGrid::operator=(OccupancyGrid&&) noexcept = default;

double OccupancyGrid::voxel_size() const { return impl_->size; }

void OccupancyGrid::mark_point(const Vec3f& p) { impl_->accessor.setValueOn(voxel_of(p, impl_->inverse_size), true); }

void OccupancyGrid::mark_box(const Vec3f& lo, const Vec3f& hi) { mark_voxels(voxel_box(lo, hi, impl_->inverse_size)); }

void OccupancyGrid::mark_voxels(const VoxelBox& voxels) {
  const openvdb::CoordBBox box = coord_box(voxels);
  // Neighbouring triangles seen from nearby viewpoints mark the same voxel boxes over and
  // over: remember recent boxes and skip repeats.
  openvdb::CoordBBox& recent = impl_->recent[box_slot(box)];
  if (recent == box) return;
  recent = box;
  if (static_cast<std::int64_t>(box.volume()) > kSmallBoxVoxels) {
    impl_->grid->tree().sparseFill(box, true, true);
    return;
  }
  // A few voxels: setting them one by one through the cached accessor beats a fill's descent.
  for (auto it = box.begin(); it; ++it) impl_->accessor.setValueOn(*it, true);
}

bool OccupancyGrid::occupied(const Vec3f& p) const {
  return impl_->grid->tree().isValueOn(voxel_of(p, impl_->inverse_size));
}

namespace {

/// Whether any voxel of `box` is on, through `access` (its cache kept for the next query).
bool any_on(const openvdb::BoolGrid& grid, openvdb::BoolGrid::ConstAccessor& access, const openvdb::CoordBBox& box) {
  if (static_cast<std::int64_t>(box.volume()) <= kDenseQueryLimit) {
    for (auto it = box.begin(); it; ++it) {
      if (access.isValueOn(*it)) return true;
    }
    return false;
  }
  // Only the nodes the box meets: walking every active value of the grid instead made each
  // query cost the whole grid (with 5 cm voxels, a street's change step went 0.3 -> 21 s).
  return openvdb::tools::anyActiveValues(grid.tree(), box);  // voxels and active tiles alike
}

}  // namespace

bool OccupancyGrid::any_in_box(const Vec3f& lo, const Vec3f& hi) const {
  openvdb::BoolGrid::ConstAccessor access = impl_->grid->getConstAccessor();
  return any_on(*impl_->grid, access, coord_box(voxel_box(lo, hi, impl_->inverse_size)));
}

struct OccupancyGrid::Reader::Impl {
  const OccupancyGrid::Impl& grid;
  openvdb::BoolGrid::ConstAccessor access;
  explicit Impl(const OccupancyGrid::Impl& g) : grid(g), access(g.grid->getConstAccessor()) {}
};

OccupancyGrid::Reader::Reader(const OccupancyGrid& grid) : impl_(std::make_unique<Impl>(*grid.impl_)) {}
OccupancyGrid::Reader::~Reader() = default;

bool OccupancyGrid::Reader::any_in_box(const Vec3f& lo, const Vec3f& hi) {
  return any_on(*impl_->grid.grid, impl_->access, coord_box(voxel_box(lo, hi, impl_->grid.inverse_size)));
}

void OccupancyGrid::merge(OccupancyGrid&& other) {
  if (other.impl_->size != impl_->size) {
    throw ProcessingError(
        fmt::format("occupancy grid: cannot merge voxels of {} m into {} m", other.impl_->size, impl_->size));
  }
  impl_->grid->tree().topologyUnion(other.impl_->grid->tree());
  other.impl_->grid->clear();
  other.impl_->accessor.clear();
  impl_->accessor.clear();  // the union may have replaced cached nodes
}

std::size_t OccupancyGrid::marked_voxels() const {
  return static_cast<std::size_t>(impl_->grid->tree().activeVoxelCount());
}

}  // namespace citymesh
