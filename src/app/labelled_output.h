// SPDX-License-Identifier: MIT
// One acquisition's labelled PLY and top-down picture, written as its vertices and then its
// labelled triangles come, chunk by chunk: an acquisition need not fit in memory with its
// labels (a tiled run reads each file again, front to back, for these outputs).
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <span>

#include "citymesh/change/detect.h"
#include "citymesh/io/ply_writer.h"

namespace citymesh::app {

struct LabelledOutputParams {
  std::filesystem::path ply;
  std::filesystem::path png;  ///< empty: no picture
  double pixel_size = 0.05;   ///< metres per pixel of the picture
  MeshVertexAttributes has;   ///< the vertex attributes the rows carry
  std::uint64_t vertices = 0, triangles = 0;  ///< the rows to come (the PLY header holds them)
};

/// Writes the PLY as write_mesh_ply writes the acquisition's mesh with the labels as face
/// columns, and the picture as render_orthographic draws that mesh in the labels' colours
/// (the same bytes), holding only the vertex positions (12 bytes each, for the picture).
class LabelledAcquisitionWriter {
 public:
  explicit LabelledAcquisitionWriter(const LabelledOutputParams& params);
  ~LabelledAcquisitionWriter();
  LabelledAcquisitionWriter(const LabelledAcquisitionWriter&) = delete;
  LabelledAcquisitionWriter& operator=(const LabelledAcquisitionWriter&) = delete;

  /// The next vertices: [begin, end) of `chunk` (its positions relative to its origin, which
  /// is the same for every chunk, and the attributes `has` names: other ones are refused).
  void add_vertices(const Mesh& chunk, std::size_t begin, std::size_t end);
  /// The next triangles, on the vertices added so far, with the face index of each in its
  /// file and their labels. Throws ProcessingError when the sizes disagree.
  void add_triangles(std::span<const Triangle> triangles, std::span<const std::int32_t> source_face,
                     const LabelView& labels);
  /// Commits the PLY and writes the picture; throws ProcessingError when fewer rows came than
  /// announced. Returns the label counts.
  StateCounts finish();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace citymesh::app
