// SPDX-License-Identifier: MIT
#include "tileset_json.h"

#include <algorithm>
#include <nlohmann/json.hpp>

#include "citymesh/core/error.h"

namespace citymesh {

namespace {

nlohmann::json box_json(const Box3d& box, const TilesetJsonParams& params) {
  const Vec3d c = (box.min + box.max) * 0.5;
  auto half = [&](double lo, double hi) {
    return std::max((hi - lo) * 0.5 + params.box_margin, params.min_half_extent);
  };
  return {{"box",
           {c.x, c.y, c.z, half(box.min.x, box.max.x), 0, 0, 0, half(box.min.y, box.max.y), 0, 0, 0,
            half(box.min.z, box.max.z)}}};
}

/// Tiles in each node's subtree, itself included (children come before their parents).
std::vector<std::size_t> subtree_sizes(const TileTree& tree) {
  std::vector<std::size_t> size(tree.nodes.size(), 1);
  for (std::size_t n = 0; n < tree.nodes.size(); ++n) {
    for (const std::uint32_t c : tree.nodes[n].children) size[n] += size[c];
  }
  return size;
}

class Writer {
 public:
  Writer(const TileTree& tree, const TilesetJsonParams& params)
      : tree_(tree), params_(params), subtree_(subtree_sizes(tree)) {}

  void write_file(std::uint32_t root, const std::string& file_name, bool main) {
    files_.emplace_back(file_name, std::string());
    const std::size_t slot = files_.size() - 1;
    const TileNode& node = tree_.nodes[root];
    std::size_t room = params_.max_tiles_per_file - 1;  // the root's tile is in
    nlohmann::json tile = tile_json(root, room);
    if (main) tile["transform"] = params_.transform;
    const double diagonal = norm(node.box.max - node.box.min);
    nlohmann::json asset{{"version", "1.1"}, {"generator", "citymesh"}};
    if (!params_.tileset_version.empty()) asset["tilesetVersion"] = params_.tileset_version;
    nlohmann::json tileset{
        {"asset", std::move(asset)},
        {"geometricError", main ? std::max(2 * node.geometric_error, diagonal) : node.geometric_error},
        {"root", std::move(tile)}};
    files_[slot].second = tileset.dump(1) + "\n";
  }

  std::vector<std::pair<std::string, std::string>> take() { return std::move(files_); }

 private:
  /// Tile n (already counted) with its children: a child's whole subtree when it fits in the
  /// `room` left in this file (keeping one tile for each later child), otherwise a tile that
  /// points at an external tileset holding that subtree. Files thus hold whole subtrees, as
  /// many tiles as allowed, whatever the depth (a parent may skip levels of the grid).
  nlohmann::json tile_json(std::uint32_t n, std::size_t& room) {
    const TileNode& node = tree_.nodes[n];
    nlohmann::json tile = tile_header(node);
    if (node.triangle_count > 0) tile["content"] = {{"uri", node.name() + ".glb"}};
    if (node.children.empty()) return tile;
    nlohmann::json children = nlohmann::json::array();
    for (std::size_t k = 0; k < node.children.size(); ++k) {
      const std::uint32_t c = node.children[k];
      const std::size_t later = node.children.size() - k - 1;
      if (subtree_[c] + later <= room) {
        room -= subtree_[c];
        std::size_t descendants = subtree_[c] - 1;  // room for exactly those: all inline
        children.push_back(tile_json(c, descendants));
      } else {
        room -= 1;
        children.push_back(external_tile(c));
      }
    }
    tile["children"] = std::move(children);
    return tile;
  }

  /// Tile c as a pointer to the external tileset "<name>.json" whose root it is.
  nlohmann::json external_tile(std::uint32_t c) {
    const TileNode& node = tree_.nodes[c];
    const std::string external = node.name() + ".json";
    write_file(c, external, false);
    nlohmann::json tile = tile_header(node);
    tile["content"] = {{"uri", external}};
    return tile;
  }

  /// What every tile of `node` says, in this file or pointing at another.
  [[nodiscard]] nlohmann::json tile_header(const TileNode& node) const {
    return {{"boundingVolume", box_json(node.box, params_)},
            {"geometricError", node.geometric_error},
            {"refine", "REPLACE"}};
  }

  const TileTree& tree_;
  const TilesetJsonParams& params_;
  std::vector<std::size_t> subtree_;
  std::vector<std::pair<std::string, std::string>> files_;
};

}  // namespace

std::vector<std::pair<std::string, std::string>> tileset_json_files(const TileTree& tree,
                                                                    const TilesetJsonParams& params) {
  if (tree.nodes.empty()) throw ProcessingError("tileset: nothing to write (the output has no triangles)");
  if (params.max_tiles_per_file < 5) throw ProcessingError("tileset: max_tiles_per_file must be at least 5");
  Writer writer(tree, params);
  writer.write_file(static_cast<std::uint32_t>(tree.nodes.size() - 1), "tileset.json", true);
  return writer.take();
}

}  // namespace citymesh
