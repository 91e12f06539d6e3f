// SPDX-License-Identifier: MIT
// Orthographic pictures of meshes (top-down maps, oblique views) by z-buffer rasterisation, and
// PNG output.
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <span>
#include <vector>

#include "citymesh/core/mesh.h"

namespace citymesh {

/// A mesh to draw and the colour of each of its triangles.
struct RenderLayer {
  const Mesh* mesh = nullptr;
  std::vector<Rgb8> face_colors;  ///< one per triangle
};

struct ViewParams {
  double pixel_size = 0.1;    ///< metres per pixel
  double elevation_deg = 90;  ///< 90: straight down (a map); lower: oblique
  double azimuth_deg = 0;     ///< direction the camera looks towards, degrees from +x towards +y
  std::uint32_t max_side = 8192;  ///< pixels; the pixel size grows to fit
  Rgb8 background{255, 255, 255};
};

struct Image {
  std::uint32_t width = 0, height = 0;
  std::vector<Rgb8> pixels;  ///< row-major, top row first
};

/// A picture drawn one layer at a time, for meshes too large to hold at once: framed by a box
/// given first, each layer drawn over the others as render_orthographic draws them (a pixel
/// shows the nearest triangle holding its centre, the first one drawn on a tie).
class OrthographicCanvas {
 public:
  /// `box`: what the picture frames, in the frame whose origin is `origin` (layers are moved
  /// into it from their own).
  OrthographicCanvas(const Box3d& box, const Vec3d& origin, const ViewParams& params);
  ~OrthographicCanvas();
  OrthographicCanvas(const OrthographicCanvas&) = delete;
  OrthographicCanvas& operator=(const OrthographicCanvas&) = delete;
  /// Throws ProcessingError when the layer's colours do not match its triangles.
  void draw(const RenderLayer& layer);
  /// The picture (once).
  [[nodiscard]] Image take();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Draws every layer, seen along the view direction, shaded by the angle between each
/// triangle and the view. The picture frames the union of the layers' bounding boxes.
/// Throws ProcessingError when a layer's colours do not match its triangles.
Image render_orthographic(std::span<const RenderLayer> layers, const ViewParams& params = {});

/// Writes an 8-bit RGB PNG atomically. Throws OutputError naming the file.
void write_png(const std::filesystem::path& path, const Image& image);

/// Reads a PNG of any colour type as 8-bit RGB (alpha dropped). Throws InputError naming the
/// file when it cannot be read or decoded.
Image read_png(const std::filesystem::path& path);

/// A distinct, stable colour for small integers (classes, epochs).
Rgb8 palette_color(std::uint32_t index);

}  // namespace citymesh
