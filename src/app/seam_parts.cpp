// SPDX-License-Identifier: MIT
#include "seam_parts.h"

#include <fmt/format.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <numeric>

#include "byte_arrays.h"
#include "citymesh/core/atomic_file.h"
#include "citymesh/core/checksum.h"
#include "citymesh/core/error.h"
#include "citymesh/core/interrupt.h"
#include "citymesh/core/parallel.h"
#include "citymesh/core/read_file.h"

namespace citymesh::app {

namespace {

constexpr std::string_view kPieceMagic = "CMPART01";
constexpr std::uint32_t kSensors = 1, kTimes = 2, kIntensities = 4, kColors = 8;

/// What precedes a piece's arrays.
struct PieceHeader {
  char magic[8];
  std::uint32_t flags;
  std::uint32_t reserved;
  std::uint64_t vertices, triangles, checksum;
};
static_assert(sizeof(PieceHeader) == 40 && sizeof(Vec3d) == 24 && sizeof(Rgb8) == 3 && sizeof(Triangle) == 12 &&
              sizeof(TriangleId) == 16);

std::uint32_t flags_of(const KeyedPiece& p) {
  return (p.sensors.empty() ? 0u : kSensors) | (p.times.empty() ? 0u : kTimes) |
         (p.intensities.empty() ? 0u : kIntensities) | (p.colors.empty() ? 0u : kColors);
}

/// The payload's size for these counts and flags: each array in turn.
std::uint64_t payload_size(std::uint32_t flags, std::uint64_t n, std::uint64_t t) {
  std::uint64_t per_vertex = sizeof(std::uint64_t) + sizeof(Vec3d);
  if ((flags & kSensors) != 0) per_vertex += sizeof(Vec3d);
  if ((flags & kTimes) != 0) per_vertex += sizeof(double);
  if ((flags & kIntensities) != 0) per_vertex += sizeof(float);
  if ((flags & kColors) != 0) per_vertex += sizeof(Rgb8);
  const std::uint64_t per_triangle = sizeof(Triangle) + sizeof(TriangleId) + 2 * sizeof(std::int32_t);
  return n * per_vertex + t * per_triangle;
}

void write_scratch_file(const std::filesystem::path& path, std::string_view bytes) {
  // Scratch for this pass only: the folder is this process's and is never reused, so no
  // fsync (hundreds of them would cost seconds); a killed run's folder is removed whole.
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  if (!out.flush()) {
    const int err = errno;  // the failed open or write's reason (a full disk, mostly)
    throw OutputError(fmt::format("{}: cannot write a part of the seam pass: {}", path.string(), std::strerror(err)));
  }
}

void make_empty_folder(const std::filesystem::path& dir, std::string_view what) {
  std::error_code ec;
  std::filesystem::remove_all(dir, ec);
  std::filesystem::create_directories(dir, ec);
  if (ec) throw OutputError(fmt::format("{}: cannot create a folder for {}: {}", dir.string(), what, ec.message()));
}

KeyedPiece read_piece(const std::filesystem::path& path) {
  const std::optional<std::string> bytes = read_file_bytes(path);
  if (!bytes) throw ProcessingError(fmt::format("{}: a part of the seam pass vanished", path.string()));
  return decode_keyed_piece(*bytes, path.string());
}

/// The pieces in `files` merged, in order; the files are removed (they were scratch).
KeyedPiece merge_and_remove(std::span<const std::filesystem::path> files) {
  std::vector<KeyedPiece> pieces;
  for (const std::filesystem::path& f : files) pieces.push_back(read_piece(f));
  std::vector<const KeyedPiece*> all;
  for (const KeyedPiece& p : pieces) all.push_back(&p);
  KeyedPiece merged = merge_pieces(all);
  for (const std::filesystem::path& f : files) {
    std::error_code ec;
    std::filesystem::remove(f, ec);
  }
  return merged;
}

/// The triangles of `piece` in input order (acquisition, then its triangle).
KeyedPiece in_input_order(const KeyedPiece& piece) {
  std::vector<std::uint32_t> order(piece.triangle_count());
  std::iota(order.begin(), order.end(), 0u);
  std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
    return std::pair{piece.source_acq[a], piece.source_triangle[a]} <
           std::pair{piece.source_acq[b], piece.source_triangle[b]};
  });
  return subset(piece, order);
}

