// SPDX-License-Identifier: MIT
#include "tiled_detect_output.h"

#include <fmt/format.h>

#include <algorithm>

#include "citymesh/core/error.h"
#include "citymesh/core/interrupt.h"
#include "citymesh/core/log.h"
#include "citymesh/io/mesh_io.h"
#include "citymesh/io/ply_reader.h"

namespace citymesh::app {

namespace {

/// Labels expanded from the spill at a time (about 32 bytes each while held), at least.
constexpr std::uint64_t kLabelWindow = std::uint64_t{1} << 20;
/// Each window reads the whole spill file (its labels come in tile order): a window of at
/// least this fraction of the acquisition keeps that to a few reads, not one per 2^20
/// triangles (~4 bytes per triangle held on a large acquisition, where the tiler held ~30).
constexpr std::uint64_t kMaxLabelReads = 8;
/// Triangles handed to the writer at a time.
constexpr std::size_t kTriangleBatch = std::size_t{1} << 16;

/// An acquisition's triangles in file order (the degenerate ones left out, as the tiler left
/// them out), handed to the writer in batches with their labels, which come from the spill a
/// window at a time.
class LabelledTriangles {
 public:
  LabelledTriangles(const TileAssembly& assembly, std::size_t k, std::filesystem::path file,
                    LabelledAcquisitionWriter& out)
      : assembly_(assembly),
        k_(k),
        labelled_(assembly.triangle_count(k)),
        window_size_(std::max(kLabelWindow, (labelled_ + kMaxLabelReads - 1) / kMaxLabelReads)),
        file_(std::move(file)),
        out_(out) {}

  void add(const Triangle& triangle, std::uint64_t face) {
    ++seen_;
    if (seen_ > labelled_) return;  // the file changed since its tiling: finish() says so
    triangles_.push_back(triangle);
    faces_.push_back(static_cast<std::int32_t>(face));
    if (triangles_.size() >= kTriangleBatch) flush();
  }

  /// Throws InputError when the file no longer has the triangles the tiles labelled.
  void finish() {
    if (seen_ != labelled_) {
      throw InputError(fmt::format("{}: {} triangles now, {} labelled (run with --force)", file_.string(), seen_,
                                   labelled_));
    }
    flush();
  }

 private:
  void flush() {
    if (triangles_.empty()) return;
    const std::uint64_t n = triangles_.size();
    if (next_ + n > window_end_) {
      window_begin_ = next_;
      window_end_ = std::min(labelled_, next_ + std::max<std::uint64_t>(window_size_, n));
      window_ = ChangeResult{};  // the previous window's memory goes first
      window_ = assembly_.labels(k_, window_begin_, window_end_);
    }
    out_.add_triangles(triangles_, faces_, label_view(window_, next_ - window_begin_, next_ - window_begin_ + n));
    next_ += n;
    triangles_.clear();
    faces_.clear();
  }

  const TileAssembly& assembly_;
  std::size_t k_;
  std::uint64_t labelled_;
  std::uint64_t window_size_;  ///< labels read from the spill at a time
  std::filesystem::path file_;
  LabelledAcquisitionWriter& out_;
  std::uint64_t seen_ = 0, next_ = 0;
  std::vector<Triangle> triangles_;
  std::vector<std::int32_t> faces_;
  ChangeResult window_;
  std::uint64_t window_begin_ = 0, window_end_ = 0;
};

/// The frame whole-mesh reading puts every acquisition in: that of the first vertex of the
/// first acquisition that has one (none: the origin).
Vec3d shared_frame(const Config& config, const LoadedAcquisitions& described) {
  PlyVertexChunk vertices;
  PlyFaceChunk faces;
  for (const Acquisition& a : described.acquisitions) {
    if (a.withdrawn) continue;
    PlyReader reader(a.path, config.ply_read_params());
    for (auto kind = reader.next(vertices, faces); kind == PlyReader::ChunkKind::vertices;
         kind = reader.next(vertices, faces)) {
      if (!vertices.positions.empty()) return whole_metre_origin(vertices.positions.front());
    }
  }
  return {};
}

}  // namespace

TiledDetectOutput::TiledDetectOutput(const Config& config, const LoadedAcquisitions& described,
                                     const TileAssembly& assembly)
    : config_(config),
      described_(described),
      assembly_(assembly),
      origin_(shared_frame(config, described)),
      readers_(described.acquisitions.size()) {}

TiledDetectOutput::~TiledDetectOutput() = default;

LabelledOutputParams TiledDetectOutput::layout(std::size_t k) {
  const Acquisition& a = described_.acquisitions[k];
  std::unique_ptr<PlyReader>& reader = readers_[k];
  reader = std::make_unique<PlyReader>(a.path, config_.ply_read_params());
  check_provenance_ids(a.path, reader->face_count());
  const PlyVertexLayout& has = reader->vertex_layout();
  LabelledOutputParams p;
  p.has = {.sensors = has.has_sensor_origin, .times = has.has_time, .intensities = has.has_intensity,
           .colors = has.has_color};
  p.vertices = reader->vertex_count();
  p.triangles = assembly_.triangle_count(k);
  return p;
}

void TiledDetectOutput::feed(std::size_t k, LabelledAcquisitionWriter& out) {
  if (!readers_[k]) throw ProcessingError(fmt::format("labelled outputs: acquisition {} fed before its layout", k));
  const std::unique_ptr<PlyReader> owned = std::move(readers_[k]);
  PlyReader& reader = *owned;
  const std::filesystem::path& file = reader.path();
  std::vector<Vec3d> absolute;  // the file's coordinates, to find the degenerate triangles
  absolute.reserve(reader.vertex_count());
  LabelledTriangles triangles(assembly_, k, file, out);
  std::uint64_t degenerate = 0;
  PlyVertexChunk vertices;
  PlyFaceChunk faces;
  Mesh chunk;
  for (auto kind = reader.next(vertices, faces); kind != PlyReader::ChunkKind::end;
       kind = reader.next(vertices, faces)) {
    throw_if_interrupted("the labelled PLYs");
    if (kind == PlyReader::ChunkKind::vertices) {
      if (vertices.positions.empty()) continue;
      chunk = Mesh{};
      chunk.origin = origin_;
      append_vertex_chunk(chunk, vertices);
      out.add_vertices(chunk, 0, chunk.vertex_count());
      absolute.insert(absolute.end(), vertices.positions.begin(), vertices.positions.end());
      continue;
    }
    for (std::size_t t = 0; t < faces.triangles.size(); ++t) {
      const Triangle& tri = faces.triangles[t];
      const std::uint64_t face = faces.faces[t];
      check_vertices_read(file, face, tri, absolute.size());
      const Vec3d &a = absolute[tri[0]], &b = absolute[tri[1]], &c = absolute[tri[2]];
      for (const std::uint32_t v : tri) check_frame_reach(file, face, v, to_local(absolute[v], origin_), origin_);
      check_face_extent(file, face, a, b, c);
      if (degenerate_input_triangle(a, b, c)) {
        ++degenerate;
        continue;
      }
      triangles.add(tri, face);
    }
  }
  triangles.finish();
  if (degenerate > 0) log::info("{}: dropped {} zero-area triangles", file.string(), degenerate);
  log::info("{}: {} triangles", file.string(), assembly_.triangle_count(k));
}

std::uint64_t TiledDetectOutput::write_pairs(const std::filesystem::path& path) {
  return assembly_.write_pairs(path, kPairsMagic);
}

}  // namespace citymesh::app
