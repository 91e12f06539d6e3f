// SPDX-License-Identifier: MIT
// Writing the tile store's blocks (version 6) and its files; reading is in
// tile_block_decode.cpp.
#include "citymesh/tiler/tile_store.h"

#include <fcntl.h>
#include <fmt/format.h>
#include <sys/resource.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <new>

#include "citymesh/core/checksum.h"
#include "citymesh/core/error.h"
#include "citymesh/core/read_file.h"
#include "tile_block_writer.h"

namespace citymesh {

using namespace tiler_detail;

namespace {

template <class T>
std::string_view bytes_of(const std::vector<T>& values) {
  return {reinterpret_cast<const char*>(values.data()), values.size() * sizeof(T)};
}

/// `piece` through the writer, whole.
std::vector<std::string_view> write_piece(const TilePiece& piece, TileBlockWriter& writer) {
  const Mesh& m = piece.mesh;
  const std::uint32_t flags = flags_of(m);
  writer.start(flags, m.vertex_count(), m.triangle_count());
  for (std::size_t v = 0; v < m.vertex_count(); ++v) {
    writer.add_vertex(piece.vertex_ids[v], m.positions[v], m.sensor_positions[v],
                      (flags & kHasIntensity) != 0 ? m.intensities[v] : 0.0f,
                      (flags & kHasColor) != 0 ? m.colors[v] : Rgb8{});
  }
  for (std::size_t t = 0; t < m.triangle_count(); ++t) {
    const TriangleId& id = m.triangle_ids[t];
    writer.add_triangle(m.triangles[t], id.face, piece.triangle_index[t], id.fan, piece.roles[t]);
  }
  return writer.finish();
}

}  // namespace

namespace tiler_detail {

void TileBlockWriter::start(std::uint32_t flags, std::size_t max_vertices, std::size_t max_triangles) {
  // Per vertex seven 32-bit deltas; per triangle fan << 3 | step | role with the corner codes
  // (44 bits), up to three corner distances and the face (64-bit deltas), and the index.
  constexpr std::size_t per_vertex = 7 * max_varint_bytes(32);
  constexpr std::size_t per_triangle = max_varint_bytes(44) + 4 * max_varint_bytes(64) + max_varint_bytes(32);
  flags_ = flags;
  vertices_ = 0;
  intensities_.clear();
  colors_.clear();
  vertex_varints_.reset(max_vertices * per_vertex);
  triangle_varints_.reset(max_triangles * per_triangle);
  id_ = index_ = 0;
  window_ = {};
  position_ = sensor_ = {};
  face_ = 0;
  triangles_ = 0;
}

std::vector<std::string_view> TileBlockWriter::finish() {
  header_ = {};
  std::memcpy(header_.start.magic, kMagic, sizeof kMagic);
  header_.start.version = kVersion;
  header_.start.flags = flags_;
  header_.vertices = vertices_;
  header_.triangles = triangles_;
  std::vector<std::string_view> parts;
  if ((flags_ & kHasIntensity) != 0) parts.push_back(bytes_of(intensities_));
  if ((flags_ & kHasColor) != 0) parts.push_back(bytes_of(colors_));
  parts.push_back(vertex_varints_.bytes());
  parts.push_back(triangle_varints_.bytes());
  BulkChecksum sum;
  for (const std::string_view part : parts) {
    sum.add(part.data(), part.size());
    header_.payload_bytes += part.size();
  }
  header_.checksum = sum.value();
  parts.insert(parts.begin(), std::string_view(reinterpret_cast<const char*>(&header_), sizeof header_));
  return parts;
}

namespace {
/// O_DIRECT's unit of offsets, sizes and buffer addresses (the largest in use).
constexpr std::size_t kPage = 4096;
/// The gathering buffer; whole pages are written once it is full.
constexpr std::size_t kGatherBytes = std::size_t{4} << 20;

int open_block_file(const std::filesystem::path& file) {
  constexpr int flags = O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC;
  const int fd = ::open(file.c_str(), flags | O_DIRECT, 0644);
  // tmpfs and some network or FUSE file systems refuse O_DIRECT: write through the page cache
  // there (an error of this second open is the one reported).
  return fd >= 0 ? fd : ::open(file.c_str(), flags, 0644);
}

/// Why a write ending at byte `end` failed with `err`. The kernel trims a write that crosses
/// the file size limit (RLIMIT_FSIZE, `ulimit -f`) to end at the limit, which an O_DIRECT write
/// then refuses as unaligned (EINVAL): that is the limit's EFBIG, "File too large".
int write_error(int err, std::uint64_t end) {
  rlimit limit{};
  const bool past_limit =
      ::getrlimit(RLIMIT_FSIZE, &limit) == 0 && limit.rlim_cur != RLIM_INFINITY && end > limit.rlim_cur;
  return err == EINVAL && past_limit ? EFBIG : err;
}

/// Writes `bytes` of `data` at `offset` of `fd` (`file` names it in errors), then asks for
/// write-back to start (without O_DIRECT, the fsync before the store is published then finds
/// little left to wait for; only a hint).
void write_pages(int fd, const char* data, std::size_t bytes, std::uint64_t offset, const std::filesystem::path& file) {
  std::size_t done = 0;
  while (done < bytes) {
    const ssize_t n = ::pwrite(fd, data + done, bytes - done, static_cast<off_t>(offset + done));
    if (n <= 0) {
      const int err = n < 0 ? write_error(errno, offset + bytes) : EIO;
      throw OutputError(fmt::format("{}: cannot append tile blocks: {}", file.string(), std::strerror(err)));
    }
    done += static_cast<std::size_t>(n);
  }
  (void)::sync_file_range(fd, static_cast<off_t>(offset), static_cast<off_t>(bytes), SYNC_FILE_RANGE_WRITE);
}

}  // namespace

BlockAppender::Buffer BlockAppender::page_aligned_buffer() {
  Buffer b(static_cast<char*>(std::aligned_alloc(kPage, kGatherBytes)), std::free);
  if (!b) throw std::bad_alloc();
  return b;
}

BlockAppender::BlockAppender(std::filesystem::path file)
    : file_(std::move(file)), buffers_{page_aligned_buffer(), page_aligned_buffer()} {
  fd_ = open_block_file(file_);
  if (fd_ < 0) throw OutputError(fmt::format("{}: cannot create the block file: {}", file_.string(), std::strerror(errno)));
}

BlockAppender::~BlockAppender() {
  if (write_.valid()) write_.wait();  // its buffer and file must outlive it
  if (fd_ >= 0) ::close(fd_);
}

ByteRange BlockAppender::append(const std::vector<std::string_view>& parts) {
  const std::uint64_t offset = appended();
  for (std::string_view part : parts) {
    while (!part.empty()) {
      const std::size_t n = std::min(part.size(), kGatherBytes - gathered_);
      std::memcpy(buffers_[current_].get() + gathered_, part.data(), n);
      gathered_ += n;
      part.remove_prefix(n);
      if (gathered_ == kGatherBytes) write_gathered(false);
    }
  }
  return {offset, appended() - offset};
}

void BlockAppender::wait_for_write() {
  if (write_.valid()) write_.get();
}

void BlockAppender::write_gathered(bool all) {
  char* full = buffers_[current_].get();
  const std::size_t bytes = all ? (gathered_ + kPage - 1) / kPage * kPage : gathered_ / kPage * kPage;
  if (bytes > gathered_) std::memset(full + gathered_, 0, bytes - gathered_);
  wait_for_write();  // the other buffer is free again
  const std::size_t kept = gathered_ > bytes ? gathered_ - bytes : 0;
  current_ = 1 - current_;
  std::memcpy(buffers_[current_].get(), full + bytes, kept);
  gathered_ = kept;
  if (bytes == 0) return;
  write_ = std::async(std::launch::async,
                      [fd = fd_, full, bytes, at = written_, file = file_] { write_pages(fd, full, bytes, at, file); });
  written_ += bytes;
}

void BlockAppender::close() {
  const std::uint64_t size = appended();
  write_gathered(true);
  wait_for_write();
  // The last page was padded: cut the file back to what was appended.
  const bool ok = ::ftruncate(fd_, static_cast<off_t>(size)) == 0;
  const int err = errno;
  ::close(fd_);
  fd_ = -1;
  if (!ok) throw OutputError(fmt::format("{}: cannot set the block file's size: {}", file_.string(), std::strerror(err)));
}

}  // namespace tiler_detail

void TilePiece::clear() {
  mesh.positions.clear();
  mesh.sensor_positions.clear();
  mesh.intensities.clear();
  mesh.colors.clear();
  mesh.triangles.clear();
  mesh.triangle_ids.clear();
  vertex_ids.clear();
  triangle_index.clear();
  roles.clear();
}

std::string encode_tile_block(const TilePiece& piece) {
  TileBlockWriter writer;
  std::string out;
  for (const std::string_view part : write_piece(piece, writer)) out += part;
  return out;
}

void sync_tile_files(const std::filesystem::path& dir) {
  std::error_code ec;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(dir, ec)) {
    const int fd = ::open(entry.path().c_str(), O_RDONLY | O_CLOEXEC);
    const bool ok = fd >= 0 && ::fsync(fd) == 0;
    const int err = errno;
    if (fd >= 0) ::close(fd);
    if (!ok) throw OutputError(fmt::format("{}: cannot sync: {}", entry.path().string(), std::strerror(err)));
  }
  if (ec) throw OutputError(fmt::format("{}: cannot list the tile store: {}", dir.string(), ec.message()));
}

TilePiece read_tile_piece(const std::filesystem::path& file, std::span<const ByteRange> blocks, const Vec3d& origin,
                          std::uint32_t acquisition, std::string_view tile) {
  const std::string source = fmt::format("{} (tile {})", file.string(), tile);
  return decode_tile_blocks(read_file_ranges(file, blocks, source), origin, acquisition, source);
}

}  // namespace citymesh