/// One more triangle of source acquisition `a` in `counts` (index: acquisition), grown as needed.
void count_source(std::vector<std::uint64_t>& counts, std::size_t a) {
  if (counts.size() <= a) counts.resize(a + 1, 0);
  ++counts[a];
}

/// `from`'s counts per source acquisition added to `into`'s.
void add_counts(std::vector<std::uint64_t>& into, const std::vector<std::uint64_t>& from) {
  if (into.size() < from.size()) into.resize(from.size(), 0);
  for (std::size_t a = 0; a < from.size(); ++a) into[a] += from[a];
}

}  // namespace

std::filesystem::path seam_parts_folder(const std::filesystem::path& work) {
  return work / (std::string(kSeamPartsPrefix) + process_tag());
}

std::string encode_keyed_piece(const KeyedPiece& p) {
  PieceHeader h{};
  std::memcpy(h.magic, kPieceMagic.data(), sizeof(h.magic));
  h.flags = flags_of(p);
  h.vertices = p.vertex_count();
  h.triangles = p.triangle_count();
  // The header's room first and the arrays after it, in one string: concatenating a header
  // and a payload copied every part of a city's seam pass once more.
  std::string out(sizeof(h), '\0');
  out.reserve(sizeof(h) + payload_size(h.flags, h.vertices, h.triangles));
  put_array(out, p.keys);
  put_array(out, p.positions);
  put_array(out, p.sensors);
  put_array(out, p.times);
  put_array(out, p.intensities);
  put_array(out, p.colors);
  put_array(out, p.triangles);
  put_array(out, p.ids);
  put_array(out, p.source_acq);
  put_array(out, p.source_triangle);
  h.checksum = bulk_checksum(out.data() + sizeof(h), out.size() - sizeof(h));
  std::memcpy(out.data(), &h, sizeof(h));
  return out;
}

KeyedPiece decode_keyed_piece(std::string_view bytes, std::string_view source) {
  PieceHeader h{};
  const auto refuse = [&](std::string_view why) {
    return ProcessingError(fmt::format("{}: not a part of the seam pass ({})", source, why));
  };
  if (bytes.size() < sizeof(h)) throw refuse("too short");
  std::memcpy(&h, bytes.data(), sizeof(h));
  if (std::string_view(h.magic, sizeof(h.magic)) != kPieceMagic) throw refuse("another magic");
  std::string_view in = bytes.substr(sizeof(h));
  // Counts are checked against the size before anything is allocated from them.
  const std::uint64_t limit = in.size();
  if (h.vertices > limit || h.triangles > limit || payload_size(h.flags, h.vertices, h.triangles) != in.size()) {
    throw refuse("its counts disagree with its size");
  }
  if (bulk_checksum(in.data(), in.size()) != h.checksum) throw refuse("its checksum does not match");
  const auto n = static_cast<std::size_t>(h.vertices), t = static_cast<std::size_t>(h.triangles);
  const auto optional = [&](std::uint32_t flag) { return (h.flags & flag) != 0 ? n : 0; };
  KeyedPiece p;
  take_array(in, p.keys, n);
  take_array(in, p.positions, n);
  take_array(in, p.sensors, optional(kSensors));
  take_array(in, p.times, optional(kTimes));
  take_array(in, p.intensities, optional(kIntensities));
  take_array(in, p.colors, optional(kColors));
  take_array(in, p.triangles, t);
  take_array(in, p.ids, t);
  take_array(in, p.source_acq, t);
  take_array(in, p.source_triangle, t);
  p.check(source);
  return p;
}

