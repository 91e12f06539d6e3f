// SPDX-License-Identifier: MIT
// `citymesh simulate`: scan the procedural street at every epoch and write the acquisitions,
// their per-face ground truth, the objects file and a ready config.
#pragma once

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "citymesh/scan/sensor_grid.h"
#include "citymesh/sim/scanner.h"
#include "citymesh/sim/scene.h"

namespace citymesh {

/// What an ideal updated map does with an object, given the epochs and Ts:
/// keep (present in the newest epoch and seen over at least Ts), remove (absent from the newest
/// epoch: gone, or only passing through), unconfirmed (present in the newest epoch but seen over
/// less than Ts: the unconfirmed-triangle policy decides).
enum class Fate { keep, remove, unconfirmed };
[[nodiscard]] std::string_view fate_name(Fate f);
[[nodiscard]] Fate fate_of(const SceneObject& object, const std::vector<EpochDrive>& epochs, Duration sustainability);

struct SimulateParams {
  StreetParams street;
  ScannerParams scanner;
  SensorMeshingParams meshing;
  Duration sustainability = std::chrono::days(30);
  /// City mode: this many parallel streets, street_spacing metres apart (north of the first),
  /// all scanned at every epoch into the same acquisition files.
  int streets = 1;
  float street_spacing = 80.0f;
  std::filesystem::path out;  ///< created if missing
};

struct SimulatedEpoch {
  std::filesystem::path ply, truth;
  std::uint64_t rays = 0, triangles = 0;
};

struct SimulationReport {
  std::vector<SimulatedEpoch> epochs;
  std::size_t objects = 0;
  double scan_seconds = 0, mesh_seconds = 0, write_seconds = 0;
  [[nodiscard]] std::uint64_t triangles() const;
  [[nodiscard]] std::uint64_t rays() const;
};

/// Writes, under params.out: acq_<k>.ply (DESIGN §3 input format, Lambert-93 doubles, sensor
/// position and time per vertex), acq_<k>.truth (object id per face), objects.json and
/// config.toml. Same params give the same bytes. Throws ConfigError, OutputError.
SimulationReport simulate(const SimulateParams& params);

/// One entry of a simulation's objects.json.
struct ObjectRecord {
  std::uint32_t id = 0;
  std::string cls;   ///< object class name
  std::string fate;  ///< keep, remove, unconfirmed; "none" for the no-surface record
};

/// Reads <sim>/objects.json, in file order, and appends a record for kNoSurface (class
/// "no_surface", fate "none") so that every id of a truth file has a record. Throws
/// InputError naming the file when it is missing or malformed.
std::vector<ObjectRecord> read_objects(const std::filesystem::path& sim);

/// The ground-truth sidecar: "CMTRUTH1", uint64 face count, uint32 object id per face (file
/// order), uint64 FNV-1a of the ids; little endian.
void write_truth(const std::filesystem::path& path, std::span<const std::uint32_t> object_ids);
/// Throws InputError naming the file when it is truncated, has the wrong magic or checksum.
std::vector<std::uint32_t> read_truth(const std::filesystem::path& path);

}  // namespace citymesh
