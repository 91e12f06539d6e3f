// SPDX-License-Identifier: MIT
// The key table. Defaults are never written here: `show` prints the member initialisers of
// the params structs in config.h, so defaults live in one place.
#include "config_keys.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <initializer_list>

#include "citymesh/core/error.h"

namespace citymesh::config_detail {

void KeyContext::fail(std::string_view why) const { throw ConfigError(fmt::format("{}: {}", where, why)); }

std::string toml_string(std::string_view s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    out += c;
  }
  return out + "\"";
}

namespace {

// Accessors are generic lambdas `[](auto& c) -> auto& { return c.section.key; }` so that the
// same one reads (Config&) and prints (const Config&).

template <class Get>
KeyDef real_key(std::string_view section, std::string_view name, std::string_view help, Get get,
                double lo, double hi) {
  return {section, name, fmt::format("{} [{} .. {}]", help, lo, hi), "",
          [=](Config& c, const toml::node& n, const KeyContext& k) {
            auto v = n.value<double>();
            if (!v || !(*v >= lo && *v <= hi)) k.fail(fmt::format("expected a number from {} to {}", lo, hi));
            get(c) = *v;
          },
          [=](const Config& c) { return fmt::format("{}", get(c)); }};
}

template <class Get>
KeyDef count_key(std::string_view section, std::string_view name, std::string_view help, Get get,
                 std::int64_t lo, std::int64_t hi) {
  return {section, name, fmt::format("{} [{} .. {}]", help, lo, hi), "",
          [=](Config& c, const toml::node& n, const KeyContext& k) {
            auto v = n.is_integer() ? n.value<std::int64_t>() : std::nullopt;
            if (!v || *v < lo || *v > hi) k.fail(fmt::format("expected a whole number from {} to {}", lo, hi));
            get(c) = static_cast<std::remove_reference_t<decltype(get(c))>>(*v);
          },
          [=](const Config& c) { return fmt::format("{}", get(c)); }};
}

template <class Get>
KeyDef bool_key(std::string_view section, std::string_view name, std::string_view help, Get get) {
  return {section, name, std::string(help), "",
          [=](Config& c, const toml::node& n, const KeyContext& k) {
            if (!n.is_boolean()) k.fail("expected true or false");
            get(c) = *n.value<bool>();
          },
          [=](const Config& c) { return std::string(get(c) ? "true" : "false"); }};
}

std::string read_string(const toml::node& n, const KeyContext& k) {
  if (!n.is_string()) k.fail("expected a string in quotes");
  return *n.value<std::string>();
}

template <class Get>
KeyDef string_key(std::string_view section, std::string_view name, std::string_view help, Get get,
                  std::string_view example = "") {
  return {section, name, std::string(help), example,
          [=](Config& c, const toml::node& n, const KeyContext& k) {
            std::string s = read_string(n, k);
            if (s.empty()) k.fail("must not be empty");
            get(c) = std::move(s);
          },
          [=](const Config& c) {
            const auto& v = get(c);
            return std::string(v).empty() ? std::string() : toml_string(std::string(v));
          }};
}

template <class Get>
KeyDef string_list_key(std::string_view section, std::string_view name, std::string_view help, Get get,
                       std::size_t exact) {
  return {section, name, std::string(help), "",
          [=](Config& c, const toml::node& n, const KeyContext& k) {
            const toml::array* a = n.as_array();
            const std::string count = exact != 0 ? fmt::format("{}", exact) : std::string("one or more");
            if (a == nullptr || a->empty() || (exact != 0 && a->size() != exact)) {
              k.fail(fmt::format("expected an array of {} strings", count));
            }
            std::vector<std::string> values;
            for (const toml::node& item : *a) {
              if (!item.is_string() || item.value<std::string>()->empty()) k.fail("array items must be non-empty strings");
              values.push_back(*item.value<std::string>());
            }
            auto& target = get(c);
            if constexpr (requires { target.assign(values.begin(), values.end()); }) {
              target.assign(values.begin(), values.end());  // std::vector
            } else {
              std::copy(values.begin(), values.end(), target.begin());  // std::array, size checked
            }
          },
          [=](const Config& c) {
            std::vector<std::string> quoted;
            for (const auto& s : get(c)) quoted.push_back(toml_string(s));
            return fmt::format("[{}]", fmt::join(quoted, ", "));
          }};
}

template <class Get>
KeyDef duration_key(std::string_view section, std::string_view name, std::string_view help, Get get) {
  return {section, name, std::string(help), "",
          [=](Config& c, const toml::node& n, const KeyContext& k) { get(c) = parse_duration(read_string(n, k), k.where); },
          [=](const Config& c) { return toml_string(format_duration(get(c))); }};
}

/// A string key naming one of `choices`, spelt by the enum's own name function (the one the
/// summaries write, so a config and a summary always use the same words); the help lists the
/// names.
template <class Get, class E>
KeyDef enum_key(std::string_view section, std::string_view name, std::string_view help, Get get,
                std::initializer_list<E> choices, std::string_view (*spell)(E)) {
  std::vector<std::pair<std::string, E>> values;
  for (const E e : choices) values.emplace_back(spell(e), e);
  std::vector<std::string> quoted;
  for (const auto& v : values) quoted.push_back(toml_string(v.first));
  return {section, name, fmt::format("{}: {}", help, fmt::join(quoted, ", ")), "",
          [=](Config& c, const toml::node& n, const KeyContext& k) {
            const std::string s = read_string(n, k);
            for (const auto& v : values) {
              if (v.first == s) {
                get(c) = v.second;
                return;
              }
            }
            k.fail(fmt::format("'{}': expected one of {}", s, fmt::join(quoted, ", ")));
          },
          [=](const Config& c) {
            for (const auto& v : values) {
              if (v.second == get(c)) return toml_string(v.first);
            }
            return std::string();
          }};
}

std::vector<KeyDef> make_keys() {
  using P = std::string_view;
  std::vector<KeyDef> keys;
  const P project = "project", input = "input", change = "change", mosaic = "mosaic", tiling = "tiling",
          run = "run", output = "output";

  keys.push_back(string_key(project, "crs",
      "projected CRS of all coordinates: EPSG:2154 (Lambert-93), EPSG:32601..32660 or "
      "EPSG:32701..32760 (UTM north/south), or ENU:lat,lon,h (local frame)",
      [](auto& c) -> auto& { return c.project.crs; }, "\"EPSG:2154\""));
  keys.push_back(string_key(project, "vertical_datum",
      "what z means: \"ellipsoidal\" (height above the ellipsoid) or \"orthometric\" (above the geoid, "
      "set geoid_undulation)",
      [](auto& c) -> auto& { return c.project.vertical_datum; }, "\"ellipsoidal\""));
  keys.push_back(real_key(project, "geoid_undulation",
      "geoid height N above the ellipsoid in metres, for orthometric z (ellipsoidal h = z + N)",
      [](auto& c) -> auto& { return c.project.geoid_undulation; }, -150, 150));
  keys.push_back({project, "output", "folder for results (relative paths: to this file's folder)", "",
      [](Config& c, const toml::node& n, const KeyContext& k) { c.project.output = read_string(n, k); },
      [](const Config& c) { return toml_string(c.project.output.string()); }});
  keys.push_back({project, "work", "folder for intermediate tiles and resume state", "",
      [](Config& c, const toml::node& n, const KeyContext& k) { c.project.work = read_string(n, k); },
      [](const Config& c) { return toml_string(c.project.work.string()); }});

  keys.push_back(string_list_key(input, "sensor_origin",
      "the three vertex properties holding the sensor position of each point",
      [](auto& c) -> auto& { return c.input.sensor_origin; }, 3));
  keys.push_back(string_list_key(input, "time", "vertex property names tried in turn for the per-point time",
      [](auto& c) -> auto& { return c.input.time; }, 0));
  keys.push_back(string_key(input, "intensity", "vertex property holding the intensity",
      [](auto& c) -> auto& { return c.input.intensity; }));

  keys.push_back(real_key(change, "distance_threshold",
      "surfaces closer than this are the same surface (metres)",
      [](auto& c) -> auto& { return c.change.distance_threshold; }, 0.001, 10));
  keys.push_back(real_key(change, "conflict_margin",
      "a triangle must lie this far inside a newer empty space to conflict (metres)",
      [](auto& c) -> auto& { return c.change.conflict_margin; }, 0, 10));
  keys.push_back(enum_key(change, "empty_space",
      "how far a triangle's empty space reaches: the whole tetrahedron to its viewpoint (the paper), or no farther "
      "than its nearest corner's range (nearest-sample: facets bridging an occluding edge do not carve what lies "
      "behind the edge)",
      [](auto& c) -> auto& { return c.change.empty_space; },
      {EmptySpaceReach::tetrahedron, EmptySpaceReach::nearest_sample}, empty_space_reach_name));
  keys.push_back(real_key(change, "normal_angle",
      "largest angle between the normals of consistent triangles (degrees)",
      [](auto& c) -> auto& { return c.change.normal_angle; }, 0, 90));
  keys.push_back(duration_key(change, "sustainability",
      "Ts: a surface seen over at least this span is sustainable (e.g. \"30d\", \"12h\")",
      [](auto& c) -> auto& { return c.change.sustainability; }));
  keys.push_back(enum_key(change, "unconfirmed",
      "triangles neither conflicting nor sustainable: drop them (the paper), keep them unless a newer scan "
      "saw their place (keep-unobserved), or keep them",
      [](auto& c) -> auto& { return c.change.unconfirmed; },
      {UnconfirmedPolicy::drop, UnconfirmedPolicy::keep_unobserved, UnconfirmedPolicy::keep},
      unconfirmed_policy_name));
  keys.push_back(real_key(change, "voxel_size",
      "voxel edge of the empty-space grids used by the pre-filter and keep-unobserved (metres)",
      [](auto& c) -> auto& { return c.change.voxel_size; }, 0.05, 10));
  keys.push_back(bool_key(change, "prefilter",
      "skip exact conflict tests where the empty-space grids show no newer empty space (never changes results)",
      [](auto& c) -> auto& { return c.change.prefilter; }));

  keys.push_back(enum_key(mosaic, "method",
      "how kept triangles are merged: the paper's energy solved by QPBO, or its baseline (keep unless something "
      "older lies within the distance threshold)",
      [](auto& c) -> auto& { return c.mosaic.method; },
      {MosaicMethod::energy, MosaicMethod::update_model}, mosaic_method_name));
  keys.push_back(enum_key(mosaic, "quality", "per-triangle quality Q (constant favours the finer mesh)",
      [](auto& c) -> auto& { return c.mosaic.quality; },
      {QualityMeasure::constant, QualityMeasure::area, QualityMeasure::resolution}, quality_measure_name));
  keys.push_back(real_key(mosaic, "quality_weight", "lambda 1: reward for keeping quality",
      [](auto& c) -> auto& { return c.mosaic.quality_weight; }, 0, 1e6));
  keys.push_back(real_key(mosaic, "boundary_weight", "lambda 2: cost per mean edge length of mesh boundary kept",
      [](auto& c) -> auto& { return c.mosaic.boundary_weight; }, 0, 1e6));
  keys.push_back(real_key(mosaic, "overlap_weight", "lambda 3: cost of keeping two overlapping triangles",
      [](auto& c) -> auto& { return c.mosaic.overlap_weight; }, 0, 1e9));
  keys.push_back(real_key(mosaic, "seam_weight", "lambda 4: cost per mean edge length of seam inside a mesh",
      [](auto& c) -> auto& { return c.mosaic.seam_weight; }, 0, 1e6));
  keys.push_back(real_key(mosaic, "crease_angle",
      "a seam inside a mesh is along a crease where its two triangles' normals are more than this apart (degrees)",
      [](auto& c) -> auto& { return c.mosaic.crease_angle; }, 0, 180));
  keys.push_back(real_key(mosaic, "crease_weight",
      "a seam along a crease costs this times seam_weight, so that pieces end on flat surface rather than at corners (1: off)",
      [](auto& c) -> auto& { return c.mosaic.crease_weight; }, 0, 1e6));
  keys.push_back(real_key(mosaic, "seen_through_quality",
      "the quality Q of a candidate that another pass saw through (inside its empty space, as for fill_holes) is multiplied by this (1: off)",
      [](auto& c) -> auto& { return c.mosaic.seen_through_quality; }, 0, 1));
  keys.push_back(count_key(mosaic, "sweeps", "sweeps of group moves at most (each re-solves every acquisition against what is kept)",
      [](auto& c) -> auto& { return c.mosaic.sweeps; }, 1, 100));
  keys.push_back(count_key(mosaic, "later_sweep_reach",
      "sweeps after the first re-solve each acquisition only within this many terms of a seam, where the first sweep's "
      "pieces meet (0: everywhere)",
      [](auto& c) -> auto& { return c.mosaic.later_sweep_reach; }, 0, 100000));
  keys.push_back(real_key(mosaic, "stitch_reach",
      "stitching joins boundaries of pieces from different sources closer than this times distance_threshold",
      [](auto& c) -> auto& { return c.mosaic.stitch_reach; }, 0.1, 100));
  keys.push_back(bool_key(
      mosaic, "stitch_own_pieces",
      "stitching also joins the pieces of one pass that share no vertex (the turns of a spinning scanner, "
      "meshed one by one); where two lie within distance_threshold of each other, clipping cuts back the "
      "later one in the pass's file "
      "(fewer cracks and layers, more holes: see docs/mosaic.md)",
      [](auto& c) -> auto& { return c.mosaic.stitch_own_pieces; }));
  keys.push_back(bool_key(mosaic, "fill_holes",
      "after the energy mosaic, add back kept triangles with nothing selected within distance_threshold (newest first), "
      "unless another pass saw through them (in its empty space, more than distance_threshold and at most 1 m in front of it)",
      [](auto& c) -> auto& { return c.mosaic.fill_holes; }));
  keys.push_back(bool_key(mosaic, "clip_overlaps",
      "before stitching, cut pieces back where they lie over a larger source's surface, so that boundaries meet",
      [](auto& c) -> auto& { return c.mosaic.clip_overlaps; }));
  keys.push_back(real_key(mosaic, "clip_reach",
      "clipping cuts a piece where a larger source's surface lies within this times distance_threshold",
      [](auto& c) -> auto& { return c.mosaic.clip_reach; }, 0.1, 10));
  keys.push_back(real_key(mosaic, "clip_angle",
      "clipping cuts a piece only where its normal is within this of the larger source's (degrees; a wall on the ground, 90, is not cut)",
      [](auto& c) -> auto& { return c.mosaic.clip_angle; }, 0, 90));
  keys.push_back(bool_key(mosaic, "close_gaps",
      "after stitching, triangulate the small holes left between pieces of several sources (up to gap_width wide)",
      [](auto& c) -> auto& { return c.mosaic.close_gaps; }));
  keys.push_back(real_key(mosaic, "gap_width",
      "gap closing takes holes up to this times distance_threshold wide (twice the area over the perimeter) and twenty times that around",
      [](auto& c) -> auto& { return c.mosaic.gap_width; }, 0.1, 10));

  keys.push_back(real_key(tiling, "tile_size", "edge of a square tile (metres)",
      [](auto& c) -> auto& { return c.tiling.tile_size; }, 1, 100000));
  keys.push_back(real_key(tiling, "halo", "context copied from neighbouring tiles (metres, < tile_size / 2; at least the largest triangle's reach from its centroid plus distance_threshold, or run warns)",
      [](auto& c) -> auto& { return c.tiling.halo; }, 0, 10000));
  keys.push_back({tiling, "origin", "grid origin [easting, northing] in the project CRS (metres)", "",
      [](Config& c, const toml::node& n, const KeyContext& k) {
        const toml::array* a = n.as_array();
        if (a == nullptr || a->size() != 2 || !(*a)[0].value<double>() || !(*a)[1].value<double>()) {
          k.fail("expected [easting, northing]");
        }
        c.tiling.origin = {*(*a)[0].value<double>(), *(*a)[1].value<double>()};
      },
      [](const Config& c) { return fmt::format("[{}, {}]", c.tiling.origin[0], c.tiling.origin[1]); }});

  keys.push_back(count_key(run, "threads", "worker threads (0: all cores)",
      [](auto& c) -> auto& { return c.run.threads; }, 0, 1024));
  keys.push_back({run, "memory", "memory budget for tiles in flight (e.g. \"2GiB\", at least 64MiB)", "",
      [](Config& c, const toml::node& n, const KeyContext& k) {
        const std::uint64_t bytes = n.is_integer() ? static_cast<std::uint64_t>(std::max<std::int64_t>(0, *n.value<std::int64_t>()))
                                                   : parse_byte_size(read_string(n, k), k.where);
        if (bytes < (64u << 20)) k.fail("the memory budget must be at least 64MiB");
        c.run.memory = bytes;
      },
      [](const Config& c) { return toml_string(format_byte_size(c.run.memory)); }});
  keys.push_back(enum_key(run, "seam_pass",
      "how a tiled run's final pass stitches the output: blocks (block by block on the tile grid from files, in "
      "parallel: memory for a few parts, not the output), whole (at once, in memory), or auto (blocks when the tiles "
      "are over four times the stitching's reach wide, else whole; see docs/mosaic.md)",
      [](auto& c) -> auto& { return c.run.seam_pass; }, {SeamPass::automatic, SeamPass::whole, SeamPass::blocks},
      seam_pass_name));

  keys.push_back(bool_key(output, "tiles_3d", "write a 3D Tiles tileset with Draco-compressed glb tiles (false also removes an earlier run's)",
      [](auto& c) -> auto& { return c.output.tiles_3d; }));
  keys.push_back(bool_key(
      output, "mosaic_ply",
      "write the whole output as one PLY with provenance, mosaic/mosaic.ply (what citymesh eval scores; for a city, "
      "one PLY per tile, ply = true, may serve better; false also removes an earlier run's)",
      [](auto& c) -> auto& { return c.output.mosaic_ply; }));
  keys.push_back(bool_key(output, "ply", "also write one PLY per tile with provenance (source_acq, source_face; false also removes an earlier run's)",
      [](auto& c) -> auto& { return c.output.ply; }));
  keys.push_back(bool_key(output, "labels",
      "citymesh run: also write the change step's labelled PLY per acquisition (what eval scores; as large as the inputs on disk; written acquisition by acquisition, several at once when the memory budget holds them, with the pairs waiting on disk; false also removes an earlier run's)",
      [](auto& c) -> auto& { return c.output.labels; }));
  keys.push_back(real_key(output, "draco_tolerance", "largest position error of Draco quantization (metres)",
      [](auto& c) -> auto& { return c.output.draco_tolerance; }, 1e-5, 1));
  return keys;
}

}  // namespace

const std::vector<KeyDef>& config_keys() {
  static const std::vector<KeyDef> keys = make_keys();
  return keys;
}

const std::vector<std::string_view>& config_sections() {
  static const std::vector<std::string_view> sections{"project", "input", "change", "mosaic",
                                                      "tiling", "run", "output"};
  return sections;
}

const std::vector<std::string_view>& acquisition_keys() {
  static const std::vector<std::string_view> keys{"path", "time", "name", "withdrawn"};
  return keys;
}

}  // namespace citymesh::config_detail
