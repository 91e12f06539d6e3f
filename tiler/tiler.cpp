// SPDX-License-Identifier: MIT
#include "citymesh/tiler/tiler.h"

#include <fmt/format.h>

#include <algorithm>
#include <atomic>
#include <map>
#include <unordered_map>

#include "citymesh/core/atomic_file.h"
#include "citymesh/core/error.h"
#include "citymesh/core/interrupt.h"
#include "citymesh/core/log.h"
#include "citymesh/core/parallel.h"
#include "citymesh/core/stopwatch.h"
#include "store_files.h"

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
};

/// The triangles of the current acquisition bound for one tile, not yet on disk.
struct TileBuffer {
  TilePiece piece;
  std::array<std::uint64_t, 3> counts{};  ///< triangles per role since the last flush
  std::uint32_t serial = 0;               ///< unique within the acquisition's run, never 0
  /// vertex id -> index in the piece, for the vertices whose cache slot (see
  /// AcquisitionTiler::slots_) went to another buffer: the slot and this map together know
  /// every vertex of the piece.
  std::unordered_map<std::uint32_t, std::uint32_t> local;
};

std::string chunk_name(TileKey key);

/// Hash-map overhead per buffered vertex, on top of the block bytes: an upper bound since
/// most vertices sit in the cache slots instead (see local_vertex).
constexpr std::uint64_t kMapBytesPerVertex = 32;

class AcquisitionTiler {
 public:
  AcquisitionTiler(const TileGrid& grid, std::filesystem::path dir, AcquisitionTiling& out, std::uint32_t acquisition,
                   std::uint64_t buffer_bytes)
      : grid_(grid), dir_(std::move(dir)), out_(out), acquisition_(acquisition), buffer_bytes_(buffer_bytes) {}

  void run(const std::filesystem::path& file, const PlyReadParams& ply) {
    PlyReader reader(file, ply);
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
        for (const std::uint32_t v : tri) {
          if (v >= vertices_.positions.size()) {
            throw InputError(fmt::format("{}: face {} uses vertex {} before the vertices are read (put the vertex "
                                         "element first)",
                                         file.string(), faces.faces[t], v));
          }
        }
        check_face_extent(file, faces.faces[t], vertices_.positions[tri[0]], vertices_.positions[tri[1]],
                          vertices_.positions[tri[2]]);
        add_triangle(tri, {acquisition_, faces.fans[t], faces.faces[t]});
        if (buffered_ > buffer_bytes_) flush();
      }
    }
    flush();
    out_.triangles = next_index_;
    out_.stats.input_bytes += reader.stats().bytes;
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

  void add_triangle(const Triangle& tri, const TriangleId& id) {
    const std::uint32_t index = next_index_++;
    const std::array<Vec3d, 3> c{vertices_.positions[tri[0]], vertices_.positions[tri[1]],
                                 vertices_.positions[tri[2]]};
    const TileKey owner = grid_.owner((c[0] + c[1] + c[2]) / 3.0);
    Box3d box;
    for (const Vec3d& p : c) box.extend(p);
    add_to(owner, tri, id, index, TileRole::owned);
    const Vec3d viewpoint =
        (vertices_.sensors[tri[0]] + vertices_.sensors[tri[1]] + vertices_.sensors[tri[2]]) / 3.0;
    Box3d reach = box;
    reach.extend(viewpoint);
    // Most triangles and their viewpoints lie well inside one tile (then it is the owner): no
    // halo copy and no other tile crossed, as halo_tiles and tiles_crossed would find.
    if (grid_.within_one_tile(reach)) return;
    const std::vector<TileKey> halo = grid_.halo_tiles(box, owner);
    for (const TileKey k : halo) add_to(k, tri, id, index, TileRole::halo);
    out_.stats.halo_copies += halo.size();
    const std::array<Vec3d, 4> tetrahedron{c[0], c[1], c[2], viewpoint};
    for (const TileKey k : grid_.tiles_crossed(tetrahedron)) {
      if (k == owner || std::binary_search(halo.begin(), halo.end(), k)) continue;
      add_to(k, tri, id, index, TileRole::empty_space);
      ++out_.stats.empty_space_copies;
    }
  }

  void add_to(TileKey key, const Triangle& tri, const TriangleId& id, std::uint32_t index, TileRole role) {
    // Consecutive triangles mostly go to the same tile: skip the map lookup then.
    if (last_ == nullptr || key != last_key_) {
      last_ = &buffers_[key];
      last_key_ = key;
      if (last_->serial == 0) {
        last_->serial = next_serial_++;
        live_.push_back(last_);
      }
    }
    TileBuffer& b = *last_;
    if (b.piece.mesh.positions.empty() && b.piece.mesh.triangles.empty()) b.piece.mesh.origin = grid_.corner(key);
    Triangle local{};
    for (std::size_t k = 0; k < 3; ++k) local[k] = local_vertex(b, tri[k]);
    b.piece.mesh.triangles.push_back(local);
    b.piece.mesh.triangle_ids.push_back(id);
    b.piece.triangle_index.push_back(index);
    b.piece.roles.push_back(role);
    buffered_ += 29;
    ++b.counts[static_cast<std::size_t>(role)];
  }

  /// v's index in b's piece, added to the piece the first time. Each vertex has one cache
  /// slot (buffer serial, index) that answers nearly every lookup, since a vertex's triangles
  /// mostly go to one tile; when another buffer takes the slot, the entry moves to its
  /// buffer's map. A map per buffer alone took three hash lookups per triangle.
  std::uint32_t local_vertex(TileBuffer& b, std::uint32_t v) {
    std::uint64_t& slot = slots_[v];
    if (slot >> 32 == b.serial) return static_cast<std::uint32_t>(slot);
    if (const auto it = b.local.find(v); it != b.local.end()) return it->second;
    if (slot >> 32 >= first_live_serial_) {
      live_[(slot >> 32) - first_live_serial_]->local.emplace(v, static_cast<std::uint32_t>(slot));
    }
    const auto index = static_cast<std::uint32_t>(b.piece.vertex_ids.size());
    slot = std::uint64_t{b.serial} << 32 | index;
    Mesh& m = b.piece.mesh;
    b.piece.vertex_ids.push_back(v);
    m.positions.push_back(to_local(vertices_.positions[v], m.origin));
    m.sensor_positions.push_back(to_local(vertices_.sensors[v], m.origin));
    if (!vertices_.intensities.empty()) m.intensities.push_back(vertices_.intensities[v]);
    if (!vertices_.colors.empty()) m.colors.push_back(vertices_.colors[v]);
    buffered_ += 28 + kMapBytesPerVertex;
    return index;
  }

  void flush() {
    for (auto& [key, b] : buffers_) {
      for (std::size_t r = 0; r < 3; ++r) out_.counts[key][r] += b.counts[r];
      if (b.piece.triangle_count() == 0) continue;
      const std::filesystem::path file = dir_ / chunk_name(key);
      std::filesystem::create_directories(file.parent_path());
      out_.stats.bytes_written += append_tile_block(file, b.piece);
      ++out_.stats.blocks;
    }
    buffers_.clear();
    live_.clear();
    first_live_serial_ = next_serial_;  // every slot now names a flushed buffer
    last_ = nullptr;
    buffered_ = 0;
  }

  const TileGrid& grid_;
  std::filesystem::path dir_;
  AcquisitionTiling& out_;
  std::uint32_t acquisition_;
  std::uint64_t buffer_bytes_;
  AcquisitionVertices vertices_;
  std::map<TileKey, TileBuffer> buffers_;
  std::vector<std::uint64_t> slots_;  ///< per vertex: buffer serial << 32 | index in its piece
  std::vector<TileBuffer*> live_;     ///< the buffers since the last flush, by serial
  std::uint32_t first_live_serial_ = 1, next_serial_ = 1;
  TileBuffer* last_ = nullptr;  ///< the buffer of last_key_ (map nodes do not move)
  TileKey last_key_;
  std::uint64_t buffered_ = 0;
  std::uint32_t next_index_ = 0;
};

