// SPDX-License-Identifier: MIT
// Positions in a project CRS mapped to a local east-north-up frame, many at a time, at a
// fraction of the exact conversion's cost.
#pragma once

#include <span>
#include <vector>

#include "citymesh/core/vec.h"
#include "citymesh/geo/crs.h"

namespace citymesh {

struct LocalFrameMapParams {
  /// Edge of the lattice's cubes in CRS units. The error of a quadratic interpolant grows with
  /// the cube of the edge over the square of the Earth's radius: about 1e-9 m at 64 m.
  double cell = 64.0;
  /// A cube whose interpolant strays further than this (metres) from the exact conversion at
  /// its check points maps its positions exactly instead.
  double tolerance = 1e-6;
};

/// The exact conversion: project CRS -> ECEF (through geodetic) -> `frame`, as floats.
Vec3f exact_local_position(const Crs& crs, const EnuFrame& frame, const Vec3d& p);

/// Maps each position of `positions` (project CRS) into `frame` as floats.
///
/// Converting through geodetic coordinates costs about a microsecond a point (Lambert-93's
/// inverse iterates), and the 3D Tiles export maps every output vertex. Here the CRS is cut into
/// cubes of a fixed lattice (params.cell, aligned on multiples of it); in each cube a position
/// is mapped by the tri-quadratic interpolant of the exact conversion at the cube's 27 nodes,
/// which each cube checks against the exact conversion at 8 inner points (where such an
/// interpolant strays most) and gives up for the exact conversion past params.tolerance. The
/// result is a pure function of the position: a vertex shared by two leaves of the export maps
/// to the same bits in both, whatever the batch or the thread. It differs from
/// exact_local_position by far less than the float's step (~1e-9 m against 6e-5 m a kilometre
/// from the origin), so a float rounds otherwise only when the exact value lies within that
/// error of a rounding boundary.
///
/// Thread-safe: each call builds the interpolants of the cubes its positions touch.
std::vector<Vec3f> map_to_local_frame(std::span<const Vec3d> positions, const Crs& crs, const EnuFrame& frame,
                                      const LocalFrameMapParams& params = {});

}  // namespace citymesh
