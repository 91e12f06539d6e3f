// SPDX-License-Identifier: MIT
#include "tileset_json.h"

#include <algorithm>
#include <nlohmann/json.hpp>

#include "citymesh/core/error.h"

namespace citymesh {

namespace {

nlohmann::json box_json(const Box3d& box, const TilesetJsonParams& params) {
  const Vec3d c = (box.min + box.max) * 0.5;
  auto half = [&](double lo, double hi) { return std::max((hi - lo) * 0.5 + params.box_margin, params.min_half_extent); };
  return {{"box",
           {c.x, c.y, c.z, half(box.min.x, box.max.x), 0, 0, 0, half(box.min.y, box.max.y), 0, 0, 0,
            half(box.min.z, box.max.z)}}};
}

/// The levels of tiles one file holds below its root: 1 + 4 + ... + 4^depth <= max.
int levels_per_file(std::size_t max_tiles) {
  int depth = 0;
  std::size_t total = 1, width = 1;
  while (total + width * 4 <= max_tiles) {
    width *= 4;
    total += width;
    ++depth;
  }
  return depth;
}

class Writer {
 public:
  Writer(const TileTree& tree, const TilesetJsonParams& params)
      : tree_(tree), params_(params), depth_(levels_per_file(params.max_tiles_per_file)) {}

  void write_file(std::uint32_t root, const std::string& file_name, bool main) {
    files_.emplace_back(file_name, std::string());
    const std::size_t slot = files_.size() - 1;
    const TileNode& node = tree_.nodes[root];
    nlohmann::json tile = tile_json(root, 0);
    if (main) tile["transform"] = params_.transform;
    const double diagonal = norm(node.box.max - node.box.min);
    nlohmann::json tileset{{"asset", {{"version", "1.1"}, {"generator", "citymesh"}}},
                           {"geometricError", main ? std::max(2 * node.geometric_error, diagonal) : node.geometric_error},
                           {"root", std::move(tile)}};
    files_[slot].second = tileset.dump(1) + "\n";
  }

  std::vector<std::pair<std::string, std::string>> take() { return std::move(files_); }

 private:
  nlohmann::json tile_json(std::uint32_t n, int depth) {
    const TileNode& node = tree_.nodes[n];
    nlohmann::json tile{{"boundingVolume", box_json(node.box, params_)},
                        {"geometricError", node.geometric_error},
                        {"refine", "REPLACE"}};
    if (depth == depth_ && !node.children.empty()) {
      // The rest of this subtree lives in an external tileset whose root is this tile.
      const std::string external = node.name() + ".json";
      tile["content"] = {{"uri", external}};
      write_file(n, external, false);
      return tile;
    }
    if (!node.mesh.triangles.empty()) tile["content"] = {{"uri", node.name() + ".glb"}};
    if (!node.children.empty()) {
      nlohmann::json children = nlohmann::json::array();
      for (const std::uint32_t c : node.children) children.push_back(tile_json(c, depth + 1));
      tile["children"] = std::move(children);
    }
    return tile;
  }

  const TileTree& tree_;
  const TilesetJsonParams& params_;
  int depth_;
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
