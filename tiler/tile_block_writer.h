// SPDX-License-Identifier: MIT
// The tile store's block encoder, private to the tiler: the tiler feeds it each tile's
// vertices and triangles as it finds them, and encode_tile_block feeds it a whole TilePiece, so
// that a block is encoded in one place.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <future>
#include <memory>
#include <string_view>
#include <vector>

#include "citymesh/core/varint.h"
#include "citymesh/tiler/tile_store.h"
#include "tile_block_format.h"

namespace citymesh::tiler_detail {

/// One version-6 block (see encode_tile_block), built vertex by vertex and triangle by
/// triangle with no TilePiece in between: building a piece and then encoding it was two passes
/// over every copy, a fifth of the tiler's time. Vertices must all come before the triangles
/// only in the bytes, not in the calls: the two varint sequences are kept apart. The buffers
/// are kept from block to block.
class TileBlockWriter {
 public:
  /// Starts a block of at most `max_vertices` vertices and `max_triangles` triangles (the
  /// varint room is sized from them), with the attributes `flags` names (kHasIntensity,
  /// kHasColor).
  void start(std::uint32_t flags, std::size_t max_vertices, std::size_t max_triangles);

  /// Adds a vertex: `id` in the acquisition, position and sensor position in the tile's frame.
  /// `intensity` and `color` are kept only when the block's flags ask for them.
  void add_vertex(std::uint32_t id, const Vec3f& position, const Vec3f& sensor, float intensity, Rgb8 color) {
    if ((flags_ & kHasIntensity) != 0) intensities_.push_back(intensity);
    if ((flags_ & kHasColor) != 0) colors_.push_back(color);
    vertex_varints_.put_next(id, id_);
    put_point(position, position_);
    put_point(sensor, sensor_);
    ++vertices_;
  }

  /// Adds a triangle: corners are indices of this block's vertices; `face`, `fan` and
  /// `index` (in the acquisition) as in the triangle's global id and TilePiece.
  void add_triangle(const Triangle& corners, std::uint64_t face, std::uint32_t index, std::uint32_t fan,
                    TileRole role) {
    std::uint64_t codes = 0;
    std::array<std::uint64_t, 3> others{};  // zigzag distances of the corners coded kOther
    std::size_t other_count = 0;
    for (const std::uint32_t c : corners) {
      const std::uint32_t code = window_.code(c);
      if (code == CornerWindow::kOther) others[other_count++] = zigzag(window_.next_new() - c);
      codes = codes << CornerWindow::kCodeBits | code;
      window_.saw(c);
    }
    window_.shift(corners);
    // Unsigned wrap-around on both sides, as the reader steps.
    const bool steps = face == face_ + 1 && index == static_cast<std::uint32_t>(index_ + 1);
    const std::uint64_t fan_role = std::uint64_t{fan} << 3 | (steps ? kSteps : 0) | static_cast<std::uint8_t>(role);
    triangle_varints_.put(fan_role << CornerWindow::kTriangleCodeBits | codes);
    for (std::size_t k = 0; k < other_count; ++k) triangle_varints_.put(others[k]);
    if (steps) {
      face_ = face;
      index_ = index;
    } else {
      triangle_varints_.put_next(face, face_);
      triangle_varints_.put_next(index, index_);
    }
    ++triangles_;
  }

  [[nodiscard]] std::uint32_t vertex_count() const { return vertices_; }
  [[nodiscard]] std::uint64_t triangle_count() const { return triangles_; }

  /// The finished block as consecutive byte ranges, header first; valid until start().
  [[nodiscard]] std::vector<std::string_view> finish();

 private:
  /// A point's coordinates as varint deltas of their floats' bits against `running`'s.
  void put_point(const Vec3f& p, std::array<std::uint32_t, 3>& running) {
    vertex_varints_.put_next(float_bits(p.x), running[0]);
    vertex_varints_.put_next(float_bits(p.y), running[1]);
    vertex_varints_.put_next(float_bits(p.z), running[2]);
  }

  BlockHeader header_{};
  std::uint32_t flags_ = 0;
  std::uint32_t vertices_ = 0;
  std::vector<float> intensities_;
  std::vector<Rgb8> colors_;
  VarintWriter vertex_varints_, triangle_varints_;
  // The running values the varints are deltas against.
  std::uint32_t id_ = 0, index_ = 0;
  CornerWindow window_;
  std::array<std::uint32_t, 3> position_{}, sensor_{};
  std::uint64_t face_ = 0;
  std::uint64_t triangles_ = 0;
};

/// An acquisition's block file, created empty and kept open while the tiler appends to it.
/// Blocks are gathered in page-aligned buffers, and each full buffer is written by a
/// background task while the next one fills, with O_DIRECT where the file system allows it
/// (not tmpfs): copying 1.2 GB of blocks into the page cache was a tenth of the tiler's time
/// on the 112 M-triangle city, and tile processing reads them back much later.
class BlockAppender {
 public:
  /// Throws OutputError naming `file` when it cannot be created.
  explicit BlockAppender(std::filesystem::path file);
  /// Waits for the write in flight and closes the file; what is not written by then is lost
  /// (the folder is never published).
  ~BlockAppender();
  BlockAppender(const BlockAppender&) = delete;
  BlockAppender& operator=(const BlockAppender&) = delete;

  /// Appends the byte ranges `parts` as one block and returns where it lies. Throws
  /// OutputError naming the file (also for an earlier buffer's write).
  ByteRange append(const std::vector<std::string_view>& parts);
  /// Writes what is left and closes the file (not synced: see sync_tile_files). Throws
  /// OutputError naming the file.
  void close();

 private:
  using Buffer = std::unique_ptr<char, void (*)(void*)>;
  /// One gathering buffer, page-aligned as O_DIRECT needs.
  static Buffer page_aligned_buffer();
  /// Bytes appended so far.
  [[nodiscard]] std::uint64_t appended() const { return written_ + gathered_; }
  /// Hands the whole pages gathered so far, or with `all` everything (the last page padded, cut
  /// off again in close()), to a background write, and goes on in the other buffer.
  void write_gathered(bool all);
  /// Waits for the write in flight, if any; rethrows its error.
  void wait_for_write();

  std::filesystem::path file_;
  int fd_ = -1;
  std::uint64_t written_ = 0;  ///< bytes handed to writes: whole pages until close()
  std::array<Buffer, 2> buffers_;
  std::size_t current_ = 0;   ///< the buffer gathering what follows written_
  std::size_t gathered_ = 0;  ///< bytes in it
  std::future<void> write_;   ///< of the other buffer
};

}  // namespace citymesh::tiler_detail
