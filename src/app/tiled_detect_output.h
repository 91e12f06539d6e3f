// SPDX-License-Identifier: MIT
// The change step's outputs of a tiled run: each acquisition's file read again, front to
// back, its labels from the tiles (spilled to disk by the assembly), a window at a time.
#pragma once

#include <memory>
#include <vector>

#include "acquisitions.h"
#include "detect_output.h"
#include "tile_assembly.h"

namespace citymesh::app {

/// Holds an acquisition's vertex positions (24 bytes each, to drop the degenerate triangles
/// as the tiler did) and a window of its labels, never its triangles: what the labelled PLY
/// and picture of an acquisition far larger than memory need. Acquisitions may be fed on
/// several threads at once (one reader each).
class TiledDetectOutput final : public DetectOutputSource {
 public:
  /// Bytes held per vertex while an acquisition is fed, with the writer's.
  static constexpr std::uint64_t kBytesPerVertex = 48;

  /// Reads the first vertices of the first acquisition that has any: every mesh shares their
  /// frame, as whole-mesh reading gives it.
  TiledDetectOutput(const Config& config, const LoadedAcquisitions& described, const TileAssembly& assembly);
  ~TiledDetectOutput() override;

  LabelledOutputParams layout(std::size_t k) override;
  void feed(std::size_t k, LabelledAcquisitionWriter& out) override;
  std::uint64_t write_pairs(const std::filesystem::path& path) override;
  [[nodiscard]] ChangeStats stats() const override { return assembly_.change_stats(); }

 private:
  class Feed;
  const Config& config_;
  const LoadedAcquisitions& described_;
  const TileAssembly& assembly_;
  Vec3d origin_;  ///< the first acquisition's frame, which every mesh shares
  std::vector<std::unique_ptr<PlyReader>> readers_;  ///< per acquisition, from layout() to feed()
};

}  // namespace citymesh::app