KeyedPiece keyed_piece(const TilePiece& piece) {
  const Mesh& m = piece.mesh;
  // A piece holds one acquisition's triangles, whose vertex ids are that acquisition's.
  const std::uint32_t acquisition = m.triangle_ids.empty() ? 0 : m.triangle_ids.front().acquisition;
  const auto key = [&](std::uint32_t v) { return input_vertex_key(acquisition, piece.vertex_ids[v]); };
  // The vertices in key order, each copied once.
  std::vector<std::uint32_t> order(m.vertex_count());
  std::iota(order.begin(), order.end(), 0u);
  std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) { return key(a) < key(b); });
  std::vector<std::uint32_t> rank(order.size());
  KeyedPiece out;
  for (std::uint32_t i = 0; i < order.size(); ++i) {
    rank[order[i]] = i;
    out.append_mesh_vertex(m, order[i], key(order[i]));
  }
  for (std::size_t t = 0; t < m.triangle_count(); ++t) {
    const Triangle& tri = m.triangles[t];
    out.triangles.push_back({rank[tri[0]], rank[tri[1]], rank[tri[2]]});
    out.ids.push_back(m.triangle_ids[t]);
    out.source_acq.push_back(static_cast<std::int32_t>(m.triangle_ids[t].acquisition));
    out.source_triangle.push_back(static_cast<std::int32_t>(piece.triangle_index[t]));
  }
  return out;
}

SeamPartFiles::SeamPartFiles(std::filesystem::path dir, const BlockStitchParams& blocks, Folder folder)
    : dir_(std::move(dir)), blocks_(blocks), owned_(folder == Folder::own) {
  if (owned_) make_empty_folder(dir_, "the seam pass");
}

SeamPartFiles::SeamPartFiles(std::filesystem::path dir, std::vector<BlockPartKey> keys)
    : dir_(std::move(dir)), keys_(std::move(keys)), owned_(false) {}

SeamPartFiles::~SeamPartFiles() {
  if (!owned_) return;
  std::error_code ec;
  std::filesystem::remove_all(dir_, ec);  // best effort: a leftover holds no finished output
}

std::uint64_t SeamPartFiles::input_bytes(std::size_t part) const {
  std::error_code ec;
  const std::uintmax_t bytes = std::filesystem::file_size(part_file(keys_.at(part), false), ec);
  return ec ? 0 : static_cast<std::uint64_t>(bytes);
}

std::filesystem::path SeamPartFiles::beside(std::size_t part, std::string_view suffix) const {
  return dir_ / fmt::format("{}.{}", keys_.at(part).name(), suffix);
}

std::filesystem::path SeamPartFiles::part_file(const BlockPartKey& key, bool stitched) const {
  return dir_ / fmt::format("{}.{}.part", key.name(), stitched ? "stitched" : "input");
}

SeamPartFiles::FiledTile SeamPartFiles::file_tile(TileKey key, const std::vector<TilePiece>& selected) const {
  throw_if_interrupted("the seam pass");
  FiledTile out;
  std::map<BlockPartKey, std::vector<KeyedPiece>> by_part;
  for (const TilePiece& tile_piece : selected) {
    if (tile_piece.triangle_count() == 0) continue;
    const KeyedPiece piece = keyed_piece(tile_piece);
    std::map<BlockPartKey, std::vector<std::uint32_t>> triangles;
    for (std::uint32_t t = 0; t < piece.triangle_count(); ++t) {
      const Triangle& tri = piece.triangles[t];
      const Vec3d centroid = (piece.positions[tri[0]] + piece.positions[tri[1]] + piece.positions[tri[2]]) / 3.0;
      triangles[block_part_of(centroid, blocks_)].push_back(t);
      count_source(out.source_sizes, static_cast<std::size_t>(piece.source_acq[t]));
    }
    for (const auto& [part, ts] : triangles) by_part[part].push_back(subset(piece, ts));
  }
  for (const auto& [part, pieces] : by_part) {
    std::vector<const KeyedPiece*> all;
    for (const KeyedPiece& p : pieces) all.push_back(&p);
    const KeyedPiece fragment = merge_pieces(all);
    out.parts.push_back(part);
    out.boxes.push_back(fragment.box());
    out.files.push_back(dir_ / fmt::format("{}.{}.tile", part.name(), key.name()));
    write_scratch_file(out.files.back(), encode_keyed_piece(fragment));
  }
  return out;
}

