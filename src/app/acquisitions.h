// SPDX-License-Identifier: MIT
// Reading a config's acquisitions into meshes sharing one local frame (the pipeline's input).
#pragma once

#include <nlohmann/json.hpp>
#include <optional>
#include <span>
#include <vector>

#include "citymesh/config/config.h"
#include "citymesh/core/mesh.h"

namespace citymesh::app {

struct LoadedAcquisitions {
  std::vector<Acquisition> acquisitions;  ///< processing order (Config::acquisitions)
  std::vector<Mesh> meshes;               ///< one per acquisition, all with the first one's origin
  std::vector<TimePoint> dates;
};

/// Throws InputError naming `file` when its `faces` do not fit the provenance ids (int32).
void check_provenance_ids(const std::filesystem::path& file, std::uint64_t faces);

/// Per triangle of an acquisition's mesh: the face index in the file (the provenance id).
std::vector<std::int32_t> source_faces(const Mesh& acquisition);

/// Throws InputError naming acquisition `a`'s file when `position` (one of its vertices, in
/// the file's coordinates) lies outside the area the project CRS is meant for
/// (Crs::area_of_use): its coordinates are in another CRS, and the map would be placed
/// elsewhere on Earth.
void check_within_crs_area(const Config& config, const Acquisition& a, const Vec3d& position);

/// What `a`'s file must be before any work, from its header and first vertex only (nothing
/// read of a withdrawn pass): a mesh, not a point cloud (check_has_faces), whose first vertex
/// lies within the area of the project CRS (check_within_crs_area). Throws InputError naming
/// the file.
void check_acquisition_file(const Config& config, const Acquisition& a);

/// Reads acquisition `a` (with `origin`, the local frame every mesh of a run shares, when
/// given). Throws InputError naming the file.
Mesh read_acquisition(const Config& config, const Acquisition& a, const std::optional<Vec3d>& origin);

/// How the summaries describe acquisition k (processing order): index (its place in the
/// config file), name, date, input file.
nlohmann::json acquisition_json(const Config& config, const LoadedAcquisitions& input, std::size_t k);

/// `source_acq` as the outputs write it: each acquisition by its place in the config file
/// (`listed`, per acquisition in processing order; Config::listed_indices); kNoSource stays.
std::vector<std::int32_t> as_listed(std::span<const std::int32_t> source_acq, std::span<const std::int32_t> listed);

/// Reads every acquisition of `config` whole. Throws InputError naming the file, and
/// ProcessingError when a file has no sensor positions.
LoadedAcquisitions load_acquisitions(const Config& config);

}  // namespace citymesh::app
