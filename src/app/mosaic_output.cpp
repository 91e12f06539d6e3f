// SPDX-License-Identifier: MIT
#include "mosaic_output.h"

#include <array>

#include "citymesh/core/atomic_file.h"
#include "citymesh/core/error.h"
#include "citymesh/core/log.h"
#include "citymesh/io/ply_writer.h"
#include "citymesh/render/render.h"
#include "leaf_outputs.h"

namespace citymesh::app {

Rgb8 source_color(std::int32_t acquisition) {
  if (acquisition < 0) return {230, 0, 230};
  // Well separated hues, none of them magenta; they repeat after ten acquisitions.
  static constexpr std::array<Rgb8, 10> kPalette{{{31, 119, 180},
                                                  {255, 127, 14},
                                                  {44, 160, 44},
                                                  {214, 39, 40},
                                                  {140, 86, 75},
                                                  {23, 190, 207},
                                                  {188, 189, 34},
                                                  {127, 127, 127},
                                                  {148, 103, 189},
                                                  {0, 80, 40}}};
  return kPalette[static_cast<std::size_t>(acquisition) % kPalette.size()];
}

namespace {

/// `source_acq`: as the outputs name the sources (as_listed), which the colours follow.
void write_picture(const std::filesystem::path& path, const Mesh& mesh, std::span<const std::int32_t> source_acq,
                   double pixel_size) {
  RenderLayer layer{&mesh, {}};
  layer.face_colors.reserve(source_acq.size());
  for (const std::int32_t a : source_acq) layer.face_colors.push_back(source_color(a));
  ViewParams view;
  view.pixel_size = pixel_size;
  write_png(path, render_orthographic(std::span<const RenderLayer>(&layer, 1), view));
}

}  // namespace

std::vector<std::int32_t> source_faces(const MergedMesh& merged) {
  const Mesh& m = merged.mesh;
  if (m.triangle_ids.size() != m.triangle_count()) {
    throw ProcessingError("mosaic output: the merged mesh lost its triangle ids");
  }
  std::vector<std::int32_t> out(merged.source_acq.size(), kNoSource);
  for (std::size_t t = 0; t < out.size(); ++t) {
    if (merged.source_acq[t] != kNoSource) out[t] = static_cast<std::int32_t>(m.triangle_ids[t].face);
  }
  return out;
}

namespace {

/// What the summary says of the output: its triangles per source and stitching's.
struct OutputCounts {
  std::vector<std::uint64_t> per_source;
  std::uint64_t stitched = 0, triangles = 0;
};

OutputCounts counts_of(const MergedMesh& merged, std::size_t acquisitions) {
  OutputCounts c{std::vector<std::uint64_t>(acquisitions, 0), 0, merged.mesh.triangle_count()};
  for (const std::int32_t a : merged.source_acq) {
    if (a >= 0) {
      ++c.per_source[static_cast<std::size_t>(a)];
    } else {
      ++c.stitched;
    }
  }
  return c;
}

void write_summary(const Config& config, const LoadedAcquisitions& input, const OutputCounts& counts,
                   const MosaicStats& s, const MosaicOutputParams& params) {
  nlohmann::json summary;
  summary["config"] = config.file.string();
  summary["method"] = mosaic_method_name(config.mosaic.method);
  summary["distance_threshold"] = config.change.distance_threshold;
  summary["quality"] = quality_measure_name(config.mosaic.quality);
  summary["weights"] = {{"quality", config.mosaic.quality_weight},
                        {"boundary", config.mosaic.boundary_weight},
                        {"overlap", config.mosaic.overlap_weight},
                        {"seam", config.mosaic.seam_weight},
                        {"crease", config.mosaic.crease_weight}};
  summary["crease_angle"] = config.mosaic.crease_angle;
  summary["seen_through_quality"] = config.mosaic.seen_through_quality;
  for (const std::size_t k : config.listed_order()) {
    nlohmann::json entry = acquisition_json(config, input, k);
    entry["triangles_kept"] = k < counts.per_source.size() ? counts.per_source[k] : 0;
    summary["acquisitions"].push_back(std::move(entry));
  }
  summary["counts"] = {{"candidates", s.candidates},       {"selected", s.selected}, {"filled", s.filled},
                       {"seen_through", s.seen_through},
                       {"fill_seen_through", s.fill_seen_through},
                       {"output_triangles", counts.triangles}, {"stitch_triangles", counts.stitched},
                       {"overlap_terms", s.overlap_terms}, {"seam_terms", s.seam_terms}};
  summary["energy"] = {{"total", s.energy},
                       {"quality", s.quality},
                       {"boundary", s.boundary},
                       {"seam", s.seam},
                       {"overlap", s.overlap},
                       {"length_unit_m", s.length_unit},
                       {"exact", s.solver.exact},
                       {"group_moves", s.moves.moves},
                       {"improving_moves", s.moves.improving_moves},
                       {"sweeps", s.moves.sweeps}};
  if (params.solved_per_tile) {
    for (const char* per_tile : {"overlap_terms", "seam_terms"}) {
      summary["counts"][per_tile] = nullptr;
    }
    summary["energy"] = nullptr;
  }
  summary["stitch"] = params.stitch;
  summary["seconds"] = params.seconds;
  summary["ply"] = config.output.mosaic_ply ? kMosaicFile : "";
  summary["png"] = params.pictures ? "mosaic.png" : "";
  write_file_atomically(params.dir / "summary.json", summary.dump(1) + "\n");
}

/// Whether this run writes mosaic.ply in `dir`; when it does not ([output] mosaic_ply =
/// false), an earlier run's is removed.
bool writes_mosaic_ply(const Config& config, const std::filesystem::path& dir) {
  if (!config.output.mosaic_ply) remove_earlier_output(dir / kMosaicFile, "[output] mosaic_ply = false");
  return config.output.mosaic_ply;
}

/// The picture of the output's tiles, drawn one at a time.
void write_leaves_picture(const std::filesystem::path& path, const OutputLeaves& leaves,
                          std::span<const std::int32_t> listed, double pixel_size) {
  const Box3d box = leaves.box();
  const Vec3d origin = box.empty() ? Vec3d{} : whole_metre_origin(box.min);
  ViewParams view;
  view.pixel_size = pixel_size;
  OrthographicCanvas canvas({box.min - origin, box.max - origin}, origin, view);
  for (std::size_t l = 0; l < leaves.leaves().size(); ++l) {
    const KeyedPiece piece = leaves.load(l);
    Mesh m;
    m.origin = whole_metre_origin(leaves.leaves()[l].box.min);
    for (const Vec3d& p : piece.positions) m.positions.push_back(to_local(p, m.origin));
    m.triangles = piece.triangles;
    RenderLayer layer{&m, {}};
    for (const std::int32_t a : as_listed(piece.source_acq, listed)) layer.face_colors.push_back(source_color(a));
    canvas.draw(layer);
  }
  write_png(path, canvas.take());
}

}  // namespace

void remove_earlier_output(const std::filesystem::path& path, const char* why) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) return;
  std::filesystem::remove_all(path, ec);
  log::info("{}: an earlier run's output removed ({})", path.string(), why);
}

