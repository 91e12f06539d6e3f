// SPDX-License-Identifier: MIT
// `citymesh info FILE...`: what a PLY acquisition holds and where it lies on Earth.
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <CLI/CLI.hpp>
#include <iostream>
#include <nlohmann/json.hpp>
#include <optional>

#include "citymesh/config/config.h"
#include "citymesh/core/error.h"
#include "citymesh/core/log.h"
#include "citymesh/geo/crs.h"
#include "citymesh/io/ply_inspect.h"
#include "command.h"

namespace citymesh::app {

namespace {

struct LatLonBox {
  double lat_min = 90, lat_max = -90, lon_min = 180, lon_max = -180;
};

/// Lat/lon extent of a projected box, from its corners and edge midpoints (exact enough for
/// street- and city-sized boxes, where the projection barely bends the edges).
LatLonBox lat_lon_box(const Crs& crs, const Box3d& b) {
  LatLonBox box;
  const double xs[3] = {b.min.x, (b.min.x + b.max.x) / 2, b.max.x};
  const double ys[3] = {b.min.y, (b.min.y + b.max.y) / 2, b.max.y};
  const double z = (b.min.z + b.max.z) / 2;
  for (double x : xs) {
    for (double y : ys) {
      const Geodetic g = crs.to_lat_lon({x, y, z});
      box.lat_min = std::min(box.lat_min, g.lat);
      box.lat_max = std::max(box.lat_max, g.lat);
      box.lon_min = std::min(box.lon_min, g.lon);
      box.lon_max = std::max(box.lon_max, g.lon);
    }
  }
  return box;
}

nlohmann::json properties_json(const PlyElement& e) {
  nlohmann::json props = nlohmann::json::array();
  for (const PlyProperty& p : e.properties) {
    props.push_back(p.is_list ? fmt::format("{} (list {} {})", p.name, ply_scalar_name(p.count_type), ply_scalar_name(p.type))
                              : fmt::format("{} ({})", p.name, ply_scalar_name(p.type)));
  }
  return props;
}

/// Whether the file's box lies within the area its CRS is meant for (Crs::area_of_use):
/// outside, its coordinates are likely in another CRS (run refuses such a file).
bool within_area(const Crs& crs, const LatLonBox& g) {
  const AreaOfUse area = crs.area_of_use();
  return area.holds({.lat = g.lat_min, .lon = g.lon_min, .height = 0}) &&
         area.holds({.lat = g.lat_max, .lon = g.lon_max, .height = 0});
}

std::string outside_area_note(const Crs& crs) {
  return fmt::format(" -- OUTSIDE the area {} is meant for: coordinates in another CRS? (run refuses them)",
                     crs.spec());
}

nlohmann::json inspection_json(const PlyInspection& r, const std::optional<Crs>& crs) {
  nlohmann::json j;
  j["file"] = r.path.string();
  j["format"] = ply_format_name(r.header.format);
  for (const PlyElement& e : r.header.elements) {
    j["elements"].push_back({{"name", e.name}, {"count", e.count}, {"properties", properties_json(e)}});
  }
  j["offset"] = {r.header.offset.x, r.header.offset.y, r.header.offset.z};
  j["sensor_origin"] = r.layout.has_sensor_origin;
  j["time_property"] = r.layout.has_time ? nlohmann::json(r.layout.time_name) : nlohmann::json();
  if (r.layout.has_time && r.stats.vertices > 0) j["time_range"] = {r.time_min, r.time_max};
  j["triangles"] = r.stats.triangles;
  j["polygons_split"] = r.stats.polygons_split;
  j["degenerate_dropped"] = r.stats.degenerate_dropped;
  if (!r.bounds.empty()) {
    j["bounds"] = {{"min", {r.bounds.min.x, r.bounds.min.y, r.bounds.min.z}},
                   {"max", {r.bounds.max.x, r.bounds.max.y, r.bounds.max.z}}};
    if (crs) {
      const LatLonBox g = lat_lon_box(*crs, r.bounds);
      j["crs"] = crs->spec();
      j["lat_lon_bounds"] = {{"lat", {g.lat_min, g.lat_max}}, {"lon", {g.lon_min, g.lon_max}}};
      j["within_crs_area"] = within_area(*crs, g);
    }
  }
  return j;
}

void print_text(const PlyInspection& r, const std::optional<Crs>& crs) {
  std::string out = fmt::format("{}\n  format: {}\n", r.path.string(), ply_format_name(r.header.format));
  for (const PlyElement& e : r.header.elements) {
    out += fmt::format("  element {}: {} rows; properties: {}\n", e.name, e.count,
                       fmt::join(properties_json(e).get<std::vector<std::string>>(), ", "));
  }
  if (r.header.offset != Vec3d{}) {
    out += fmt::format("  header offset: {} {} {} (applied)\n", r.header.offset.x, r.header.offset.y, r.header.offset.z);
  }
  out += fmt::format("  sensor origin: {}\n", r.layout.has_sensor_origin ? "present" : "absent");
  if (r.layout.has_time && r.stats.vertices > 0) {
    out += fmt::format("  time ({}): {:.6f} .. {:.6f} ({:.6f} s)\n", r.layout.time_name, r.time_min, r.time_max,
                       r.time_max - r.time_min);
  } else {
    out += "  time: absent\n";
  }
  out += fmt::format("  triangles: {} ({} polygons split, {} degenerate faces dropped)\n", r.stats.triangles,
                     r.stats.polygons_split, r.stats.degenerate_dropped);
  if (!r.bounds.empty()) {
    const std::string frame = crs ? fmt::format("{}, {}", crs->spec(), crs->name()) : "file coordinates";
    out += fmt::format("  bounds ({}):\n    x {:.3f} .. {:.3f}\n    y {:.3f} .. {:.3f}\n    z {:.3f} .. {:.3f}\n",
                       frame, r.bounds.min.x, r.bounds.max.x, r.bounds.min.y, r.bounds.max.y, r.bounds.min.z,
                       r.bounds.max.z);
    if (crs) {
      const LatLonBox g = lat_lon_box(*crs, r.bounds);
      out += fmt::format("  lat/lon: lat {:.7f} .. {:.7f}, lon {:.7f} .. {:.7f}{}\n", g.lat_min, g.lat_max, g.lon_min,
                         g.lon_max, within_area(*crs, g) ? "" : outside_area_note(*crs));
    } else {
      out += "  lat/lon: unknown (pass --crs or --config)\n";
    }
  }
  std::cout << out;
}

class InfoCommand final : public Command {
 public:
  std::string_view name() const override { return "info"; }
  std::string_view summary() const override {
    return "describe PLY files: format, counts, properties, sensor origin, time range, bounds";
  }

