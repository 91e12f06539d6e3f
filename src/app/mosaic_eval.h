// SPDX-License-Identifier: MIT
// Scoring against the simulator's ground truth, shared by the detect and mosaic parts of
// `citymesh eval`.
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace citymesh::app {

nlohmann::json read_json(const std::filesystem::path& path, std::string_view what);

struct ObjectInfo {
  std::string cls, fate;  ///< fate: keep, remove, unconfirmed, none (no surface)
  double area = 0, kept_area = 0;
  std::uint64_t triangles = 0;
};

/// The simulation's objects (objects.json), with the no-surface record.
std::map<std::uint32_t, ObjectInfo> objects_by_id(const std::filesystem::path& sim);

/// Where a face came from, for error messages (built per face: it refers, never copies).
struct FaceOrigin {
  const std::filesystem::path& ply;
  const std::filesystem::path& truth;
  std::uint64_t face = 0;
};

/// The object of input face `source_face` (a double read from a PLY) under `truth`; throws
/// InputError naming the files when the face or the object does not exist.
ObjectInfo& object_of(std::map<std::uint32_t, ObjectInfo>& objects, const std::vector<std::uint32_t>& truth,
                      double source_face, const FaceOrigin& origin);
const ObjectInfo& object_of(const std::map<std::uint32_t, ObjectInfo>& objects, const std::vector<std::uint32_t>& truth,
                            double source_face, const FaceOrigin& origin);

/// The mosaic's scores (overlap ratio, seam length, hole ratio, static completeness, dynamic
/// residue, mean edge length against the finest input) from <output>/mosaic and the detect
/// outputs listed in `detect_summary`.
nlohmann::json evaluate_mosaic(const std::filesystem::path& output, const std::filesystem::path& truth_dir,
                               const nlohmann::json& detect_summary,
                               const std::map<std::uint32_t, ObjectInfo>& objects);

/// The positions of a summary's `acquisitions` by their dates (equal dates in list order):
/// the order eval adds their areas up in, so that its figures do not depend on the order in
/// which the config lists the passes.
std::vector<std::size_t> by_date(const nlohmann::json& acquisitions);

/// The truth file of an acquisition listed in the detect summary.
std::filesystem::path truth_file(const std::filesystem::path& truth_dir, const nlohmann::json& acquisition);

}  // namespace citymesh::app
