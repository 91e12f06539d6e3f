// SPDX-License-Identifier: MIT
// Orthographic pictures of meshes (top-down maps, oblique views) by z-buffer rasterisation, and
// PNG output.
#pragma once

#include <cstdint>
#include <filesystem>
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
