// SPDX-License-Identifier: MIT
// What `citymesh detect` writes: per acquisition a labelled PLY and a top-down PNG, and a
// summary JSON. `citymesh eval` reads them back.
#pragma once

#include <filesystem>
#include <span>
#include <string_view>

#include "acquisitions.h"
#include "citymesh/change/detect.h"
#include "labelled_output.h"

namespace citymesh::app {

/// Face properties of the labelled PLY (besides vertex_indices).
inline constexpr const char* kStateProperty = "state";          ///< uchar: 0 consistent, 1 conflicting, 2 single
inline constexpr const char* kKeptProperty = "kept";            ///< uchar: survives the time series
inline constexpr const char* kSourceFaceProperty = "source_face";  ///< int: face index in the input file
/// The consistent pairs (global triangle ids, acquisitions by time), as uint32 a0 b0 a1 b1 ... with a < b.
inline constexpr const char* kPairsFile = "pairs.bin";
inline constexpr std::string_view kPairsMagic = "CMPAIRS1";

struct DetectOutputParams {
  std::filesystem::path dir;  ///< <output>/detect
  double pixel_size = 0.05;   ///< metres per pixel of the PNGs
  bool pictures = true;
  double read_seconds = 0;
  unsigned at_once = 1;  ///< acquisitions written at once (see labelled_output_workers)
};

/// What the change step's outputs are written from, acquisition by acquisition: `citymesh
/// detect` has every mesh and label in memory; a tiled run reads each acquisition's file
/// again, front to back, with its labels from the tiles (a city's inputs and labels do not
/// fit in memory; one acquisition with its labels need not either). layout(k) then feed(k)
/// are called once per acquisition, on one thread, but the calls for different acquisitions
/// and write_pairs may run at the same time on other threads.
class DetectOutputSource {
 public:
  virtual ~DetectOutputSource() = default;
  /// Acquisition k's vertex attributes and row counts, asked before feed(k).
  virtual LabelledOutputParams layout(std::size_t k) = 0;
  /// Gives acquisition k's vertices, then its triangles with their labels, to `out` (every
  /// mesh in the first one's frame, as `detect` reads them).
  virtual void feed(std::size_t k, LabelledAcquisitionWriter& out) = 0;
  /// Writes the consistent pairs and the pairs of layers of one pass (ChangeResult::layer_pairs),
  /// in one list sorted and unique, to `path` (kPairsMagic records); returns how many.
  virtual std::uint64_t write_pairs(const std::filesystem::path& path) = 0;
  /// The change step's statistics (pre-filter, seconds); the pair count comes from write_pairs.
  [[nodiscard]] virtual ChangeStats stats() const = 0;
};

/// Bytes one acquisition's labelled outputs hold while they are written: `bytes_per_vertex`
/// per vertex (the source's and the writer's) and, with pictures, the largest picture with
/// its depth (ViewParams::max_side squared, 7 bytes per pixel: 470 MB).
std::uint64_t labelled_output_bytes(std::uint64_t vertices, std::uint64_t bytes_per_vertex, bool pictures);

/// How many acquisitions write_detect_outputs may write at once: one per thread while each,
/// at `largest` bytes, fits in `memory` (what the budget leaves), and at least one.
unsigned labelled_output_workers(std::uint64_t largest, std::uint64_t memory);

/// labelled_output_workers() for acquisitions of `vertex_counts` vertices, against what the
/// memory `budget` leaves beside the resident set now.
unsigned labelled_outputs_at_once(std::span<const std::uint64_t> vertex_counts, std::uint64_t bytes_per_vertex,
                                  bool pictures, std::uint64_t budget);

/// Writes <dir>/<k>_<name>.ply and .png per acquisition, <dir>/pairs.bin and
/// <dir>/summary.json (last), each atomically; `params.at_once` of the files at a time (the
/// same bytes for any number). `described`: the acquisitions and dates (its meshes are not
/// used).
void write_detect_outputs(const Config& config, const LoadedAcquisitions& described, DetectOutputSource& source,
                          const DetectOutputParams& params);

/// Removes what write_detect_outputs wrote in `dir` before (the files its summary.json lists,
/// pairs.bin, then summary.json): a run that writes no labels (`[output] labels = false`)
/// leaves no earlier run's labels beside its mosaic, which they no longer describe.
void remove_detect_outputs(const std::filesystem::path& dir);

/// `citymesh detect`'s source: the meshes and the result it has in memory.
class InMemoryDetectOutput final : public DetectOutputSource {
 public:
  /// Bytes the writer holds per vertex while an acquisition is fed (its positions, a slot).
  static constexpr std::uint64_t kBytesPerVertex = 16;

  InMemoryDetectOutput(const LoadedAcquisitions& input, const ChangeResult& result) : input_(input), result_(result) {}
  LabelledOutputParams layout(std::size_t k) override;
  void feed(std::size_t k, LabelledAcquisitionWriter& out) override;
  std::uint64_t write_pairs(const std::filesystem::path& path) override;
  [[nodiscard]] ChangeStats stats() const override { return result_.stats; }

 private:
  const LoadedAcquisitions& input_;
  const ChangeResult& result_;
};

/// The picture colours, as in the paper's figures.
Rgb8 detect_color(TriangleState state, bool kept, bool refutes);

}  // namespace citymesh::app