  void declare(CLI::App& app) override {
    app.add_option("files", files_, "PLY files to describe (default: the acquisitions of --config)")
        ->check(CLI::ExistingFile);
    app.add_option("--config", config_, "run config: gives the CRS, property names and acquisitions");
    app.add_option("--crs", crs_, "project CRS for bounds and lat/lon: EPSG:2154, EPSG:326xx/327xx, ENU:lat,lon,h "
                                  "(default: the config's, else none)");
    app.add_option("--sensor-origin", origin_names_, "sensor-position property names (default: x_origin y_origin "
                                                     "z_origin, or the config's)")
        ->expected(3);
    app.add_flag("--require-origin", require_origin_,
                 "fail on a file without per-vertex sensor positions (every acquisition needs them)");
    app.add_flag("--json", json_, "print one JSON object per file instead of text");
    app.footer("Examples:\n  citymesh info --crs EPSG:2154 scan.ply\n  citymesh info --config configs/demo.toml --json");
  }

  void run() override {
    PlyReadParams params;
    std::optional<Crs> crs;
    if (!config_.empty()) {
      const Config config = load_config(config_, {.overrides = {}, .check_files = false});
      params = config.ply_read_params();
      crs = config.crs();
      if (files_.empty()) {
        for (const std::size_t k : config.listed_order()) {  // as the file lists them
          const AcquisitionEntry& a = config.acquisitions[k];
          if (a.withdrawn) {
            log::info("{}: withdrawn, not described", a.path.string());
          } else {
            files_.push_back(a.path.string());
          }
        }
      }
    }
    if (!crs_.empty()) crs = Crs::parse(crs_);
    if (!origin_names_.empty()) params.sensor_origin_names = {origin_names_[0], origin_names_[1], origin_names_[2]};
    if (files_.empty()) throw UsageError("no files given (name PLY files or pass --config)");
    for (const std::string& file : files_) {
      const PlyInspection r = inspect_ply(file, params);
      if (require_origin_ && !r.layout.has_sensor_origin) {
        throw InputError(fmt::format("{}: no sensor position: vertex properties {}, {}, {} not found", file,
                                     params.sensor_origin_names[0], params.sensor_origin_names[1],
                                     params.sensor_origin_names[2]));
      }
      if (json_) {
        std::cout << inspection_json(r, crs).dump() << "\n";
      } else {
        print_text(r, crs);
      }
    }
  }

 private:
  std::vector<std::string> files_;
  std::string config_;
  std::string crs_;
  std::vector<std::string> origin_names_;
  bool json_ = false;
  bool require_origin_ = false;
};

}  // namespace

std::unique_ptr<Command> make_info_command() { return std::make_unique<InfoCommand>(); }

}  // namespace citymesh::app
