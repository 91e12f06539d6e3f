// SPDX-License-Identifier: MIT
// Runs the simulator end to end and writes its files.
#include "citymesh/sim/simulate.h"

#include <fmt/format.h>

#include <chrono>
#include <cmath>
#include <nlohmann/json.hpp>
#include <optional>

#include "citymesh/config/config.h"
#include "citymesh/core/atomic_file.h"
#include "citymesh/core/error.h"
#include "citymesh/core/interrupt.h"
#include "citymesh/core/log.h"
#include "citymesh/core/stopwatch.h"
#include "citymesh/core/triangle_reach.h"
#include "citymesh/io/ply_writer.h"

namespace citymesh {

namespace {

/// A face is labelled with the object whose surface lies this close to its centroid (range
/// noise, registration error and chords of curved surfaces stay well below it).
constexpr float kTruthTolerance = 0.03f;

/// Object ids of street s are offset by s * kIdsPerStreet, so they stay unique in a city.
constexpr std::uint32_t kIdsPerStreet = 1'000'000;

/// One street, or `streets` parallel streets street_spacing metres apart (city mode), each
/// with its own seed and its own van (lane, speed) but the same epoch dates.
std::vector<Scene> make_scenes(const SimulateParams& p) {
  if (p.streets < 1 || p.streets > 1000) throw ConfigError(fmt::format("simulate: {} streets (1..1000)", p.streets));
  if (p.streets > 1 && !(p.street_spacing >= p.street.width + 10)) {
    throw ConfigError(fmt::format("simulate: street spacing {} m must exceed the street width + 10 m", p.street_spacing));
  }
  std::vector<Scene> scenes;
  for (int s = 0; s < p.streets; ++s) {
    StreetParams street = p.street;
    street.seed = p.street.seed + 7919ull * static_cast<std::uint64_t>(s);
    street.origin.y += static_cast<double>(p.street_spacing) * s;
    scenes.push_back(make_street_scene(street));
    if (s > 0) {
      for (SceneObject& o : scenes.back().objects) o.id += kIdsPerStreet * static_cast<std::uint32_t>(s);
    }
  }
  return scenes;
}

std::string objects_json(const std::vector<Scene>& scenes, const SimulateParams& p) {
  nlohmann::json j;
  j["seed"] = p.street.seed;
  j["crs"] = "EPSG:2154";
  j["sustainability"] = format_duration(p.sustainability);
  for (std::size_t k = 0; k < scenes.front().epochs.size(); ++k) {
    j["epochs"].push_back({{"index", k}, {"date", format_iso8601(scenes.front().epochs[k].date)}});
  }
  for (std::size_t s = 0; s < scenes.size(); ++s) {
    const Scene& scene = scenes[s];
    nlohmann::json drives = nlohmann::json::array();
    for (const EpochDrive& e : scene.epochs) drives.push_back({{"lane_offset", e.lane_offset}, {"speed", e.speed}});
    j["streets"].push_back({{"index", s}, {"origin", {scene.origin.x, scene.origin.y, scene.origin.z}},
                            {"length", scene.length}, {"width", scene.width}, {"drives", drives}});
    for (const SceneObject& o : scene.objects) {
      nlohmann::json seen = nlohmann::json::array();
      for (std::size_t k = 0; k < scene.epochs.size(); ++k) {
        if (o.present_at(scene.epochs[k].date)) seen.push_back(k);
      }
      nlohmann::json entry{{"id", o.id}, {"street", s}, {"class", object_class_name(o.type)}, {"epochs", seen},
                           {"fate", fate_name(fate_of(o, scene.epochs, p.sustainability))}};
      entry["appear"] = o.appear == TimePoint::min() ? nlohmann::json() : nlohmann::json(format_iso8601(o.appear));
      entry["disappear"] =
          o.disappear == TimePoint::max() ? nlohmann::json() : nlohmann::json(format_iso8601(o.disappear));
      j["objects"].push_back(entry);
    }
  }
  return j.dump(1) + "\n";
}

/// The largest x-y reach of the mesh's triangles from their centroids, as `run`'s tiling
/// measures it (TilingStats::largest_radius).
double largest_horizontal_reach(const Mesh& mesh) {
  double largest_squared = 0;
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
    largest_squared = std::max(largest_squared, horizontal_reach_squared(mesh.corners(t)));
  }
  return std::sqrt(largest_squared);
}

/// The [tiling] halo the street needs when the default is too narrow: its largest triangle's
/// reach plus the distance threshold (else `run` warns that labels near tile borders may
/// differ from an untiled run's), rounded up to 10 cm; none when the default will do.
std::optional<double> needed_halo(double largest_reach) {
  const double needed = largest_reach + ChangeParams{}.distance_threshold;
  if (needed <= TilingParams{}.halo) return std::nullopt;
  return std::ceil(needed * 10 + 1e-9) / 10;
}

std::string config_toml(const Scene& scene, const SimulateParams& p, double largest_reach) {
  std::string out = fmt::format(
      "# Written by citymesh simulate (seed {}): runs the pipeline on this simulated street.\n"
      "[project]\ncrs = \"EPSG:2154\"\nvertical_datum = \"orthometric\"\ngeoid_undulation = 44.6\n"
      "output = \"out\"\nwork = \"work\"\n\n[change]\nsustainability = \"{}\"\n",
      p.street.seed, format_duration(p.sustainability));
  if (const std::optional<double> halo = needed_halo(largest_reach)) {
    out += fmt::format(
        "\n[tiling]\n# this scanner meshes far surfaces with long triangles (up to {:.2f} m from their centroid)\n"
        "halo = {:.1f}\n",
        largest_reach, *halo);
  }
  for (std::size_t k = 0; k < scene.epochs.size(); ++k) {
    out += fmt::format("\n[[acquisition]]\npath = \"acq_{}.ply\"\ntime = \"{}\"\nname = \"epoch {}\"\n", k,
                       format_iso8601(scene.epochs[k].date), k);
  }
  return out;
}

/// The edge limit must follow the scanner's sampling: at a grazing 80° incidence, successive
/// pulses land about 6 x (angular step in radians) x range apart.
SensorMeshingParams meshing_for(const SimulateParams& p) {
  SensorMeshingParams m = p.meshing;
  const bool spinning = p.scanner.mode == ScannerParams::Mode::spinning;
  const float step = spinning ? std::max(2.0f * float(M_PI) / static_cast<float>(p.scanner.columns),
                                         p.scanner.vertical_fov_deg * float(M_PI) / 180.0f / static_cast<float>(std::max(1, p.scanner.rings - 1)))
                              : p.scanner.angular_step_deg * float(M_PI) / 180.0f;
  m.max_edge_per_metre = std::max(m.max_edge_per_metre, 6.0f * step);
  return m;
}

}  // namespace

