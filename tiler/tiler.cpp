// SPDX-License-Identifier: MIT
#include "citymesh/tiler/tiler.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <span>

#include "citymesh/core/atomic_file.h"
#include "citymesh/core/error.h"
#include "citymesh/core/interrupt.h"
#include "citymesh/core/log.h"
#include "citymesh/core/parallel.h"
#include "citymesh/core/stopwatch.h"
#include "citymesh/core/triangle_reach.h"
#include "store_files.h"
#include "tile_block_writer.h"

namespace citymesh {

namespace {

/// One acquisition's vertices, whole: faces refer to any of them.
struct AcquisitionVertices {
  std::vector<Vec3d> positions, sensors;
  std::vector<float> intensities;
  std::vector<Rgb8> colors;

  void append(const PlyVertexChunk& c) {
    positions.insert(positions.end(), c.positions.begin(), c.positions.end());
    sensors.insert(sensors.end(), c.sensor_positions.begin(), c.sensor_positions.end());
    intensities.insert(intensities.end(), c.intensities.begin(), c.intensities.end());
    colors.insert(colors.end(), c.colors.begin(), c.colors.end());
  }

  /// The block flags of the attributes the acquisition has.
  [[nodiscard]] std::uint32_t flags() const {
    return tiler_detail::attribute_flags(!intensities.empty(), !colors.empty());
  }
};

/// A triangle of the current batch: what its copies need once the batch is written.
struct BatchTriangle {
  Triangle corners;  ///< vertex ids in the acquisition
  std::uint32_t fan = 0;
  std::uint64_t face = 0;
  std::uint32_t index = 0;  ///< in the acquisition (PlyReader's order)
};

/// One copy of a batch triangle bound for a tile: the tile's slot in the batch and the role.
struct TileCopy {
  std::uint32_t triangle;   ///< in the batch
  std::uint32_t slot_role;  ///< slot << 2 | role
};

/// A tile the current batch sends triangles to.
struct BatchTile {
  TileKey key;
  std::array<std::uint64_t, 3> counts{};  ///< copies per role
  std::uint32_t copies = 0;               ///< in all
};

/// Memory one copy takes in the block of its tile while that tile is written: its varints up
/// to 52 bytes and a new vertex up to 42 more (a tile's copies bring fewer new vertices than
/// that on average: a mesh has about half as many vertices as triangles). Only the largest
/// tile of a batch is ever built at once.
constexpr std::uint64_t kBlockBytesPerCopy = 96;
/// A batch is written once it holds this much, even when the budget allows more: larger
/// batches gain nothing (their blocks go to the same files) and touch fresh memory, whose
/// page faults took a fifth of the tiler's time with batches of a quarter of a 2 GiB budget.
constexpr std::uint64_t kMaxBatchBytes = 32ull << 20;
/// Batch triangles are numbered in 30 bits (TileCopy, the sorted copies).
constexpr std::size_t kMaxBatchTriangles = (std::size_t{1} << 30) - 1;

/// Tiles one acquisition in batches: each triangle's destinations (owner, halo tiles, tiles
/// its empty space crosses) are recorded as it is read; when the batch is full, its copies are
/// sorted by tile and each tile's block is encoded by one reused writer and appended to the
/// tile's chunk file. A tile's triangles keep their input order and its vertices their order
/// of first use, so the blocks do not depend on how the work is done.
class AcquisitionTiler {
 public:
  /// Appends to `blocks_file`, created empty.
  AcquisitionTiler(const TileGrid& grid, const std::filesystem::path& blocks_file, AcquisitionTiling& out,
                   std::uint64_t buffer_bytes)
      : grid_(grid), out_(out), buffer_bytes_(std::min(buffer_bytes, kMaxBatchBytes)), blocks_file_(blocks_file) {}