void write_mosaic_outputs(const Config& config, const LoadedAcquisitions& input, const MergedMesh& merged,
                          const MosaicStats& stats, const MosaicOutputParams& params) {
  std::filesystem::create_directories(params.dir);
  const std::vector<std::int32_t> faces = source_faces(merged);
  const std::vector<std::int32_t> sources = as_listed(merged.source_acq, config.listed_indices());
  if (writes_mosaic_ply(config, params.dir)) {
    write_mesh_ply(params.dir / kMosaicFile, merged.mesh,
                   {{kSourceAcqProperty, std::span<const std::int32_t>(sources)},
                    {"source_face", std::span<const std::int32_t>(faces)}});
  }
  if (params.pictures) write_picture(params.dir / "mosaic.png", merged.mesh, sources, params.pixel_size);
  write_summary(config, input, counts_of(merged, input.acquisitions.size()), stats, params);
}

void write_mosaic_outputs(const Config& config, const LoadedAcquisitions& input, const OutputLeaves& leaves,
                          const MosaicStats& stats, const MosaicOutputParams& params) {
  std::filesystem::create_directories(params.dir);
  const std::vector<std::int32_t> listed = config.listed_indices();
  if (writes_mosaic_ply(config, params.dir)) write_leaves_ply(params.dir / kMosaicFile, leaves, listed);
  if (params.pictures) write_leaves_picture(params.dir / "mosaic.png", leaves, listed, params.pixel_size);
  OutputCounts counts{leaves.per_source(), leaves.stitched(), 0};
  counts.per_source.resize(input.acquisitions.size(), 0);
  for (const OutputLeaf& leaf : leaves.leaves()) counts.triangles += leaf.triangles;
  write_summary(config, input, counts, stats, params);
}

}  // namespace citymesh::app
