// SPDX-License-Identifier: MIT
// The steps `citymesh detect` and `citymesh run` share.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "acquisitions.h"
#include "citymesh/change/detect.h"

namespace CLI {
class App;
}

namespace citymesh::app {

struct PictureOptions {
  double pixel_size = 0.05;  ///< metres per pixel
  bool pictures = true;
};

/// The options of the commands that run the pipeline on a config.
struct PipelineOptions {
  std::string config;
  std::vector<std::string> overrides;
  std::optional<unsigned> threads;
  double pixel_size = 0.05;
  bool no_pictures = false;

  void declare(CLI::App& app);
  /// The config with the overrides; checks that the acquisitions exist.
  [[nodiscard]] Config load() const;
  [[nodiscard]] PictureOptions pictures() const { return {pixel_size, !no_pictures}; }
};

struct DetectStep {
  LoadedAcquisitions input;
  ChangeResult result;
  double read_seconds = 0, detect_seconds = 0, write_seconds = 0;
};

/// Reads the config's acquisitions, runs change detection, writes <output>/detect and prints
/// a short report on stdout.
DetectStep run_detect_step(const Config& config, const PictureOptions& pictures);

}  // namespace citymesh::app