  void run(const std::filesystem::path& file, PlyReadParams ply) {
    // The tile store carries no per-vertex times, so they are not parsed.
    ply.time_names.clear();
    PlyReader reader(file, ply);
    check_has_faces(file, reader.header());
    if (reader.vertex_count() > std::uint64_t{UINT32_MAX}) {
      throw InputError(fmt::format("{}: {} vertices; the tile store numbers them in 32 bits (split the file)",
                                   file.string(), reader.vertex_count()));
    }
    reserve_vertices(reader.vertex_count());
    PlyVertexChunk vertices;
    PlyFaceChunk faces;
    for (;;) {
      throw_if_interrupted("tiling");
      const PlyReader::ChunkKind kind = reader.next(vertices, faces);
      if (kind == PlyReader::ChunkKind::end) break;
      if (kind == PlyReader::ChunkKind::vertices) {
        vertices_.append(vertices);
        slots_.resize(vertices_.positions.size(), 0);
        continue;
      }
      for (std::size_t t = 0; t < faces.triangles.size(); ++t) {
        const Triangle& tri = faces.triangles[t];
        check_vertices_read(file, faces.faces[t], tri, vertices_.positions.size());
        if (!add_triangle({tri, faces.fans[t], faces.faces[t], next_index_}, file)) continue;
        ++next_index_;
        if (batch_bytes() > buffer_bytes_ || batch_.size() >= kMaxBatchTriangles) flush();
      }
    }
    finish();
    if (zero_area_dropped_ > 0) log::info("{}: dropped {} zero-area triangles", file.string(), zero_area_dropped_);
    out_.triangles = next_index_;
    out_.stats.input_bytes += reader.stats().bytes;
    out_.stats.largest_radius = std::sqrt(largest_radius_squared_);
  }

  /// Writes what is buffered and closes the blocks file: after run(), or alone for a
  /// withdrawn acquisition (no triangle).
  void finish() {
    flush();
    blocks_file_.close();
  }

 private:
  /// Room for the header's vertex count at once: growing by doubling touched (and zeroed)
  /// twice the pages and copied every vertex several times. The reader has already checked
  /// the header's counts against the file's size, so a lying header cannot ask for much.
  void reserve_vertices(std::uint64_t declared) {
    const auto n = static_cast<std::size_t>(declared);
    vertices_.positions.reserve(n);
    vertices_.sensors.reserve(n);
    slots_.reserve(n);
  }

  /// What the batch holds, and the largest tile's block while it is written.
  [[nodiscard]] std::uint64_t batch_bytes() const {
    return batch_.size() * sizeof(BatchTriangle) + copies_.size() * (sizeof(TileCopy) + sizeof(std::uint32_t)) +
           std::uint64_t{largest_tile_} * kBlockBytesPerCopy;
  }

  /// Records where `triangle` goes (`file` names the input for its errors), unless it is
  /// degenerate: then returns false (whole-mesh reading drops the same triangles, so both
  /// number the others alike).
  bool add_triangle(const BatchTriangle& triangle, const std::filesystem::path& file) {
    const Triangle& tri = triangle.corners;
    const std::array<Vec3d, 3> c{vertices_.positions[tri[0]], vertices_.positions[tri[1]], vertices_.positions[tri[2]]};
    Box3d corners;
    for (const Vec3d& p : c) corners.extend(p);
    check_face_extent(file, triangle.face, corners, c[0], c[1], c[2]);
    if (degenerate_input_triangle(c[0], c[1], c[2])) {
      ++zero_area_dropped_;
      return false;
    }
    note_radius(c, corners);
    const auto t = static_cast<std::uint32_t>(batch_.size());
    batch_.push_back(triangle);
    const Vec3d viewpoint = (vertices_.sensors[tri[0]] + vertices_.sensors[tri[1]] + vertices_.sensors[tri[2]]) / 3.0;
    // Most triangles lie, with their viewpoint, inside the previous triangle's owner: that
    // tile owns them and no other gets a copy (what owner() and copy_targets() would say).
    Box3d reach = corners;
    reach.extend(viewpoint);
    if (last_interior_.holds(reach)) {
      add_copy(last_interior_.key, t, TileRole::owned);
      return true;
    }
    const TileKey owner = grid_.owner((c[0] + c[1] + c[2]) / 3.0);
    // Most triangles that get here lie near a side of the same tile (98 % on the city).
    if (owner != last_interior_.key) last_interior_ = grid_.interior(owner);
    add_copy(owner, t, TileRole::owned);
    grid_.copy_targets(c, viewpoint, owner, halo_, crossed_);
    for (const TileKey k : halo_) add_copy(k, t, TileRole::halo);
    for (const TileKey k : crossed_) add_copy(k, t, TileRole::empty_space);
    out_.stats.halo_copies += halo_.size();
    out_.stats.empty_space_copies += crossed_.size();
    return true;
  }