std::uint64_t SimulationReport::triangles() const {
  std::uint64_t n = 0;
  for (const auto& e : epochs) n += e.triangles;
  return n;
}

std::uint64_t SimulationReport::rays() const {
  std::uint64_t n = 0;
  for (const auto& e : epochs) n += e.rays;
  return n;
}

SimulationReport simulate(const SimulateParams& p) {
  if (p.out.empty()) throw UsageError("simulate: no output folder given (--out DIR)");
  const std::vector<Scene> scenes = make_scenes(p);
  SimulationReport report;
  for (const Scene& scene : scenes) report.objects += scene.objects.size();
  const std::size_t epochs = scenes.front().epochs.size();
  double largest_reach = 0;
  for (std::size_t k = 0; k < epochs; ++k) {
    Mesh epoch;
    epoch.origin = scenes.front().origin;
    std::vector<std::uint32_t> truth;
    SimulatedEpoch e;
    for (const Scene& scene : scenes) {
      throw_if_interrupted("simulate");
      Stopwatch stage;
      const std::vector<SensorGrid> grids = scan_epoch(scene, k, p.scanner);
      report.scan_seconds += stage.restart();
      Mesh street;
      street.origin = epoch.origin;
      for (const SensorGrid& grid : grids) {
        append_mesh(mesh_sensor_grid(grid, meshing_for(p), static_cast<std::uint32_t>(k)).mesh, street);
      }
      const std::vector<std::uint32_t> labels = surface_labels(scene, k, street, kTruthTolerance);
      truth.insert(truth.end(), labels.begin(), labels.end());
      append_mesh(street, epoch);
      report.mesh_seconds += stage.seconds();
      e.rays += rays_per_epoch(scene, k, p.scanner);
    }
    const Stopwatch writing;
    e.ply = p.out / fmt::format("acq_{}.ply", k);
    e.truth = p.out / fmt::format("acq_{}.truth", k);
    e.triangles = epoch.triangle_count();
    largest_reach = std::max(largest_reach, largest_horizontal_reach(epoch));
    write_mesh_ply(e.ply, epoch);
    write_truth(e.truth, truth);
    report.write_seconds += writing.seconds();
    log::info("simulate: epoch {} ({}): {} rays, {} triangles", k, format_iso8601(scenes.front().epochs[k].date),
              e.rays, e.triangles);
    report.epochs.push_back(e);
  }
  write_file_atomically(p.out / "objects.json", objects_json(scenes, p));
  write_file_atomically(p.out / "config.toml", config_toml(scenes.front(), p, largest_reach));
  return report;
}

}  // namespace citymesh