void SeamPartFiles::add_filed(const FiledTile& tile) {
  for (std::size_t k = 0; k < tile.parts.size(); ++k) {
    boxes_[tile.parts[k]].extend(tile.boxes[k]);
    fragments_[tile.parts[k]].push_back(tile.files[k]);
  }
  add_counts(source_sizes_, tile.source_sizes);
}

std::vector<BlockPart> SeamPartFiles::finish(const PartMerging& merging) {
  std::vector<BlockPart> parts;
  for (const auto& [key, box] : boxes_) parts.push_back({key, box, {}});
  keys_.clear();
  std::vector<std::vector<std::filesystem::path>> fragments;
  for (const BlockPart& p : parts) {
    keys_.push_back(p.key);
    fragments.push_back(std::move(fragments_.at(p.key)));
  }
  fragments_.clear();
  const std::function<void(std::size_t)> here = [&](std::size_t i) { merge_fragments(keys_[i], fragments[i]); };
  if (merging) {
    merging(keys_, fragments, here);
  } else {
    parallel_for_blocks(parts.size(), 1, [&](std::size_t begin, std::size_t end) {
      for (std::size_t i = begin; i < end; ++i) here(i);
    });
  }
  return parts;
}

void SeamPartFiles::merge_fragments(const BlockPartKey& key, std::span<const std::filesystem::path> fragments) const {
  throw_if_interrupted("the seam pass");
  const KeyedPiece merged = merge_and_remove(fragments);
  write_scratch_file(part_file(key, false), encode_keyed_piece(in_input_order(merged)));
}

std::shared_ptr<const KeyedPiece> SeamPartFiles::load(std::size_t part, bool stitched) const {
  return std::make_shared<const KeyedPiece>(read_piece(part_file(keys_.at(part), stitched)));
}

void SeamPartFiles::release_input(std::size_t part) {
  std::error_code ec;
  std::filesystem::remove(part_file(keys_.at(part), false), ec);
}

void SeamPartFiles::release_stitched() {
  for (const BlockPartKey& key : keys_) {
    std::error_code ec;
    std::filesystem::remove(part_file(key, true), ec);
  }
}

void SeamPartFiles::save_stitched(std::size_t part, KeyedPiece stitched) {
  write_scratch_file(part_file(keys_.at(part), true), encode_keyed_piece(stitched));
}

std::vector<OutputShare> file_part_shares(const std::filesystem::path& dir, const TileGrid& grid,
                                          const PartStore& store, std::size_t part) {
  throw_if_interrupted("the seam pass");
  const std::shared_ptr<const KeyedPiece> piece = store.load(part, true);
  std::map<TileKey, std::vector<std::uint32_t>> by_tile;
  for (std::uint32_t t = 0; t < piece->triangle_count(); ++t) {
    const Triangle& tri = piece->triangles[t];
    by_tile[grid.owner((piece->positions[tri[0]] + piece->positions[tri[1]] + piece->positions[tri[2]]) / 3.0)]
        .push_back(t);
  }
  std::vector<OutputShare> shares;
  for (const auto& [key, ts] : by_tile) {
    const KeyedPiece share = subset(*piece, ts);
    OutputShare& out = shares.emplace_back();
    out.key = key;
    out.box = share.box();
    out.triangles = ts.size();
    out.file = dir / fmt::format("{}.{}.share", key.name(), part);
    for (const std::int32_t a : share.source_acq) {
      if (a < 0) {
        ++out.stitched;
        continue;
      }
      count_source(out.per_source, static_cast<std::size_t>(a));
    }
    write_scratch_file(out.file, encode_keyed_piece(share));
  }
  return shares;
}