  /// Keeps the largest x-y distance from a centroid to a corner (TilingStats::largest_radius),
  /// squared. The box's diagonal bounds it, so only the rare triangle whose box could beat the
  /// largest so far costs the exact distances.
  void note_radius(const std::array<Vec3d, 3>& c, const Box3d& box) {
    const double dx = box.max.x - box.min.x, dy = box.max.y - box.min.y;
    if (dx * dx + dy * dy <= largest_radius_squared_) return;
    largest_radius_squared_ = std::max(largest_radius_squared_, horizontal_reach_squared(c));
  }

  void add_copy(TileKey key, std::uint32_t triangle, TileRole role) {
    // Consecutive triangles mostly go to the same tile: skip the map lookup then.
    if (tiles_.empty() || key != tiles_[last_slot_].key) {
      const auto [it, added] = slot_of_.try_emplace(key, static_cast<std::uint32_t>(tiles_.size()));
      if (added) tiles_.push_back({key, {}, 0});
      last_slot_ = it->second;
    }
    copies_.push_back({triangle, last_slot_ << 2 | static_cast<std::uint32_t>(role)});
    BatchTile& tile = tiles_[last_slot_];
    ++tile.counts[static_cast<std::size_t>(role)];
    largest_tile_ = std::max(largest_tile_, ++tile.copies);
  }

  /// Writes one block per tile of the batch (in key order) and empties the batch.
  void flush() {
    // Copies grouped by tile, each tile's in input order (a stable counting sort).
    std::vector<std::uint32_t> start(tiles_.size() + 1, 0);
    for (std::size_t s = 0; s < tiles_.size(); ++s) start[s + 1] = start[s] + tiles_[s].copies;
    sorted_.resize(copies_.size());
    std::vector<std::uint32_t> at(start.begin(), start.end() - 1);
    for (const TileCopy& c : copies_) sorted_[at[c.slot_role >> 2]++] = c.triangle << 2 | (c.slot_role & 3u);
    for (const auto& [key, s] : slot_of_) {
      AcquisitionTile& tile = out_.tiles[key];
      for (std::size_t r = 0; r < 3; ++r) tile.counts[r] += tiles_[s].counts[r];
      const std::vector<std::string_view> block =
          build_block(key, std::span(sorted_).subspan(start[s], start[s + 1] - start[s]));
      const ByteRange range = blocks_file_.append(block);
      tile.blocks.push_back(range);
      out_.stats.bytes_written += range.bytes;
      ++out_.stats.blocks;
    }
    batch_.clear();
    copies_.clear();
    tiles_.clear();
    slot_of_.clear();
    largest_tile_ = 0;
  }

  /// One tile's block of the batch (`copies`: batch triangle << 2 | role): its triangles in
  /// input order, their vertices in order of first use, in the tile's frame.
  std::vector<std::string_view> build_block(TileKey key, std::span<const std::uint32_t> copies) {
    origin_ = grid_.corner(key);
    ++stamp_;  // every slot of an earlier block is stale
    block_.start(vertices_.flags(), 3 * copies.size(), copies.size());
    for (const std::uint32_t copy : copies) {
      const BatchTriangle& t = batch_[copy >> 2];
      Triangle local{};
      for (std::size_t k = 0; k < 3; ++k) local[k] = local_vertex(t.corners[k]);
      block_.add_triangle(local, t.face, t.index, t.fan, static_cast<TileRole>(copy & 3u));
    }
    return block_.finish();
  }

