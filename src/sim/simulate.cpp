// SPDX-License-Identifier: MIT
// Runs the simulator end to end and writes its files.
#include "citymesh/sim/simulate.h"

#include <fmt/format.h>

#include <chrono>
#include <nlohmann/json.hpp>

#include "citymesh/core/atomic_file.h"
#include "citymesh/core/error.h"
#include "citymesh/core/interrupt.h"
#include "citymesh/core/log.h"
#include "citymesh/io/ply_writer.h"

namespace citymesh {

namespace {

double seconds_since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

std::string objects_json(const Scene& scene, const SimulateParams& p) {
  nlohmann::json j;
  j["seed"] = p.street.seed;
  j["origin"] = {scene.origin.x, scene.origin.y, scene.origin.z};
  j["crs"] = "EPSG:2154";
  j["sustainability"] = format_duration(p.sustainability);
  for (std::size_t k = 0; k < scene.epochs.size(); ++k) {
    const EpochDrive& e = scene.epochs[k];
    j["epochs"].push_back({{"index", k}, {"date", format_iso8601(e.date)}, {"lane_offset", e.lane_offset},
                           {"speed", e.speed}});
  }
  for (const SceneObject& o : scene.objects) {
    nlohmann::json seen = nlohmann::json::array();
    for (std::size_t k = 0; k < scene.epochs.size(); ++k) {
      if (o.present_at(scene.epochs[k].date)) seen.push_back(k);
    }
    nlohmann::json entry{{"id", o.id}, {"class", object_class_name(o.type)}, {"epochs", seen},
                         {"fate", fate_name(fate_of(o, scene.epochs, p.sustainability))}};
    entry["appear"] = o.appear == TimePoint::min() ? nlohmann::json() : nlohmann::json(format_iso8601(o.appear));
    entry["disappear"] =
        o.disappear == TimePoint::max() ? nlohmann::json() : nlohmann::json(format_iso8601(o.disappear));
    j["objects"].push_back(entry);
  }
  return j.dump(1) + "\n";
}

std::string config_toml(const Scene& scene, const SimulateParams& p) {
  std::string out = fmt::format(
      "# Written by citymesh simulate (seed {}): runs the pipeline on this simulated street.\n"
      "[project]\ncrs = \"EPSG:2154\"\nvertical_datum = \"orthometric\"\ngeoid_undulation = 44.6\n"
      "output = \"out\"\nwork = \"work\"\n\n[change]\nsustainability = \"{}\"\n",
      p.street.seed, format_duration(p.sustainability));
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
  const float step = p.scanner.angular_step_deg * float(M_PI) / 180.0f;
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
  const Scene scene = make_street_scene(p.street);
  SimulationReport report;
  report.objects = scene.objects.size();
  for (std::size_t k = 0; k < scene.epochs.size(); ++k) {
    throw_if_interrupted("simulate");
    auto t = std::chrono::steady_clock::now();
    const SensorGrid grid = scan_epoch(scene, k, p.scanner);
    report.scan_seconds += seconds_since(t);
    t = std::chrono::steady_clock::now();
    const SensorMeshResult meshed = mesh_sensor_grid(grid, meshing_for(p), static_cast<std::uint32_t>(k));
    report.mesh_seconds += seconds_since(t);
    t = std::chrono::steady_clock::now();
    SimulatedEpoch e;
    e.ply = p.out / fmt::format("acq_{}.ply", k);
    e.truth = p.out / fmt::format("acq_{}.truth", k);
    e.rays = rays_per_epoch(scene, k, p.scanner);
    e.hits = static_cast<std::uint64_t>(std::count(grid.valid.begin(), grid.valid.end(), 1));
    e.triangles = meshed.mesh.triangle_count();
    write_mesh_ply(e.ply, meshed.mesh);
    write_truth(e.truth, meshed.face_labels);
    report.write_seconds += seconds_since(t);
    log::info("simulate: epoch {} ({}): {} rays, {} triangles", k, format_iso8601(scene.epochs[k].date), e.rays,
              e.triangles);
    report.epochs.push_back(e);
  }
  write_file_atomically(p.out / "objects.json", objects_json(scene, p));
  write_file_atomically(p.out / "config.toml", config_toml(scene, p));
  return report;
}

}  // namespace citymesh