void merge_leaf_file(const std::filesystem::path& leaf_file, std::span<const std::filesystem::path> shares) {
  write_scratch_file(leaf_file, encode_keyed_piece(merge_and_remove(shares)));
}

OutputLeaves::OutputLeaves(std::filesystem::path dir, const TileGrid& grid, std::span<const BlockPart> parts,
                           const PartStore& store, const LeafFilingWork& work)
    : dir_(std::move(dir)) {
  make_empty_folder(dir_, "the output's tiles");
  const std::function<std::vector<OutputShare>(std::size_t)> split_here = [&](std::size_t p) {
    return file_part_shares(dir_, grid, store, p);
  };
  const std::vector<std::vector<OutputShare>> shares =
      work.split ? work.split(parts.size(), split_here) : parallel_map(parts.size(), split_here);
  if (shares.size() != parts.size()) throw ProcessingError("the seam pass: a part was not filed by grid tile");
  // The tiles in key order, each with its shares in part order.
  std::map<TileKey, std::size_t> index;
  for (const std::vector<OutputShare>& of_part : shares) {
    for (const OutputShare& s : of_part) index.try_emplace(s.key, 0);
  }
  for (auto& [key, i] : index) {
    i = leaves_.size();
    leaves_.push_back({key, {}, 0});
  }
  std::vector<std::vector<std::filesystem::path>> fragments(leaves_.size());
  for (const std::vector<OutputShare>& of_part : shares) {
    for (const OutputShare& s : of_part) {
      OutputLeaf& leaf = leaves_[index.at(s.key)];
      leaf.box.extend(s.box);
      leaf.triangles += s.triangles;
      fragments[index.at(s.key)].push_back(s.file);
      add_counts(per_source_, s.per_source);
      stitched_ += s.stitched;
    }
  }
  // Each tile's shares in one file, read once per output.
  std::vector<std::filesystem::path> files;
  for (const OutputLeaf& leaf : leaves_) files.push_back(leaf_file(leaf));
  const std::function<void(std::size_t)> merge_here = [&](std::size_t l) { merge_leaf_file(files[l], fragments[l]); };
  if (work.merge) {
    work.merge(files, fragments, merge_here);
  } else {
    parallel_for_blocks(leaves_.size(), 1, [&](std::size_t begin, std::size_t end) {
      for (std::size_t l = begin; l < end; ++l) merge_here(l);
    });
  }
}

OutputLeaves::OutputLeaves(std::filesystem::path dir, std::vector<OutputLeaf> leaves)
    : dir_(std::move(dir)), leaves_(std::move(leaves)), owned_(false) {}

std::filesystem::path OutputLeaves::leaf_file(const OutputLeaf& leaf) const {
  return dir_ / fmt::format("{}.leaf", leaf.key.name());
}

void OutputLeaves::keep(std::size_t leaf, std::string_view name, std::string_view bytes) const {
  write_scratch_file(dir_ / fmt::format("{}.{}", leaves_.at(leaf).key.name(), name), bytes);
}

std::string OutputLeaves::kept(std::size_t leaf, std::string_view name) const {
  const std::filesystem::path path = dir_ / fmt::format("{}.{}", leaves_.at(leaf).key.name(), name);
  std::optional<std::string> bytes = read_file_bytes(path);
  if (!bytes) throw ProcessingError(fmt::format("{}: a note of the output's tiles vanished", path.string()));
  return std::move(*bytes);
}

Box3d OutputLeaves::box() const {
  Box3d b;
  for (const OutputLeaf& leaf : leaves_) b.extend(leaf.box);
  return b;
}

OutputLeaves::~OutputLeaves() {
  if (!owned_) return;
  std::error_code ec;
  std::filesystem::remove_all(dir_, ec);  // best effort: scratch of this pass
}

KeyedPiece OutputLeaves::load(std::size_t leaf) const { return read_piece(leaf_file(leaves_.at(leaf))); }

}  // namespace citymesh::app
