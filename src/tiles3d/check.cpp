// SPDX-License-Identifier: MIT
#include "citymesh/tiles3d/check.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <map>
#include <optional>
#include <set>
#include <span>
#include <string>

#include "citymesh/core/error.h"
#include "citymesh/core/read_file.h"
#include "citymesh/encode/glb.h"
#include "tile_cracks.h"

namespace citymesh {

namespace {

using nlohmann::json;

/// The file's bytes, or nullopt when it is missing or unreadable (reported, not thrown).
std::optional<std::string> read_bytes(const std::filesystem::path& path) {
  try {
    return read_file_bytes(path);
  } catch (const InputError&) {
    return std::nullopt;
  }
}

std::span<const std::uint8_t> as_bytes(const std::string& s) {
  return {reinterpret_cast<const std::uint8_t*>(s.data()), s.size()};
}

bool finite_numbers(const json& j, std::size_t count) {
  if (!j.is_array() || j.size() != count) return false;
  return std::all_of(j.begin(), j.end(), [](const json& v) { return v.is_number() && std::isfinite(v.get<double>()); });
}

/// Axis-aligned bounds of an oriented box (centre + three half-axes).
struct Bounds {
  double lo[3], hi[3];
};

Bounds box_bounds(const json& box) {
  Bounds b{};
  for (int k = 0; k < 3; ++k) {
    const auto ku = static_cast<std::size_t>(k);
    double extent = 0;
    for (std::size_t axis = 0; axis < 3; ++axis) extent += std::abs(box[3 + 3 * axis + ku].get<double>());
    b.lo[k] = box[ku].get<double>() - extent;
    b.hi[k] = box[ku].get<double>() + extent;
  }
  return b;
}

class Checker {
 public:
  Checker(std::filesystem::path root_dir, const TilesetCheckParams& params, TilesetCheckReport& report)
      : dir_(std::move(root_dir)), params_(params), report_(report) {}

  /// Checks tileset file `name`, whose root tile goes under tile `parent` of the crack count.
  void tileset_file(const std::string& name, double parent_error, int depth,
                    std::uint32_t parent = tiles3d_detail::TileCrackCounter::kNoParent) {
    if (!visited_.insert(name).second) return error(name, "", "referenced twice (a cycle or a shared external tileset)");
    const std::filesystem::path path = dir_ / name;
    const std::optional<std::string> read = read_bytes(path);
    if (!read) return error(name, "", "missing or unreadable");
    const std::string& bytes = *read;
    ++report_.json_files;
    report_.json_bytes += bytes.size();
    if (bytes.size() > params_.max_json_bytes) {
      error(name, "", fmt::format("{} bytes: larger than {} (split into external tilesets)", bytes.size(),
                                  params_.max_json_bytes));
    }
    const json tileset = json::parse(bytes.begin(), bytes.end(), nullptr, false);
    if (tileset.is_discarded() || !tileset.is_object()) return error(name, "", "not valid JSON");
    const json& asset = tileset.value("asset", json::object());
    if (!asset.contains("version") || !asset["version"].is_string()) error(name, "asset", "no version");
    else if (asset["version"] != "1.1" && asset["version"] != "1.0") error(name, "asset", "version is not 1.0 or 1.1");
    if (!tileset.contains("geometricError") || !tileset["geometricError"].is_number()) {
      error(name, "", "no top-level geometricError");
    }
    if (!tileset.contains("root") || !tileset["root"].is_object()) return error(name, "", "no root tile");
    const json& root = tileset["root"];
    if (!root.contains("refine")) error(name, "root", "no refine (required on the root tile)");
    tile(name, "root", root, parent_error, depth, parent);
  }

  [[nodiscard]] tiles3d_detail::TileCracks cracks() const {
    return cracks_.count([&](std::uint32_t tile) {
      tiles3d_detail::TileContent content;
      const std::string name = content_name(tile);
      const std::optional<std::string> bytes = read_bytes(dir_ / name);
      if (!bytes) return content;  // checked before: it was there
      try {
        DecodedMesh m = read_glb_mesh(parse_glb(as_bytes(*bytes), name), name);
        content.positions = std::move(m.positions);
        content.triangles = std::move(m.triangles);
      } catch (const InputError&) {
        // reported when it was first read
      }
      return content;
    });
  }
  /// The glb file of crack-count tile `id`.
  [[nodiscard]] std::string content_name(std::uint32_t id) const {
    const auto it = glb_names_.find(id);
    return it == glb_names_.end() ? std::string() : it->second;
  }

