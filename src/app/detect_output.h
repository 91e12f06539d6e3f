// SPDX-License-Identifier: MIT
// What `citymesh detect` writes: per acquisition a labelled PLY and a top-down PNG, and a
// summary JSON. `citymesh eval` reads them back.
#pragma once

#include <filesystem>
#include <string_view>

#include "acquisitions.h"
#include "citymesh/change/detect.h"

namespace citymesh::app {

/// Face properties of the labelled PLY (besides vertex_indices).
inline constexpr const char* kStateProperty = "state";          ///< uchar: 0 consistent, 1 conflicting, 2 single
inline constexpr const char* kKeptProperty = "kept";            ///< uchar: survives the time series
inline constexpr const char* kSourceFaceProperty = "source_face";  ///< int: face index in the input file
/// The consistent pairs (global triangle ids, config order), as uint32 a0 b0 a1 b1 ... with a < b.
inline constexpr const char* kPairsFile = "pairs.bin";
inline constexpr std::string_view kPairsMagic = "CMPAIRS1";

struct DetectOutputParams {
  std::filesystem::path dir;  ///< <output>/detect
  double pixel_size = 0.05;   ///< metres per pixel of the PNGs
  bool pictures = true;
  double read_seconds = 0;
};

/// Writes <dir>/<k>_<name>.ply and .png per acquisition, <dir>/pairs.bin and
/// <dir>/summary.json (last), each atomically.
void write_detect_outputs(const Config& config, const LoadedAcquisitions& input, const ChangeResult& result,
                          const DetectOutputParams& params);

/// The picture colours, as in the paper's figures.
Rgb8 detect_color(TriangleState state, bool kept, bool refutes);

}  // namespace citymesh::app
