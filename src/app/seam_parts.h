// SPDX-License-Identifier: MIT
// The seam pass of a tiled run block by block in files (`[run] seam_pass = "blocks"`): every
// tile's selected triangles filed under the block-stitching part holding their centroid, in
// a folder of this process's own, then stitched level by level with only the parts around
// each one in memory (stitch_parts).
#pragma once

#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "citymesh/mosaic/merged_mesh.h"
#include "citymesh/mosaic/stitch_blocks.h"
#include "citymesh/tiler/tile_grid.h"
#include "citymesh/tiler/tile_store.h"

namespace citymesh::app {

/// What the folder of a run's seam parts is named after: "seams.<host>.<pid>".
inline constexpr std::string_view kSeamPartsPrefix = "seams.";

/// <work>/seams.<process tag>: this process's own (a killed run's is removed by the next run).
std::filesystem::path seam_parts_folder(const std::filesystem::path& work);

/// A keyed piece as bytes: magic, attribute flags, counts, XXH3 of the payload, the arrays.
std::string encode_keyed_piece(const KeyedPiece& piece);
/// The piece in `bytes`; throws ProcessingError naming `source` when they are not one
/// (another magic, counts that disagree with the size, a checksum that does not match).
KeyedPiece decode_keyed_piece(std::string_view bytes, std::string_view source);

/// A tile's selected triangles of one acquisition (as a tile result holds them) as a keyed
/// piece: vertices keyed by input_vertex_key, positions in the project CRS.
KeyedPiece keyed_piece(const TilePiece& piece);

/// The parts of a seam pass, in files under one folder (created empty, removed with this).
class SeamPartFiles final : public PartStore {
 public:
  /// Whose folder the parts are filed in: this object's (made empty, removed with it), or
  /// another process's (an MPI rank filing tiles for the root: never made nor removed here).
  enum class Folder { own, others };
  /// `blocks`: the grid, in the project CRS.
  SeamPartFiles(std::filesystem::path dir, const BlockStitchParams& blocks, Folder folder = Folder::own);
  /// The parts `keys` (in part order) of another process's folder `dir` (an MPI rank helping
  /// the root's seam pass): loads and saves them there, never creates nor removes the folder.
  SeamPartFiles(std::filesystem::path dir, std::vector<BlockPartKey> keys);
  ~SeamPartFiles() override;
  SeamPartFiles(const SeamPartFiles&) = delete;
  SeamPartFiles& operator=(const SeamPartFiles&) = delete;

  /// A tile's selected triangles written under their parts, not yet added.
  struct FiledTile {
    std::vector<BlockPartKey> parts;           ///< ascending
    std::vector<std::filesystem::path> files;  ///< per part: its fragment's file
    std::vector<Box3d> boxes;                  ///< per part: its fragment's box
    std::vector<std::uint64_t> source_sizes;   ///< per source acquisition
  };
  /// Writes the selected triangles of tile `key` under their parts; safe from several
  /// threads for different tiles.
  [[nodiscard]] FiledTile file_tile(TileKey key, const std::vector<TilePiece>& selected) const;
  /// Adds a tile file_tile() wrote. Tiles come one at a time, in the order of the output.
  void add_filed(const FiledTile& tile);
  /// Both at once.
  void add_tile(TileKey key, const std::vector<TilePiece>& selected) { add_filed(file_tile(key, selected)); }
  /// How finish() merges every part's fragments (merge_fragments): given the parts, their
  /// fragments and `here` (one part merged in this process). Empty: here, on the pool's threads.
  using PartMerging = std::function<void(std::span<const BlockPartKey> parts,
                                         std::span<const std::vector<std::filesystem::path>> fragments,
                                         const std::function<void(std::size_t)>& here)>;
  /// Puts each part's tiles together, its triangles in input order (acquisition, then
  /// triangle); the parts in key order with their boxes. Called once, after the last tile.
  [[nodiscard]] std::vector<BlockPart> finish(const PartMerging& merging = {});
  /// Writes part `key`'s input file from its tiles' `fragments` (in tile order), which are
  /// removed; safe from several threads (or processes) for different parts.
  void merge_fragments(const BlockPartKey& key, std::span<const std::filesystem::path> fragments) const;
  /// Per source acquisition: its triangles in the output (clipping's precedence).
  [[nodiscard]] const std::vector<std::uint64_t>& source_sizes() const { return source_sizes_; }

  [[nodiscard]] std::shared_ptr<const KeyedPiece> load(std::size_t part, bool stitched) const override;
  void save_stitched(std::size_t part, KeyedPiece stitched) override;
  /// Removes the part's input file: the disk holds about two copies of the output at most.
  void release_input(std::size_t part) override;
  /// Removes every stitched part's file, once the output is filed by tile (OutputLeaves).
  void release_stitched();
  [[nodiscard]] const std::filesystem::path& dir() const { return dir_; }
  /// Bytes of part `part`'s file before stitching: what stitching it costs, roughly.
  [[nodiscard]] std::uint64_t input_bytes(std::size_t part) const override;
  /// "<dir>/<part>.<suffix>": a file beside the part's (the outcome of its stitching).
  [[nodiscard]] std::filesystem::path beside(std::size_t part, std::string_view suffix) const;