 private:
  void error(const std::string& file, const std::string& where, const std::string& what) {
    report_.errors.push_back(where.empty() ? fmt::format("{}: {}", file, what) : fmt::format("{}: {}: {}", file, where, what));
  }

  void tile(const std::string& file, const std::string& where, const json& t, double parent_error, int depth,
            std::uint32_t parent) {
    const std::uint32_t id = cracks_.add_tile(parent);
    ++report_.tiles;
    report_.levels = std::max(report_.levels, static_cast<std::size_t>(depth) + 1);
    if (depth > 64) return error(file, where, "tree deeper than 64 levels");
    const json& volume = t.value("boundingVolume", json::object());
    std::optional<Bounds> bounds;
    if (volume.contains("box")) {
      if (!finite_numbers(volume["box"], 12)) error(file, where, "boundingVolume.box is not 12 finite numbers");
      else bounds = box_bounds(volume["box"]);
    } else if (!(volume.contains("region") && finite_numbers(volume["region"], 6)) &&
               !(volume.contains("sphere") && finite_numbers(volume["sphere"], 4))) {
      error(file, where, "no valid boundingVolume (box, region or sphere)");
    }
    if (t.contains("transform") && !finite_numbers(t["transform"], 16)) {
      error(file, where, "transform is not 16 finite numbers");
    } else if (t.contains("transform")) {
      const json& m = t["transform"];
      if (m[3] != 0 || m[7] != 0 || m[11] != 0 || m[15] != 1) error(file, where, "transform's last row is not 0 0 0 1");
    }
    if (t.contains("refine") && t["refine"] != "REPLACE" && t["refine"] != "ADD") {
      error(file, where, "refine is neither REPLACE nor ADD");
    }
    const double ge = t.value("geometricError", -1.0);
    if (ge < 0 || !std::isfinite(ge)) error(file, where, "geometricError missing or negative");
    if (ge > parent_error * (1 + 1e-9)) {
      error(file, where, fmt::format("geometricError {} exceeds its parent's {}", ge, parent_error));
    }
    const json children = t.value("children", json::array());
    std::string content_uri;
    if (t.contains("content")) content_uri = t["content"].value("uri", std::string());
    const bool external = content_uri.size() > 5 && content_uri.ends_with(".json");
    if ((!children.empty() || external) && ge <= 0) error(file, where, "a parent tile has geometricError 0");
    if (external && !children.empty()) error(file, where, "a tile with an external tileset has children");
    if (t.contains("content")) content(file, where, content_uri, ge, depth, bounds, children.empty(), id);
    for (std::size_t c = 0; c < children.size(); ++c) {
      tile(file, fmt::format("{}.children[{}]", where, c), children[c], ge, depth + 1, id);
    }
  }

  void content(const std::string& file, const std::string& where, const std::string& uri, double ge, int depth,
               const std::optional<Bounds>& bounds, bool leaf, std::uint32_t id) {
    if (uri.empty()) return error(file, where, "content has no uri");
    if (uri.front() == '/' || uri.find("..") != std::string::npos || uri.find(':') != std::string::npos) {
      return error(file, where, fmt::format("content uri \"{}\" leaves the tileset folder", uri));
    }
    if (uri.ends_with(".json")) return tileset_file(uri, ge, depth + 1, id);
    if (!uri.ends_with(".glb")) return error(file, where, fmt::format("content \"{}\" is neither glb nor json", uri));
    glb(uri, bounds, leaf, id);
  }

  void glb(const std::string& name, const std::optional<Bounds>& bounds, bool leaf, std::uint32_t id) {
    const std::optional<std::string> bytes = read_bytes(dir_ / name);
    if (!bytes) return error(name, "", "missing or unreadable");
    ++report_.glb_files;
    report_.glb_bytes += bytes->size();
    try {
      const GlbFile g = parse_glb(as_bytes(*bytes), name);
      glb_json(name, g.json);
      const DecodedMesh m = read_glb_mesh(g, name);
      glb_mesh(name, g.json, m, bounds);
      cracks_.set_content(id, m.positions, m.triangles);
      glb_names_[id] = name;
      report_.triangles += m.triangles.size();
      if (leaf) report_.leaf_triangles += m.triangles.size();
    } catch (const InputError& e) {
      error(name, "", e.what());
    } catch (const json::exception& e) {
      error(name, "", fmt::format("unexpected glTF JSON: {}", e.what()));
    }
  }

