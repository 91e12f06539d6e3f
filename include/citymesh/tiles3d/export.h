// SPDX-License-Identifier: MIT
// Writing the output mesh as an OGC 3D Tiles 1.1 tileset of Draco-compressed glb tiles with
// levels of detail, placed on the globe (docs/3d-tiles.md).
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "citymesh/core/keyed_piece.h"
#include "citymesh/core/mesh.h"
#include "citymesh/encode/glb.h"
#include "citymesh/geo/crs.h"
#include "citymesh/tiler/tile_grid.h"
#include "citymesh/tiles3d/tile_tree.h"

namespace citymesh {

struct TilesetExportParams {
  std::filesystem::path dir;                 ///< replaced as a whole once every file is written
  TileGridParams grid;                       ///< the leaves are the tiles of this grid (the run's tiling)
  double tolerance = 0.001;                  ///< metres: the largest position error Draco quantization may add
  std::vector<GlbAcquisition> acquisitions;  ///< feature id k names acquisition k
  TileTreeParams tree;
  std::size_t max_tiles_per_file = 341;  ///< per tileset JSON file; deeper tiles go to external tilesets
  bool draco = true;
  int draco_speed = 5;
  /// Where encoded tiles are looked up before encoding and kept after (null: none): a tile
  /// whose mesh did not change since the run that kept it is not encoded again.
  GlbPrimitiveCache* primitives = nullptr;
};

struct TilesetExportStats {
  std::size_t tiles = 0, leaves = 0, levels = 0, json_files = 0;
  std::uint64_t leaf_triangles = 0, all_triangles = 0, glb_bytes = 0;
  int position_bits = 0;
  double quantization_step = 0.0;  ///< metres
  Geodetic origin;                 ///< of the local east-north-up frame
  double seconds = 0.0;
};

/// The output mesh to export: positions in the project CRS (mesh origin + floats), and per
/// triangle its source acquisition (-1: none, e.g. stitching) for the feature ids.
struct TilesetSource {
  const Mesh& mesh;
  std::span<const std::int32_t> source_acq;
  const Crs& crs;  ///< needs a vertical datum
};

/// Writes <dir>/tileset.json, external tilesets and one glb per tile. Vertices are converted
/// to a local east-north-up frame at the centre of the output (ECEF through geodetic
/// coordinates), quantized on one lattice shared by every tile so that equal vertices decode
/// bit-identically in neighbouring tiles. Throws ConfigError when the tolerance is too fine
/// for the output's extent, OutputError when a file cannot be written.
TilesetExportStats export_tileset(const TilesetSource& source, const TilesetExportParams& params);

/// Where positions in the project CRS lie in the tileset's local frame (map_to_local_frame: a
/// position maps to the same bits in any batch).
using LocalMapping = std::function<std::vector<Vec3f>(std::span<const Vec3d>)>;

/// An output given to the export one grid tile at a time, for an output too large to hold at
/// once. Called from several threads at once.
class TilesetLeaves {
 public:
  virtual ~TilesetLeaves() = default;
  /// The grid tiles holding triangles (the tree's leaves), ascending.
  [[nodiscard]] virtual std::vector<TileKey> keys() const = 0;
  /// The box of the output's vertices in the project CRS (the local frame is put at its centre).
  [[nodiscard]] virtual Box3d box() const = 0;
  /// Leaf `key`'s mesh (the triangles whose centroid the tile holds), positions mapped by
  /// `to_local`, each vertex keyed as the same vertex in every leaf (see tile_mesh).
  [[nodiscard]] virtual TileMesh leaf(const TileKey& key, const LocalMapping& to_local) const = 0;
  /// The box of leaf `key`'s vertices mapped by `to_local` (the export's first pass, which
  /// asks it of every leaf before leaf() is asked of any): by default that of leaf()'s
  /// positions.
  [[nodiscard]] virtual Box3d local_box(const TileKey& key, const LocalMapping& to_local) const;
};

/// What every process writing tiles of one export agrees on once the first pass has mapped
/// every leaf: the local frame and the Draco lattice.
struct TilesetFrame {
  Geodetic origin;            ///< of the local east-north-up frame
  DracoEncodeParams lattice;  ///< shared by every tile
};

/// A cell of the export's tree (TileTreeBuild::build_cell), its tiles written, the open
/// node's too.
struct ExportedCell {
  TileSubtree subtree;  ///< every node's mesh released but the open node's
  std::uint64_t glb_bytes = 0;
};

/// Builds cell `cell` of the export of `leaves` in `frame` and writes its tiles into the
/// export's staging folder (staging_directory(params.dir), which the export created): what
/// another process does for its share of an export. The same tiles as on the exporting process.
ExportedCell export_cell(const TilesetLeaves& leaves, const Crs& crs, const TilesetFrame& frame,
                         const TilesetExportParams& params, std::size_t cell);

/// How the cells of an export are built, given its frame, its tree and `here` (builds one in
/// this process, through export_cell): every cell's result, index: cell. The default builds
/// them all here, on the pool's threads; a cluster hands them out to its processes.
using ExportCells = std::function<std::vector<ExportedCell>(const TilesetFrame& frame, const TileTreeBuild& tree,
                                                            const std::function<ExportedCell(std::size_t)>& here)>;

/// Maps leaf `key` of `leaves` to the local frame at `origin` (TilesetLeaves::local_box):
/// what another process does for its share of the export's first pass.
Box3d export_leaf_box(const TilesetLeaves& leaves, const Crs& crs, const Geodetic& origin, const TileKey& key);

/// How the export's first pass maps the leaves, given the frame's origin, the leaves' keys and
/// `here` (maps leaf k in this process, through export_leaf_box): every leaf's box in the
/// local frame, index: leaf. The default maps them all here, on the pool's threads.
using ExportBoxes = std::function<std::vector<Box3d>(const Geodetic& origin, std::span<const TileKey> keys,
                                                     const std::function<Box3d(std::size_t)>& here)>;

/// The export's work that other processes can share; empty members: done here.
struct ExportWork {
  ExportBoxes boxes;
  ExportCells cells;
  /// Non-empty: the cells built are counted on stderr under this name (StageProgress, those
  /// of other processes when all are built), and the levels above them announced.
  std::string progress;
};

/// Writes the tileset of `leaves` as export_tileset writes a mesh's, reading each leaf twice
/// (once for the lattice, once for the tree) and holding only the tiles the tree is building.
/// The leaves are mapped by `work.boxes` and the tree's cells built by `work.cells` (default:
/// here); the levels above the cells are built here.
TilesetExportStats export_tileset(const TilesetLeaves& leaves, const Crs& crs, const TilesetExportParams& params,
                                  const ExportWork& work = {});

/// Some triangles of the output as a tile's mesh: one vertex per (vertex key, feature id of a
/// triangle using it; stitch triangles have none), positions mapped by `to_local`.
TileMesh tile_mesh(const KeyedPiece& piece, const LocalMapping& to_local);
/// The same with the piece's positions already mapped: `local`, one per vertex of `piece`.
TileMesh tile_mesh(const KeyedPiece& piece, std::span<const Vec3f> local);

/// The leaf (grid tile) of each triangle: the tile containing its centroid.
std::vector<TileKey> leaf_keys(const Mesh& mesh, const TileGrid& grid);

}  // namespace citymesh
