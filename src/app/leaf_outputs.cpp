// SPDX-License-Identifier: MIT
#include "leaf_outputs.h"

#include <fmt/format.h>

#include <algorithm>
#include <cstring>
#include <map>
#include <optional>

#include "citymesh/core/error.h"
#include "citymesh/core/interrupt.h"
#include "citymesh/core/parallel.h"
#include "citymesh/io/ply_writer.h"
#include "citymesh/mosaic/merged_mesh.h"
#include "detect_output.h"
#include "mosaic_output.h"

namespace citymesh::app {

namespace {

/// The tiles before `leaf` (in key order) whose boxes meet its box: the only ones that can
/// hold its vertices (a shared vertex lies in both boxes).
std::vector<std::size_t> earlier_neighbours(const std::vector<OutputLeaf>& leaves, std::size_t leaf) {
  std::vector<std::size_t> out;
  for (std::size_t m = 0; m < leaf; ++m) {
    if (leaves[m].box.intersects(leaves[leaf].box)) out.push_back(m);
  }
  return out;
}

/// Where `key` is in `piece`'s vertices (ascending keys), or nothing.
std::optional<std::uint32_t> find_key(const KeyedPiece& piece, std::uint64_t key) {
  const auto it = std::lower_bound(piece.keys.begin(), piece.keys.end(), key);
  if (it == piece.keys.end() || *it != key) return std::nullopt;
  return static_cast<std::uint32_t>(it - piece.keys.begin());
}

/// Where a vertex of a tile is written: by the tile `leaf`, as its vertex `index`.
struct Owner {
  std::uint32_t leaf, index;
};

/// Which tile writes each vertex: the first, in key order, holding it. Each tile's owners
/// are found once, when its earlier neighbours are read, and kept beside it (8 bytes per
/// vertex): numbering its faces then reads those notes, not the neighbours again. In memory
/// only the number of the first vertex each tile writes.
struct VertexNumbering {
  static constexpr std::string_view kOwners = "owners";
  std::vector<std::uint64_t> first;
  std::uint64_t vertices = 0;

  explicit VertexNumbering(const OutputLeaves& leaves) {
    const std::vector<OutputLeaf>& all = leaves.leaves();
    std::vector<std::uint64_t> count(all.size(), 0);
    parallel_for_blocks(all.size(), 1, [&](std::size_t begin, std::size_t end) {
      for (std::size_t l = begin; l < end; ++l) count[l] = find_owners(leaves, l);
    });
    for (std::size_t l = 0; l < all.size(); ++l) {
      first.push_back(vertices);
      vertices += count[l];
    }
  }

  /// Per vertex of tile `leaf`: where it is written.
  static std::vector<Owner> owners(const OutputLeaves& leaves, std::size_t leaf) {
    const std::string bytes = leaves.kept(leaf, kOwners);
    std::vector<Owner> out(bytes.size() / sizeof(Owner));
    if (!out.empty()) std::memcpy(out.data(), bytes.data(), out.size() * sizeof(Owner));
    return out;
  }

  /// Per vertex of tile `leaf`: 1 when the tile writes it.
  static std::string owned(const OutputLeaves& leaves, std::size_t leaf) {
    const std::vector<Owner> o = owners(leaves, leaf);
    std::string flags(o.size(), '\0');
    for (std::size_t v = 0; v < o.size(); ++v) flags[v] = o[v].leaf == leaf ? '\1' : '\0';
    return flags;
  }