  void glb_json(const std::string& name, const json& j) {
    if (j.value("asset", json::object()).value("version", std::string()) != "2.0") error(name, "asset", "version is not 2.0");
    const json used = j.value("extensionsUsed", json::array()), required = j.value("extensionsRequired", json::array());
    for (const json& r : required) {
      if (std::find(used.begin(), used.end(), r) == used.end()) error(name, "", fmt::format("{} required but not used", r.dump()));
    }
    const bool draco = std::find(used.begin(), used.end(), "KHR_draco_mesh_compression") != used.end();
    const bool draco_required =
        std::find(required.begin(), required.end(), "KHR_draco_mesh_compression") != required.end();
    if (draco && !draco_required) error(name, "", "KHR_draco_mesh_compression used but not required");
  }

  void glb_mesh(const std::string& name, const json& j, const DecodedMesh& m, const std::optional<Bounds>& bounds) {
    const json& primitive = j.at("meshes").at(0).at("primitives").at(0);
    const json& position = j.at("accessors").at(primitive.at("attributes").at("POSITION").get<std::size_t>());
    if (!finite_numbers(position.value("min", json()), 3) || !finite_numbers(position.value("max", json()), 3)) {
      return error(name, "POSITION", "accessor min/max missing");
    }
    if (position.at("count").get<std::size_t>() != m.positions.size()) {
      error(name, "POSITION", fmt::format("accessor count {} but {} vertices decode", position["count"].get<std::size_t>(),
                                          m.positions.size()));
    }
    if (primitive.contains("indices")) {
      const std::size_t corners = j.at("accessors").at(primitive["indices"].get<std::size_t>()).at("count");
      if (corners != m.triangles.size() * 3) {
        error(name, "indices", fmt::format("accessor count {} but {} triangles decode", corners, m.triangles.size()));
      }
    }
    const double eps = 1e-4;
    std::size_t outside_accessor = 0, outside_box = 0;
    for (const Vec3f& p : m.positions) {
      for (std::size_t k = 0; k < 3; ++k) {
        const double v = static_cast<double>(p[static_cast<int>(k)]);
        if (v < position["min"][k].get<double>() - eps || v > position["max"][k].get<double>() + eps) ++outside_accessor;
        if (bounds && (v < bounds->lo[k] - params_.box_tolerance || v > bounds->hi[k] + params_.box_tolerance)) ++outside_box;
      }
    }
    if (outside_accessor > 0) error(name, "POSITION", fmt::format("{} coordinates outside the accessor min/max", outside_accessor));
    if (outside_box > 0) error(name, "", fmt::format("{} coordinates outside the tile's bounding box", outside_box));
    feature_ids(name, j, primitive, m);
  }

  void feature_ids(const std::string& name, const json& j, const json& primitive, const DecodedMesh& m) {
    if (m.feature_ids.empty()) return;
    std::size_t rows = 0;
    std::uint64_t null_id = 1ull << 32;
    try {
      rows = j.at("extensions").at("EXT_structural_metadata").at("propertyTables").at(0).at("count");
      null_id = primitive.at("extensions").at("EXT_mesh_features").at("featureIds").at(0).value("nullFeatureId", null_id);
    } catch (const json::exception&) {
      return error(name, "", "feature ids without the EXT_mesh_features / EXT_structural_metadata acquisition table");
    }
    const std::size_t bad = static_cast<std::size_t>(std::count_if(m.feature_ids.begin(), m.feature_ids.end(), [&](std::uint16_t f) {
      return f >= rows && f != null_id;
    }));
    if (bad > 0) error(name, kFeatureIdAttribute, fmt::format("{} feature ids beyond the {} acquisitions", bad, rows));
  }

  std::filesystem::path dir_;
  const TilesetCheckParams& params_;
  TilesetCheckReport& report_;
  std::set<std::string> visited_;
  tiles3d_detail::TileCrackCounter cracks_;
  std::map<std::uint32_t, std::string> glb_names_;  ///< by crack-count tile
};

}  // namespace

TilesetCheckReport check_tileset(const std::filesystem::path& path, const TilesetCheckParams& params) {
  std::error_code ec;
  const bool is_dir = std::filesystem::is_directory(path, ec);
  const std::filesystem::path file = is_dir ? path / "tileset.json" : path;
  if (!std::filesystem::is_regular_file(file, ec)) {
    throw InputError(fmt::format("{}: no tileset.json there", file.string()));
  }
  TilesetCheckReport report;
  Checker checker(file.parent_path(), params, report);
  checker.tileset_file(file.filename().string(), std::numeric_limits<double>::infinity(), 0);
  const tiles3d_detail::TileCracks cracks = checker.cracks();
  report.seam_length = cracks.seam_length;
  report.crack_length = cracks.crack_length;
  for (const auto& [tile, length] : cracks.by_tile) {
    report.cracked_tiles.push_back({checker.content_name(tile), length});
  }
  return report;
}

}  // namespace citymesh