 private:
  [[nodiscard]] std::filesystem::path part_file(const BlockPartKey& key, bool stitched) const;

  std::filesystem::path dir_;
  BlockStitchParams blocks_;
  std::map<BlockPartKey, std::vector<std::filesystem::path>> fragments_;  ///< per part, its tiles' files in order
  std::map<BlockPartKey, Box3d> boxes_;
  std::vector<BlockPartKey> keys_;  ///< the parts, once finished
  std::vector<std::uint64_t> source_sizes_;
  bool owned_ = true;  ///< the folder is this object's: made empty, removed with it
};

/// One stitched part's triangles in one grid tile of the output, in a file of their own.
struct OutputShare {
  TileKey key;
  Box3d box;
  std::uint64_t triangles = 0;
  std::filesystem::path file;
  std::vector<std::uint64_t> per_source;  ///< its triangles per source acquisition
  std::uint64_t stitched = 0;             ///< and stitching's
};

/// Stitched part `part` of `store` split by the grid tile holding each triangle's centroid,
/// each share written to `dir`: safe from several threads (or processes) for different parts.
std::vector<OutputShare> file_part_shares(const std::filesystem::path& dir, const TileGrid& grid,
                                          const PartStore& store, std::size_t part);

/// Writes `leaf_file` from the shares in `shares` (in order), which are removed.
void merge_leaf_file(const std::filesystem::path& leaf_file, std::span<const std::filesystem::path> shares);

/// How OutputLeaves files the output: each step given its item count and `here` (one item
/// done in this process); empty members: done here, on the pool's threads.
struct LeafFilingWork {
  /// Every stitched part split by grid tile (file_part_shares), index: part.
  std::function<std::vector<std::vector<OutputShare>>(std::size_t parts,
                                                      const std::function<std::vector<OutputShare>(std::size_t)>& here)>
      split;
  /// Every leaf's file written from its shares (merge_leaf_file): `files[l]` from `shares[l]`.
  std::function<void(std::span<const std::filesystem::path> files,
                     std::span<const std::vector<std::filesystem::path>> shares,
                     const std::function<void(std::size_t)>& here)>
      merge;
};

/// A grid tile of the output: its key and what its triangles span.
struct OutputLeaf {
  TileKey key;
  Box3d box;  ///< of its triangles' corners, in the project CRS
  std::uint64_t triangles = 0;
};

/// The stitched output by grid tile (the tile holding each triangle's centroid), in files:
/// what the outputs read one tile at a time.
class OutputLeaves {
 public:
  /// Files the triangles of the stitched `parts` under their tiles, in `dir` (created empty,
  /// removed with this); reads each part once. `work` may share the filing with other
  /// processes.
  OutputLeaves(std::filesystem::path dir, const TileGrid& grid, std::span<const BlockPart> parts,
               const PartStore& store, const LeafFilingWork& work = {});
  /// The tiles `leaves` (keys ascending) of another process's folder `dir` (an MPI rank
  /// helping the root's export): reads them there, never creates nor removes the folder.
  OutputLeaves(std::filesystem::path dir, std::vector<OutputLeaf> leaves);
  ~OutputLeaves();
  OutputLeaves(const OutputLeaves&) = delete;
  OutputLeaves& operator=(const OutputLeaves&) = delete;

  /// The tiles holding triangles, keys ascending.
  [[nodiscard]] const std::vector<OutputLeaf>& leaves() const { return leaves_; }
  /// Tile `leaf`'s triangles (part by part, each part's in order), vertices in key order.
  [[nodiscard]] KeyedPiece load(std::size_t leaf) const;
  /// The output's triangles per source acquisition (index: source_acq), and stitching's.
  [[nodiscard]] const std::vector<std::uint64_t>& per_source() const { return per_source_; }
  [[nodiscard]] std::uint64_t stitched() const { return stitched_; }
  /// The box of every triangle's corners, in the project CRS.
  [[nodiscard]] Box3d box() const;
  /// Keeps `bytes` beside tile `leaf` under `name` (an output's notes on the tile, scratch
  /// like the tiles); safe from several threads for different tiles.
  void keep(std::size_t leaf, std::string_view name, std::string_view bytes) const;
  /// What keep() kept; throws ProcessingError when it is gone.
  [[nodiscard]] std::string kept(std::size_t leaf, std::string_view name) const;
  [[nodiscard]] const std::filesystem::path& dir() const { return dir_; }

 private:
  std::filesystem::path dir_;
  std::vector<OutputLeaf> leaves_;

  [[nodiscard]] std::filesystem::path leaf_file(const OutputLeaf& leaf) const;

  std::vector<std::uint64_t> per_source_;
  std::uint64_t stitched_ = 0;
  bool owned_ = true;  ///< the folder is this object's: made empty, removed with it
};

}  // namespace citymesh::app