  /// v's index in the block, added to it the first time the block uses v.
  std::uint32_t local_vertex(std::uint32_t v) {
    std::uint64_t& slot = slots_[v];
    if (slot >> 32 == stamp_) return static_cast<std::uint32_t>(slot);
    const std::uint32_t index = block_.vertex_count();
    slot = std::uint64_t{stamp_} << 32 | index;
    const std::vector<float>& intensities = vertices_.intensities;
    const std::vector<Rgb8>& colors = vertices_.colors;
    block_.add_vertex(v, to_local(vertices_.positions[v], origin_), to_local(vertices_.sensors[v], origin_),
                      intensities.empty() ? 0.0f : intensities[v], colors.empty() ? Rgb8{} : colors[v]);
    return index;
  }

  const TileGrid& grid_;
  AcquisitionTiling& out_;
  std::uint64_t buffer_bytes_;
  tiler_detail::BlockAppender blocks_file_;
  AcquisitionVertices vertices_;
  std::uint32_t next_index_ = 0;
  std::uint64_t zero_area_dropped_ = 0;
  // The batch: triangles read since the last flush and their copies.
  std::vector<BatchTriangle> batch_;
  std::vector<TileCopy> copies_;
  std::vector<BatchTile> tiles_;  ///< by slot
  std::map<TileKey, std::uint32_t> slot_of_;
  std::uint32_t last_slot_ = 0;
  std::vector<TileKey> halo_, crossed_;  ///< the current triangle's other tiles
  /// Of the last owner owner() found; at first of no tile (owner() never gives INT32_MIN) and
  /// holding nothing.
  TileInterior last_interior_{.key = {INT32_MIN, INT32_MIN}};
  std::uint32_t largest_tile_ = 0;  ///< copies of the batch's largest tile
  double largest_radius_squared_ = 0;
  // Reused by every flush.
  std::vector<std::uint32_t> sorted_;
  tiler_detail::TileBlockWriter block_;
  Vec3d origin_;                      ///< of the tile whose block is being built
  std::vector<std::uint64_t> slots_;  ///< per vertex: stamp << 32 | index in the block
  std::uint32_t stamp_ = 0;           ///< of the block being built; slots start at 0, stamps at 1
};

}  // namespace

std::uint64_t TileContents::owned() const {
  std::uint64_t n = 0;
  for (const auto& a : triangles) n += a[0];
  return n;
}

std::uint64_t TileContents::total() const {
  std::uint64_t n = 0;
  for (const auto& a : triangles) n += a[0] + a[1] + a[2];
  return n;
}

std::vector<std::uint32_t> TileContents::passes() const {
  std::vector<std::uint32_t> out;
  for (std::size_t a = 0; a < triangles.size(); ++a) {
    if (triangles[a][0] + triangles[a][1] + triangles[a][2] > 0) out.push_back(static_cast<std::uint32_t>(a));
  }
  return out;
}

std::filesystem::path acquisition_tiles_path(const std::filesystem::path& dir, std::uint32_t acquisition) {
  return dir / fmt::format("a{}", acquisition);
}

std::filesystem::path acquisition_blocks_path(const std::filesystem::path& dir, std::uint32_t acquisition) {
  return acquisition_tiles_path(dir, acquisition) / kBlocksFile;
}

AcquisitionTiling tile_acquisition(const Acquisition& acquisition, const TilerParams& params,
                                   const std::string& fingerprint) {
  Stopwatch clock;
  const TileGrid grid(params.grid);
  const std::filesystem::path target = acquisition_tiles_path(params.dir, acquisition.index);
  // Unique per process: processes of a cluster may tile the same acquisition at once.
  const std::filesystem::path staged =
      params.dir / kStagingFolder / fmt::format("a{}.{}", acquisition.index, process_tag());
  std::error_code ec;
  std::filesystem::remove_all(staged, ec);
  std::filesystem::create_directories(staged, ec);
  if (ec) throw OutputError(fmt::format("{}: cannot create a tiling folder: {}", staged.string(), ec.message()));
  AcquisitionTiling out;
  out.fingerprint = fingerprint;
  AcquisitionTiler tiler(grid, staged / kBlocksFile, out, params.buffer_bytes);
  if (acquisition.withdrawn) {
    tiler.finish();  // an empty tiling: the tiles it was in are redone without it
  } else {
    tiler.run(acquisition.path, params.ply);
  }
  out.stats.seconds = clock.seconds();
  write_acquisition_tiling(staged, out);
  sync_tile_files(staged);
  if (std::optional<AcquisitionTiling> first = publish_acquisition_tiling(staged, target, fingerprint)) return *first;
  log::info("tiled {}: {} triangles in {:.2f} s{}", acquisition.path.string(), out.triangles, out.stats.seconds,
            acquisition.withdrawn ? " (withdrawn)" : "");
  return out;
}

TileStore assemble_tile_store(const std::filesystem::path& dir, const TileGridParams& grid,
                              std::span<const AcquisitionTiling> parts, std::string fingerprint) {
  TileStore store;
  store.dir = dir;
  store.grid = grid;
  store.fingerprint = std::move(fingerprint);
  std::map<TileKey, TileContents> tiles;
  for (std::size_t a = 0; a < parts.size(); ++a) {
    const AcquisitionTiling& part = parts[a];
    store.triangles.push_back(part.triangles);
    const TilingStats& s = part.stats;
    store.stats.input_bytes += s.input_bytes;
    store.stats.halo_copies += s.halo_copies;
    store.stats.empty_space_copies += s.empty_space_copies;
    store.stats.blocks += s.blocks;
    store.stats.bytes_written += s.bytes_written;
    store.stats.seconds += s.seconds;
    store.stats.largest_radius = std::max(store.stats.largest_radius, s.largest_radius);
    for (const auto& [key, here] : part.tiles) {
      TileContents& t = tiles[key];
      t.key = key;
      t.triangles.resize(parts.size());
      t.blocks.resize(parts.size());
      t.triangles[a] = here.counts;
      t.blocks[a] = here.blocks;
    }
  }
  for (auto& [key, t] : tiles) {
    if (t.owned() > 0) store.tiles.push_back(std::move(t));
  }
  return store;
}

std::uint64_t acquisition_bytes(const Acquisition& acquisition) {
  if (acquisition.withdrawn) return 0;
  std::error_code ec;
  const std::uintmax_t size = std::filesystem::file_size(acquisition.path, ec);
  return ec ? 0 : size;
}

TileStore tile_acquisitions(std::span<const Acquisition> acquisitions, const TilerParams& params, unsigned at_once) {
  std::error_code ec;
  std::filesystem::remove_all(params.dir, ec);
  std::filesystem::create_directories(params.dir, ec);
  if (ec) throw OutputError(fmt::format("{}: cannot create the tile store: {}", params.dir.string(), ec.message()));
  // Largest file first, as `citymesh run` hands them out: the last acquisitions to start are
  // the shortest, so the threads finish together.
  std::vector<std::size_t> order(acquisitions.size());
  std::vector<std::uintmax_t> sizes(acquisitions.size(), 0);
  for (std::size_t k = 0; k < order.size(); ++k) {
    order[k] = k;
    sizes[k] = acquisition_bytes(acquisitions[k]);
  }
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return sizes[a] > sizes[b]; });
  std::vector<AcquisitionTiling> parts(acquisitions.size());
  parallel_jobs(acquisitions.size(), at_once, [&](std::size_t i) {
    const std::size_t k = order[i];
    parts[k] = tile_acquisition(acquisitions[k], params, "");
  });
  return assemble_tile_store(params.dir, params.grid, parts, "");
}

std::vector<TilePiece> read_tile(const TileStore& store, TileKey key) {
  const Vec3d origin = TileGrid(store.grid).corner(key);
  std::vector<TilePiece> pieces(store.triangles.size());
  for (TilePiece& p : pieces) p.mesh.origin = origin;
  const TileContents* tile = store.find(key);
  if (tile == nullptr) return pieces;  // the store holds nothing of it
  for (std::uint32_t a = 0; a < pieces.size(); ++a) {
    if (tile->blocks[a].empty()) continue;
    pieces[a] = read_tile_piece(acquisition_blocks_path(store.dir, a), tile->blocks[a], origin, a, key.name());
  }
  return pieces;
}

}  // namespace citymesh
