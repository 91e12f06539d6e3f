// SPDX-License-Identifier: MIT
#include "output_ranks.h"

#include <fmt/format.h>

#include <atomic>
#include <cstring>
#include <fstream>
#include <map>
#include <memory>
#include <optional>

#include "byte_arrays.h"
#include "citymesh/core/atomic_file.h"
#include "citymesh/core/checksum.h"
#include "citymesh/core/error.h"
#include "citymesh/core/interrupt.h"
#include "citymesh/core/log.h"
#include "citymesh/core/parallel.h"
#include "citymesh/core/read_file.h"
#include "json_bits.h"
#include "kept_files.h"
#include "shared_steps.h"
#include "tileset_output.h"
#include "work_schedule.h"

namespace citymesh::app {

namespace {

/// The plan of the step being shared, written by the root before it shares the step.
std::filesystem::path plan_path(const Config& config) { return config.project.work / "output-step.json"; }

/// What another rank needs for one step:
/// - "split": file the stitched parts `parts` of `parts_dir` by grid tile into `dir`;
/// - "merge": write each leaf file `leaf_files[l]` from its shares `shares[l]`;
/// - "boxes": map the output's tiles (`leaves`, in `dir`) to the frame at `frame.origin`;
/// - "cells": build the export's cells in `frame`, from the same tiles;
/// - "plys": write each tile's (`leaves`, in `dir`) provenance PLY to `leaf_files`;
/// - "end": nothing more.
struct StepPlan {
  std::string step;
  std::filesystem::path dir;
  std::filesystem::path parts_dir;
  std::vector<BlockPartKey> parts;
  std::vector<std::filesystem::path> leaf_files;
  std::vector<std::vector<std::filesystem::path>> shares;
  std::vector<TileKey> leaves;
  TilesetFrame frame;
};

/// A plan of step `step` reading the output's tiles in `dir` (or nothing).
StepPlan plan_of(std::string step, std::filesystem::path dir = {}) {
  StepPlan plan;
  plan.step = std::move(step);
  plan.dir = std::move(dir);
  return plan;
}

std::string absolute_or_empty(const std::filesystem::path& p) {
  return p.empty() ? std::string() : std::filesystem::absolute(p).string();
}

void write_plan(const Config& config, const StepPlan& plan) {
  nlohmann::json leaves = nlohmann::json::array();
  for (const TileKey& k : plan.leaves) leaves.push_back(tile_key_json(k));
  const TilesetFrame& f = plan.frame;
  nlohmann::json lattice = nlohmann::json::array();
  if (f.lattice.lattice) {
    for (const float v : f.lattice.lattice->origin) lattice.push_back(float_bits(v));
    lattice.push_back(float_bits(f.lattice.lattice->range));
  }
  nlohmann::json leaf_files = nlohmann::json::array(), shares = nlohmann::json::array();
  for (const std::filesystem::path& file : plan.leaf_files) leaf_files.push_back(absolute_or_empty(file));
  for (const auto& of_leaf : plan.shares) {
    nlohmann::json files = nlohmann::json::array();
    for (const std::filesystem::path& file : of_leaf) files.push_back(absolute_or_empty(file));
    shares.push_back(files);
  }
  const nlohmann::json j{
      {"step", plan.step},
      {"dir", absolute_or_empty(plan.dir)},
      {"parts_dir", absolute_or_empty(plan.parts_dir)},
      {"parts", block_part_keys_json(plan.parts)},
      {"leaf_files", leaf_files},
      {"shares", shares},
      {"leaves", leaves},
      {"origin", {double_bits(f.origin.lat), double_bits(f.origin.lon), double_bits(f.origin.height)}},
      {"position_bits", f.lattice.position_bits},
      {"speed", f.lattice.speed},
      {"lattice", lattice}};
  write_file_atomically(plan_path(config), j.dump() + "\n");
}

StepPlan read_plan(const Config& config) {
  return decode_json_file(plan_path(config), "rank 0's plan of a step of the final pass", [](const nlohmann::json& j) {
    StepPlan plan;
    plan.step = j.at("step").get<std::string>();
    plan.dir = j.at("dir").get<std::string>();
    plan.parts_dir = j.at("parts_dir").get<std::string>();
    plan.parts = block_part_keys_from(j.at("parts"));
    for (const auto& f : j.at("leaf_files")) plan.leaf_files.emplace_back(f.get<std::string>());
    for (const auto& of_leaf : j.at("shares")) {
      plan.shares.emplace_back();
      for (const auto& f : of_leaf) plan.shares.back().emplace_back(f.get<std::string>());
    }
    for (const auto& k : j.at("leaves")) plan.leaves.push_back(tile_key_from(k));
    const auto& o = j.at("origin");
    plan.frame.origin = {double_from_bits(o.at(0)), double_from_bits(o.at(1)), double_from_bits(o.at(2))};
    plan.frame.lattice.position_bits = j.at("position_bits").get<int>();
    plan.frame.lattice.speed = j.at("speed").get<int>();
    const auto& l = j.at("lattice");
    if (!l.empty()) {
      plan.frame.lattice.lattice = DracoLattice{
          {float_from_bits(l.at(0)), float_from_bits(l.at(1)), float_from_bits(l.at(2))}, float_from_bits(l.at(3))};
    }
    return plan;
  });
}

// A cell built on another rank comes back as two files beside the output's tiles: its nodes
// (JSON, doubles as bits) and the mesh of its open node (binary: the levels above read it).

std::filesystem::path cell_file(const std::filesystem::path& dir, std::size_t cell, std::string_view suffix) {
  return dir / fmt::format("cell-{}.{}", cell, suffix);
}

constexpr std::string_view kMeshMagic = "CMCELL01";
constexpr std::uint32_t kIntensities = 1, kColors = 2;

/// What precedes the open mesh's arrays.
struct MeshHeader {
  char magic[8];
  std::uint32_t flags;
  std::uint32_t reserved;
  std::uint64_t vertices, triangles, checksum;
};
static_assert(sizeof(MeshHeader) == 40 && sizeof(Vec3f) == 12 && sizeof(Rgb8) == 3 && sizeof(Triangle) == 12);

std::uint64_t mesh_payload_size(std::uint32_t flags, std::uint64_t n, std::uint64_t t) {
  std::uint64_t per_vertex = sizeof(std::uint64_t) + sizeof(std::uint16_t) + sizeof(Vec3f);
  if ((flags & kIntensities) != 0) per_vertex += sizeof(float);
  if ((flags & kColors) != 0) per_vertex += sizeof(Rgb8);
  return n * per_vertex + t * sizeof(Triangle);
}

std::string encode_tile_mesh(const TileMesh& m) {
  MeshHeader h{};
  std::memcpy(h.magic, kMeshMagic.data(), sizeof(h.magic));
  h.flags = (m.intensities.empty() ? 0u : kIntensities) | (m.colors.empty() ? 0u : kColors);
  h.vertices = m.vertex_count();
  h.triangles = m.triangles.size();
  std::vector<std::uint64_t> vertices;
  std::vector<std::uint16_t> features;
  for (const TileVertexKey& k : m.keys) {
    vertices.push_back(k.vertex);
    features.push_back(k.feature);
  }
  std::string payload;
  payload.reserve(mesh_payload_size(h.flags, h.vertices, h.triangles));
  put_array(payload, vertices);
  put_array(payload, features);
  put_array(payload, m.positions);
  put_array(payload, m.intensities);
  put_array(payload, m.colors);
  put_array(payload, m.triangles);
  h.checksum = bulk_checksum(payload.data(), payload.size());
  return std::string(reinterpret_cast<const char*>(&h), sizeof(h)) + payload;
}

TileMesh decode_tile_mesh(std::string_view bytes, const std::filesystem::path& source) {
  const auto refuse = [&](std::string_view why) {
    return ProcessingError(fmt::format("{}: not a 3D Tiles cell's mesh ({})", source.string(), why));
  };
  MeshHeader h{};
  if (bytes.size() < sizeof(h)) throw refuse("too short");
  std::memcpy(&h, bytes.data(), sizeof(h));
  if (std::string_view(h.magic, sizeof(h.magic)) != kMeshMagic) throw refuse("another magic");
  std::string_view in = bytes.substr(sizeof(h));
  // Counts are checked against the size before anything is allocated from them.
  if (h.vertices > in.size() || h.triangles > in.size() ||
      mesh_payload_size(h.flags, h.vertices, h.triangles) != in.size()) {
    throw refuse("its counts disagree with its size");
  }
  if (bulk_checksum(in.data(), in.size()) != h.checksum) throw refuse("its checksum does not match");
  const auto n = static_cast<std::size_t>(h.vertices);
  std::vector<std::uint64_t> vertices;
  std::vector<std::uint16_t> features;
  TileMesh m;
  take_array(in, vertices, n);
  take_array(in, features, n);
  take_array(in, m.positions, n);
  take_array(in, m.intensities, (h.flags & kIntensities) != 0 ? n : 0);
  take_array(in, m.colors, (h.flags & kColors) != 0 ? n : 0);
  take_array(in, m.triangles, static_cast<std::size_t>(h.triangles));
  for (std::size_t v = 0; v < n; ++v) m.keys.push_back({vertices[v], features[v]});
  for (const Triangle& t : m.triangles) {
    if (t[0] >= n || t[1] >= n || t[2] >= n) throw refuse("a triangle's corner is not one of its vertices");
  }
  return m;
}

nlohmann::json nodes_json(const ExportedCell& cell) {
  nlohmann::json nodes = nlohmann::json::array();
  for (const TileNode& n : cell.subtree.nodes) {
    nodes.push_back({{"level", n.level},
                     {"key", tile_key_json(n.key)},
                     {"triangles", n.triangle_count},
                     {"error", double_bits(n.geometric_error)},
                     {"box", box_bits(n.box)},
                     {"children", n.children}});
  }
  return {{"nodes", nodes},
          {"open", cell.subtree.open},
          {"open_is_final", cell.subtree.open_is_final},
          {"glb_bytes", cell.glb_bytes}};
}

/// Writes a cell built here for the root: the open node's mesh first, then the nodes (the
/// root reads them once this rank reports the cell done).
void write_cell(const std::filesystem::path& dir, std::size_t c, const ExportedCell& cell) {
  write_file_atomically(cell_file(dir, c, "mesh"), encode_tile_mesh(cell.subtree.nodes.at(cell.subtree.open).mesh));
  write_file_atomically(cell_file(dir, c, "json"), nodes_json(cell).dump());
}

/// Reads, and removes, a cell another rank built.
ExportedCell take_cell(const std::filesystem::path& dir, std::size_t c) {
  constexpr std::string_view kWhat = "a cell of the 3D Tiles export another rank built";
  const std::filesystem::path json_file = cell_file(dir, c, "json"), mesh_file = cell_file(dir, c, "mesh");
  ExportedCell cell = take_json_file(json_file, kWhat, [](const nlohmann::json& j) {
    ExportedCell out;
    for (const auto& n : j.at("nodes")) {
      TileNode& node = out.subtree.nodes.emplace_back();
      node.level = n.at("level").get<int>();
      node.key = tile_key_from(n.at("key"));
      node.triangle_count = n.at("triangles").get<std::size_t>();
      node.geometric_error = double_from_bits(n.at("error"));
      node.box = box_from_bits(n.at("box"));
      node.children = n.at("children").get<std::vector<std::uint32_t>>();
    }
    out.subtree.open = j.at("open").get<std::uint32_t>();
    out.subtree.open_is_final = j.at("open_is_final").get<bool>();
    out.glb_bytes = j.at("glb_bytes").get<std::uint64_t>();
    return out;
  });
  if (cell.subtree.open >= cell.subtree.nodes.size()) {
    throw ProcessingError(fmt::format("{}: its open node is not one of its nodes", json_file.string()));
  }
  const std::optional<std::string> bytes = read_file_bytes(mesh_file);
  if (!bytes) throw ProcessingError(fmt::format("{}: missing ({})", mesh_file.string(), kWhat));
  cell.subtree.nodes[cell.subtree.open].mesh = decode_tile_mesh(*bytes, mesh_file);
  std::filesystem::remove(mesh_file);
  return cell;
}

/// A part's shares another rank filed: beside them, in JSON.
std::filesystem::path shares_file(const std::filesystem::path& dir, std::size_t part) {
  return dir / fmt::format("part-{}.shares", part);
}

nlohmann::json shares_json(const std::vector<OutputShare>& shares) {
  nlohmann::json out = nlohmann::json::array();
  for (const OutputShare& s : shares) {
    out.push_back({{"key", tile_key_json(s.key)},
                   {"box", box_bits(s.box)},
                   {"triangles", s.triangles},
                   {"file", s.file.string()},
                   {"per_source", s.per_source},
                   {"stitched", s.stitched}});
  }
  return out;
}

std::vector<OutputShare> take_shares(const std::filesystem::path& dir, std::size_t part) {
  return take_json_file(shares_file(dir, part), "a part another rank filed", [](const nlohmann::json& list) {
    std::vector<OutputShare> shares;
    for (const auto& j : list) {
      OutputShare& s = shares.emplace_back();
      s.key = tile_key_from(j.at("key"));
      s.box = box_from_bits(j.at("box"));
      s.triangles = j.at("triangles").get<std::uint64_t>();
      s.file = j.at("file").get<std::string>();
      s.per_source = j.at("per_source").get<std::vector<std::uint64_t>>();
      s.stitched = j.at("stitched").get<std::uint64_t>();
    }
    return shares;
  });
}

/// A leaf's box another rank mapped: beside the leaf, as bits.
std::filesystem::path box_file(const std::filesystem::path& dir, const TileKey& key) {
  return dir / fmt::format("{}.box", key.name());
}

Box3d take_box(const std::filesystem::path& dir, const TileKey& key) {
  return take_json_file(box_file(dir, key), "a leaf another rank mapped", box_from_bits);
}

/// A step of the outputs on every rank, with this rank's threads.
SharedStep output_step() { return {.workers = available_threads(), .what = "the final pass", .progress = {}}; }

/// Shares one step with every rank: one item per cost (none for "end"), largest first.
void share_items(Cluster& cluster, std::vector<std::uint64_t> costs, const std::function<void(std::size_t)>& here) {
  app::share_items(cluster, std::move(costs), output_step(), here);
}

}  // namespace

LeafFilingWork share_leaf_filing(const Config& config, Cluster& cluster, const std::filesystem::path& parts_dir,
                                 std::vector<BlockPartKey> parts) {
  LeafFilingWork work;
  work.split = [&config, &cluster, parts_dir, parts](std::size_t count,
                                                     const std::function<std::vector<OutputShare>(std::size_t)>& here) {
    if (count != parts.size()) throw ProcessingError("the seam pass: other parts to file than those stitched");
    const std::filesystem::path dir = parts_dir / "tiles";
    StepPlan plan = plan_of("split", dir);
    plan.parts_dir = parts_dir;
    plan.parts = parts;
    write_plan(config, plan);
    return share_and_gather<std::vector<OutputShare>>(cluster, std::vector<std::uint64_t>(count, 1), output_step(),
                                                      "parts filed by grid tile", here,
                                                      [&](std::size_t p) { return take_shares(dir, p); });
  };
  work.merge = [&config, &cluster](std::span<const std::filesystem::path> files,
                                   std::span<const std::vector<std::filesystem::path>> shares,
                                   const std::function<void(std::size_t)>& here) {
    StepPlan plan = plan_of("merge");
    plan.leaf_files.assign(files.begin(), files.end());
    plan.shares.assign(shares.begin(), shares.end());
    write_plan(config, plan);
    std::vector<std::uint64_t> costs;  // the shares to read: largest leaf first
    for (const auto& of_leaf : shares) costs.push_back(of_leaf.size());
    share_items(cluster, std::move(costs), here);
  };
  return work;
}

ExportWork share_export(const Config& config, Cluster& cluster, const OutputLeaves& leaves) {
  // Each leaf's triangles: what mapping it costs, and with its cell's, building the cell.
  auto triangles = std::make_shared<std::map<TileKey, std::uint64_t>>();
  std::vector<TileKey> keys;
  for (const OutputLeaf& leaf : leaves.leaves()) {
    (*triangles)[leaf.key] = leaf.triangles;
    keys.push_back(leaf.key);
  }
  ExportWork work;
  work.boxes = [&config, &cluster, &leaves, triangles, keys](const Geodetic& origin, std::span<const TileKey> asked,
                                                             const std::function<Box3d(std::size_t)>& here) {
    if (!std::equal(asked.begin(), asked.end(), keys.begin(), keys.end())) {
      throw ProcessingError("3D Tiles: the export asks for other leaves than the output's");
    }
    StepPlan plan = plan_of("boxes", leaves.dir());
    plan.leaves = keys;
    plan.frame.origin = origin;
    write_plan(config, plan);
    std::vector<std::uint64_t> costs;
    for (const TileKey& k : keys) costs.push_back(triangles->at(k));
    return share_and_gather<Box3d>(cluster, std::move(costs), output_step(), "leaves mapped", here,
                                   [&](std::size_t k) { return take_box(leaves.dir(), keys[k]); });
  };
  work.cells = [&config, &cluster, &leaves, triangles, keys](const TilesetFrame& frame, const TileTreeBuild& tree,
                                                             const std::function<ExportedCell(std::size_t)>& here) {
    StepPlan plan = plan_of("cells", leaves.dir());
    plan.leaves = keys;
    plan.frame = frame;
    write_plan(config, plan);
    // Largest cell first, so that none is left to end the step alone.
    std::vector<std::uint64_t> costs(tree.cell_count(), 0);
    for (std::size_t c = 0; c < costs.size(); ++c) {
      for (const TileKey& k : tree.cell_leaves(c)) costs[c] += triangles->at(k);
    }
    return share_and_gather<ExportedCell>(cluster, std::move(costs), output_step(), "3D Tiles cells built", here,
                                          [&](std::size_t c) { return take_cell(leaves.dir(), c); });
  };
  return work;
}

LeafPlyWork share_leaf_plys(const Config& config, Cluster& cluster, const OutputLeaves& leaves) {
  return [&config, &cluster, &leaves](std::span<const std::filesystem::path> files,
                                      const std::function<void(std::size_t)>& here) {
    StepPlan plan = plan_of("plys", leaves.dir());
    for (const OutputLeaf& leaf : leaves.leaves()) plan.leaves.push_back(leaf.key);
    plan.leaf_files.assign(files.begin(), files.end());
    write_plan(config, plan);
    std::vector<std::uint64_t> costs;  // largest tile first
    for (const OutputLeaf& leaf : leaves.leaves()) costs.push_back(leaf.triangles);
    share_items(cluster, std::move(costs), here);
  };
}

void end_shared_outputs(const Config& config, Cluster& cluster) {
  write_plan(config, plan_of("end"));
  share_items(cluster, {}, [](std::size_t) {});
  std::error_code ec;
  std::filesystem::remove(plan_path(config), ec);
}

void help_outputs(const Config& config, Cluster& cluster) {
  std::atomic<std::size_t> filed = 0, merged = 0, mapped = 0, built = 0, plys = 0;
  const std::vector<std::int32_t> listed = config.listed_indices();
  const Crs crs = config.crs();
  ExportCaches cache(config.project.work);
  TilesetExportParams params = tileset_export_params(config);
  params.primitives = &cache.primitives;
  params.tree.simplified = &cache.simplified;
  const TileGrid grid({config.tiling.tile_size, config.tiling.halo, config.tiling.origin});
  for (;;) {
    // The root writes the plan before it shares the step, and sharing starts with a barrier.
    auto channel = cluster.share(nullptr, {});
    const StepPlan plan = read_plan(config);
    if (plan.step == "end") break;
    // Each result is written before the root hears that the item is done (the worker's next
    // request says so).
    const auto work = [&](const std::function<void(std::size_t)>& body) {
      work_on_shared_items(*channel, output_step(), body);
    };
    if (plan.step == "split") {
      const SeamPartFiles parts(plan.parts_dir, plan.parts);
      work([&](std::size_t p) {
        const std::vector<OutputShare> shares = file_part_shares(plan.dir, grid, parts, p);
        write_file_atomically(shares_file(plan.dir, p), shares_json(shares).dump());
        ++filed;
      });
      continue;
    }
    if (plan.step == "merge") {
      work([&](std::size_t l) {
        merge_leaf_file(plan.leaf_files.at(l), plan.shares.at(l));
        ++merged;
      });
      continue;
    }
    std::vector<OutputLeaf> leaves;
    for (const TileKey& k : plan.leaves) leaves.push_back({k, {}, 0});
    const OutputLeaves attached(plan.dir, std::move(leaves));
    const std::unique_ptr<TilesetLeaves> view = export_view(attached);
    if (plan.step == "boxes") {
      work([&](std::size_t k) {
        const Box3d box = export_leaf_box(*view, crs, plan.frame.origin, plan.leaves.at(k));
        write_file_atomically(box_file(plan.dir, plan.leaves[k]), box_bits(box).dump());
        ++mapped;
      });
    } else if (plan.step == "cells") {
      work([&](std::size_t c) {
        write_cell(plan.dir, c, export_cell(*view, crs, plan.frame, params, c));
        ++built;
      });
    } else if (plan.step == "plys") {
      work([&](std::size_t l) {
        write_leaf_ply(attached, l, plan.leaf_files.at(l), listed);
        ++plys;
      });
    } else {
      throw ProcessingError(
          fmt::format("{}: unknown step '{}' of the final pass", plan_path(config).string(), plan.step));
    }
  }
  log::info(
      "rank {}: filed {} parts and {} tiles of the output; mapped {} leaves and built {} cells of the 3D Tiles export; "
      "wrote {} per-tile PLYs",
      cluster.rank(), filed.load(), merged.load(), mapped.load(), built.load(), plys.load());
}

}  // namespace citymesh::app