std::string chunk_name(TileKey key) { return key.name() + ".bin"; }

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

std::filesystem::path acquisition_tiles_path(const std::filesystem::path& dir, std::uint32_t acquisition) {
  return dir / fmt::format("a{}", acquisition);
}

std::filesystem::path tile_chunk_path(const std::filesystem::path& dir, TileKey key, std::uint32_t acquisition) {
  return acquisition_tiles_path(dir, acquisition) / chunk_name(key);
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
  AcquisitionTiler tiler(grid, staged, out, acquisition.index, params.buffer_bytes);
  tiler.run(acquisition.path, params.ply);
  out.stats.seconds = clock.seconds();
  write_acquisition_tiling(staged, out);
  sync_tile_files(staged);
  if (std::optional<AcquisitionTiling> first = publish_acquisition_tiling(staged, target, fingerprint)) return *first;
  log::info("tiled {}: {} triangles in {:.2f} s", acquisition.path.string(), out.triangles, out.stats.seconds);
  return out;
}

TileStore assemble_tile_store(const std::filesystem::path& dir, const TileGridParams& grid,
                              std::span<const AcquisitionTiling> parts, std::string fingerprint) {
  TileStore store;
  store.dir = dir;
  store.grid = grid;
  store.fingerprint = std::move(fingerprint);
  std::map<TileKey, std::vector<std::array<std::uint64_t, 3>>> counts;
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
    for (const auto& [key, roles] : part.counts) {
      auto& all = counts[key];
      all.resize(parts.size());
      all[a] = roles;
    }
  }
  for (auto& [key, per_acquisition] : counts) {
    TileContents t{key, std::move(per_acquisition)};
    t.triangles.resize(parts.size());
    if (t.owned() > 0) store.tiles.push_back(std::move(t));
  }
  return store;
}

TileStore tile_acquisitions(std::span<const Acquisition> acquisitions, const TilerParams& params,
                            unsigned at_once) {
  std::error_code ec;
  std::filesystem::remove_all(params.dir, ec);
  std::filesystem::create_directories(params.dir, ec);
  if (ec) throw OutputError(fmt::format("{}: cannot create the tile store: {}", params.dir.string(), ec.message()));
  std::vector<AcquisitionTiling> parts(acquisitions.size());
  std::atomic<std::size_t> next{0};
  parallel_workers(std::max(at_once, 1u), [&](unsigned) {
    for (std::size_t k = next++; k < acquisitions.size(); k = next++) {
      parts[k] = tile_acquisition(acquisitions[k], params, "");
    }
  });
  return assemble_tile_store(params.dir, params.grid, parts, "");
}

std::vector<TilePiece> read_tile(const TileStore& store, TileKey key) {
  const TileGrid grid(store.grid);
  std::vector<TilePiece> pieces(store.triangles.size());
  for (std::uint32_t a = 0; a < pieces.size(); ++a) {
    const std::filesystem::path file = tile_chunk_path(store.dir, key, a);
    if (std::filesystem::exists(file)) {
      pieces[a] = read_tile_piece(file, grid.corner(key), a);
    } else {
      pieces[a].mesh.origin = grid.corner(key);
    }
  }
  return pieces;
}

}  // namespace citymesh
