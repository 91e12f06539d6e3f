// SPDX-License-Identifier: MIT
#include "labelled_output.h"

#include <fmt/format.h>

#include <algorithm>
#include <optional>

#include "citymesh/core/error.h"
#include "citymesh/render/render.h"
#include "detect_output.h"

namespace citymesh::app {

namespace {

double unix_seconds(TimePoint t) { return static_cast<double>(t.time_since_epoch().count()) / 1000.0; }

/// Vertex rows are written this many at a time, so their buffers stay small.
constexpr std::size_t kVertexRows = 1 << 16;
/// Triangles drawn at a time: each draw sets up the picture's bands once.
constexpr std::size_t kDrawBatch = 1 << 18;

/// The labelled PLY's face columns over `labels` (state and dates converted into `state`,
/// `first` and `last`, which must outlive the columns).
std::vector<PlyColumn> face_columns(std::span<const std::int32_t> source_face, const LabelView& labels,
                                    std::vector<std::uint8_t>& state, std::vector<double>& first,
                                    std::vector<double>& last) {
  const std::size_t n = labels.size();
  state.resize(n);
  first.resize(n);
  last.resize(n);
  for (std::size_t t = 0; t < n; ++t) {
    state[t] = static_cast<std::uint8_t>(labels.state[t]);
    first[t] = unix_seconds(labels.first_seen[t]);
    last[t] = unix_seconds(labels.last_seen[t]);
  }
  return {{kSourceFaceProperty, source_face},
          {kStateProperty, std::span<const std::uint8_t>(state)},
          {"first_seen", std::span<const double>(first)},
          {"last_seen", std::span<const double>(last)},
          {"sustainable", labels.sustainable},
          {kKeptProperty, labels.kept},
          {"refutes", labels.refutes}};
}

/// The PLY's layout: its columns' names and types (PlyStreamWriter reads no rows of it, so
/// the empty spans may outlive the vectors they came from).
PlyWriteInput ply_layout(const MeshVertexAttributes& has) {
  static const std::vector<std::int32_t> no_faces;
  std::vector<std::uint8_t> state;
  std::vector<double> first, last;
  return {{}, {}, MeshVertexRows(has).columns(), face_columns(no_faces, LabelView{}, state, first, last),
          {std::string(kPlyComment)}};
}

}  // namespace

struct LabelledAcquisitionWriter::Impl {
  explicit Impl(const LabelledOutputParams& p)
      : params(p), ply(p.ply, ply_layout(p.has), p.vertices, p.triangles) {}

  /// Draws the batch of triangles gathered so far (on its own compact vertices).
  void draw_batch() {
    if (!canvas) canvas.emplace(box, origin, ViewParams{.pixel_size = params.pixel_size});
    if (batch.triangles.empty()) return;
    batch.origin = origin;
    canvas->draw(RenderLayer{&batch, colors});
    for (const std::uint32_t v : batch_vertices) slot[v] = UINT32_MAX;
    batch_vertices.clear();
    batch.positions.clear();
    batch.triangles.clear();
    batch.triangle_ids.clear();
    colors.clear();
  }

  /// Adds triangle `tri` in `color` to the batch to draw.
  void add_to_batch(const Triangle& tri, Rgb8 color) {
    Triangle local{};
    for (std::size_t c = 0; c < 3; ++c) {
      std::uint32_t& s = slot[tri[c]];
      if (s == UINT32_MAX) {
        s = static_cast<std::uint32_t>(batch.positions.size());
        batch.positions.push_back(positions[tri[c]]);
        batch_vertices.push_back(tri[c]);
      }
      local[c] = s;
    }
    batch.triangles.push_back(local);
    batch.triangle_ids.push_back({});
    colors.push_back(color);
    if (batch.triangles.size() >= kDrawBatch) draw_batch();
  }

  LabelledOutputParams params;
  PlyStreamWriter ply;
  StateCounts counts;
  std::uint64_t vertices = 0, triangles = 0;
  // The picture: every vertex's position, their box, and a batch of triangles to draw.
  Vec3d origin;
  Box3d box;
  std::vector<Vec3f> positions;
  std::vector<std::uint32_t> slot;  ///< a vertex's index in the batch, or UINT32_MAX
  std::vector<std::uint32_t> batch_vertices;
  Mesh batch;
  std::vector<Rgb8> colors;
  std::optional<OrthographicCanvas> canvas;
};

LabelledAcquisitionWriter::LabelledAcquisitionWriter(const LabelledOutputParams& params)
    : impl_(std::make_unique<Impl>(params)) {}

LabelledAcquisitionWriter::~LabelledAcquisitionWriter() = default;

void LabelledAcquisitionWriter::add_vertices(const Mesh& chunk, std::size_t begin, std::size_t end) {
  Impl& w = *impl_;
  if (w.vertices == 0) w.origin = chunk.origin;
  if (chunk.origin != w.origin) throw ProcessingError(fmt::format("{}: vertices in two frames", w.params.ply.string()));
  for (std::size_t b = begin; b < end; b += kVertexRows) {
    // Rows of other attributes than the layout's are refused by the PLY writer.
    const MeshVertexRows rows = mesh_vertex_rows(chunk, b, std::min(end, b + kVertexRows));
    w.ply.add_vertices({rows.positions, {}, rows.columns(), {}, {}});
  }
  w.vertices += end - begin;
  if (w.params.png.empty()) return;
  for (std::size_t v = begin; v < end; ++v) {
    w.positions.push_back(chunk.positions[v]);
    w.box.extend(Vec3d(chunk.positions[v]));
  }
}

void LabelledAcquisitionWriter::add_triangles(std::span<const Triangle> triangles,
                                              std::span<const std::int32_t> source_face, const LabelView& labels) {
  Impl& w = *impl_;
  if (source_face.size() != triangles.size() || labels.size() != triangles.size()) {
    throw ProcessingError(fmt::format("{}: {} triangles with {} face ids and {} labels", w.params.ply.string(),
                                      triangles.size(), source_face.size(), labels.size()));
  }
  for (const Triangle& tri : triangles) {
    for (const std::uint32_t v : tri) {
      if (v >= w.vertices) {
        throw ProcessingError(fmt::format("{}: a triangle uses vertex {} of {}", w.params.ply.string(), v, w.vertices));
      }
    }
  }
  std::vector<std::uint8_t> state;
  std::vector<double> first, last;
  w.ply.add_faces({{}, triangles, {}, face_columns(source_face, labels, state, first, last), {}});
  w.triangles += triangles.size();
  w.counts += count_states(labels);
  if (w.params.png.empty()) return;
  if (w.slot.empty()) w.slot.assign(w.positions.size(), UINT32_MAX);
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    w.add_to_batch(triangles[t], detect_color(labels.state[t], labels.kept[t] != 0, labels.refutes[t] != 0));
  }
}

StateCounts LabelledAcquisitionWriter::finish() {
  Impl& w = *impl_;
  w.ply.commit();
  if (!w.params.png.empty()) {
    w.draw_batch();
    write_png(w.params.png, w.canvas->take());
  }
  return w.counts;
}

}  // namespace citymesh::app