 private:
  /// Keeps tile `leaf`'s owners; returns how many of its vertices it writes itself.
  static std::uint64_t find_owners(const OutputLeaves& leaves, std::size_t leaf) {
    const KeyedPiece piece = leaves.load(leaf);
    std::vector<Owner> owner(piece.vertex_count());
    for (std::uint32_t v = 0; v < owner.size(); ++v) owner[v] = {static_cast<std::uint32_t>(leaf), v};
    // Earlier tiles in key order: the first holding a vertex writes it.
    for (const std::size_t m : earlier_neighbours(leaves.leaves(), leaf)) {
      const KeyedPiece other = leaves.load(m);
      for (std::size_t v = 0; v < owner.size(); ++v) {
        if (owner[v].leaf != leaf) continue;
        if (const auto at = find_key(other, piece.keys[v])) owner[v] = {static_cast<std::uint32_t>(m), *at};
      }
    }
    leaves.keep(leaf, kOwners, {reinterpret_cast<const char*>(owner.data()), owner.size() * sizeof(Owner)});
    return static_cast<std::uint64_t>(
        std::count_if(owner.begin(), owner.end(), [&](const Owner& o) { return o.leaf == leaf; }));
  }
};

/// Per vertex: the vertices written before it by its tile (among those `owned` flags).
std::vector<std::uint32_t> ranks(std::string_view owned) {
  std::vector<std::uint32_t> out(owned.size());
  std::uint32_t before = 0;
  for (std::size_t v = 0; v < owned.size(); ++v) {
    out[v] = before;
    before += owned[v] != 0 ? 1u : 0u;
  }
  return out;
}

/// A tile's faces on the file's vertex numbers, with their provenance columns.
struct FaceRows {
  std::vector<Triangle> triangles;
  Provenance provenance;
};

FaceRows face_rows(const OutputLeaves& leaves, const VertexNumbering& numbers, std::size_t leaf,
                   std::span<const std::int32_t> listed) {
  const KeyedPiece piece = leaves.load(leaf);
  const std::vector<Owner> owners = VertexNumbering::owners(leaves, leaf);
  // Each owning tile's ranks, from its notes (a few tiles: this one and its earlier neighbours).
  std::map<std::uint32_t, std::vector<std::uint32_t>> rank;
  for (const Owner& o : owners) {
    if (!rank.contains(o.leaf)) rank[o.leaf] = ranks(VertexNumbering::owned(leaves, o.leaf));
  }
  std::vector<std::uint32_t> number(piece.vertex_count());
  for (std::size_t v = 0; v < number.size(); ++v) {
    number[v] = static_cast<std::uint32_t>(numbers.first[owners[v].leaf] + rank.at(owners[v].leaf)[owners[v].index]);
  }
  FaceRows rows{{}, Provenance(piece, listed)};
  for (const Triangle& tri : piece.triangles) rows.triangles.push_back({number[tri[0]], number[tri[1]], number[tri[2]]});
  return rows;
}

/// Tiles prepared at a time before their rows are written in order.
constexpr std::size_t kLeavesInFlight = 4;

}  // namespace

MeshVertexRows piece_rows(const KeyedPiece& piece, std::string_view owned) {
  MeshVertexRows rows({.sensors = !piece.sensors.empty(), .times = !piece.times.empty(),
                       .intensities = !piece.intensities.empty(), .colors = !piece.colors.empty()});
  for (std::size_t v = 0; v < piece.vertex_count(); ++v) {
    if (!owned.empty() && owned[v] == 0) continue;
    rows.add(piece.positions[v], piece.sensors.empty() ? Vec3d{} : piece.sensors[v],
             piece.times.empty() ? 0.0 : piece.times[v], piece.intensities.empty() ? 0.0f : piece.intensities[v],
             piece.colors.empty() ? Rgb8{} : piece.colors[v]);
  }
  return rows;
}

Provenance::Provenance(const KeyedPiece& piece, std::span<const std::int32_t> listed)
    : acq(as_listed(piece.source_acq, listed)) {
  face.reserve(acq.size());
  for (std::size_t t = 0; t < acq.size(); ++t) {
    face.push_back(acq[t] == kNoSource ? kNoSource : static_cast<std::int32_t>(piece.ids[t].face));
  }
}

std::vector<PlyColumn> Provenance::columns() const {
  return {{kSourceAcqProperty, std::span<const std::int32_t>(acq)}, {kSourceFaceProperty, std::span<const std::int32_t>(face)}};
}

void write_leaves_ply(const std::filesystem::path& path, const OutputLeaves& leaves,
                      std::span<const std::int32_t> listed) {
  const std::vector<OutputLeaf>& all = leaves.leaves();
  const VertexNumbering numbers(leaves);
  if (numbers.vertices > UINT32_MAX) {
    throw ProcessingError(fmt::format("{}: {} vertices do not fit the PLY's 32-bit indices", path.string(), numbers.vertices));
  }
  std::uint64_t faces = 0;
  for (const OutputLeaf& leaf : all) faces += leaf.triangles;
  const KeyedPiece first = all.empty() ? KeyedPiece{} : leaves.load(0);
  // The columns the tiles carry (the first tile's), with no rows.
  const MeshVertexRows layout_rows = piece_rows(first, std::string(first.vertex_count(), '\0'));
  const Provenance no_faces;
  const PlyWriteInput layout{{}, {}, layout_rows.columns(), no_faces.columns(), {std::string(kPlyComment)}};
  PlyStreamWriter out(path, layout, numbers.vertices, faces);
  for (std::size_t l = 0; l < all.size(); ++l) {
    const MeshVertexRows rows = piece_rows(leaves.load(l), VertexNumbering::owned(leaves, l));
    out.add_vertices({rows.positions, {}, rows.columns(), {}, {}});
  }
  for (std::size_t begin = 0; begin < all.size(); begin += kLeavesInFlight) {
    throw_if_interrupted(path.string());
    const std::size_t count = std::min(kLeavesInFlight, all.size() - begin);
    std::vector<FaceRows> rows(count);
    parallel_for_blocks(count, 1, [&](std::size_t b, std::size_t e) {
      for (std::size_t i = b; i < e; ++i) rows[i] = face_rows(leaves, numbers, begin + i, listed);
    });
    for (const FaceRows& r : rows) {
      out.add_faces({{}, r.triangles, {}, r.provenance.columns(), {}});
    }
  }
  out.commit();
}

}  // namespace citymesh::app
