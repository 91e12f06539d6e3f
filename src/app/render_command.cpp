// SPDX-License-Identifier: MIT
// `citymesh render`: pictures of acquisitions (simulated or not), by ray casting.
#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include <iostream>
#include <map>

#include "citymesh/core/error.h"
#include "citymesh/io/mesh_io.h"
#include "citymesh/render/render.h"
#include "citymesh/sim/simulate.h"
#include "command.h"

namespace citymesh::app {

namespace {

/// How an object is drawn: its class and that class's colour.
struct ObjectStyle {
  std::string cls;
  Rgb8 color;
};

/// Object id -> class and colour, from a simulation's objects.json. Classes take palette
/// colours in the order they first appear, so colours are stable for a scene.
std::map<std::uint32_t, ObjectStyle> object_classes(const std::filesystem::path& sim) {
  std::map<std::uint32_t, ObjectStyle> classes;
  std::map<std::string, Rgb8> class_colors;
  for (const ObjectRecord& o : read_objects(sim)) {
    const auto [it, added] = class_colors.emplace(o.cls, Rgb8{});
    if (added) it->second = palette_color(static_cast<std::uint32_t>(class_colors.size() - 1));
    classes[o.id] = {o.cls, it->second};
  }
  return classes;
}

class RenderCommand final : public Command {
 public:
  std::string_view name() const override { return "render"; }
  std::string_view summary() const override { return "draw acquisitions to a PNG (map or oblique view)"; }

  void declare(CLI::App& app) override {
    app.add_option("files", files_, "PLY meshes to draw (or use --sim)")->check(CLI::ExistingFile);
    app.add_option("--sim", sim_, "a citymesh simulate folder")->check(CLI::ExistingDirectory);
    app.add_option("--epoch", epoch_, "with --sim: draw only this epoch (default: all)");
    app.add_option("--color", color_, "class (with --sim: object class), input (one colour per file/epoch), height")
        ->check(CLI::IsMember({"class", "input", "height"}));
    app.add_option("--out", out_, "PNG file to write")->required();
    app.add_option("--pixel", view_.pixel_size, "metres per pixel")->check(CLI::Range(0.005, 100.0));
    app.add_option("--elevation", view_.elevation_deg, "view elevation, degrees (90: map)")->check(CLI::Range(5.0, 90.0));
    app.add_option("--azimuth", view_.azimuth_deg, "view azimuth, degrees from +x")->check(CLI::Range(-360.0, 360.0));
    app.footer("Examples:\n  citymesh render --sim sim --epoch 3 --color class --out epoch3.png\n"
               "  citymesh render --sim sim --color input --out epochs.png\n"
               "  citymesh render scan.ply --color height --elevation 35 --out scan.png");
  }

  void run() override {
    std::vector<std::filesystem::path> inputs;
    if (!sim_.empty()) {
      for (int k = 0; std::filesystem::exists(sim_ / fmt::format("acq_{}.ply", k)); ++k) {
        if (epoch_ < 0 || epoch_ == k) inputs.push_back(sim_ / fmt::format("acq_{}.ply", k));
      }
      if (inputs.empty()) throw InputError(fmt::format("{}: no acq_<k>.ply for the requested epoch", sim_.string()));
    }
    for (const auto& f : files_) inputs.emplace_back(f);
    if (inputs.empty()) throw UsageError("nothing to draw: give PLY files or --sim DIR");
    if (color_ == "class" && sim_.empty()) throw UsageError("--color class needs --sim (the ground truth)");

    MeshReadParams read;
    read.ply.require_sensor_origin = false;
    std::vector<Mesh> meshes;
    for (const auto& path : inputs) meshes.push_back(read_mesh(path, read).mesh);
    const auto classes = color_ == "class" ? object_classes(sim_) : std::map<std::uint32_t, ObjectStyle>{};
    std::map<std::string, Rgb8> legend;
    std::vector<RenderLayer> layers;
    for (std::size_t i = 0; i < meshes.size(); ++i) layers.push_back({&meshes[i], colors(meshes[i], inputs[i], i, classes, legend)});
    const Image image = render_orthographic(layers, view_);
    write_png(out_, image);
    std::cout << fmt::format("{}: {} x {} pixels, {} meshes\n", out_, image.width, image.height, meshes.size());
    for (const auto& [label, c] : legend) std::cout << fmt::format("  {:>14}: rgb({}, {}, {})\n", label, c.r, c.g, c.b);
  }

 private:
  std::vector<Rgb8> colors(const Mesh& m, const std::filesystem::path& path, std::size_t layer,
                           const std::map<std::uint32_t, ObjectStyle>& classes, std::map<std::string, Rgb8>& legend) {
    std::vector<Rgb8> out(m.triangle_count());
    if (color_ == "input") {
      const Rgb8 c = palette_color(static_cast<std::uint32_t>(layer) + 1);
      legend[path.filename().string()] = c;
      std::fill(out.begin(), out.end(), c);
    } else if (color_ == "height") {
      for (std::size_t t = 0; t < out.size(); ++t) {
        const double z = m.world_position(m.triangles[t][0]).z - m.origin.z;
        const auto k = static_cast<std::uint8_t>(std::clamp(z * 12.0, 0.0, 255.0));
        out[t] = {k, static_cast<std::uint8_t>(120 + k / 2), static_cast<std::uint8_t>(255 - k)};
      }
    } else {
      auto truth_path = path;
      const std::vector<std::uint32_t> truth = read_truth(truth_path.replace_extension(".truth"));
      if (truth.size() != out.size()) throw InputError(fmt::format("{}: ground truth does not match the mesh", truth_path.string()));
      for (std::size_t t = 0; t < out.size(); ++t) {
        const auto style = classes.find(truth[t]);
        if (style == classes.end()) {
          throw InputError(fmt::format("{}: face {} names object {}, absent from objects.json", truth_path.string(), t,
                                       truth[t]));
        }
        out[t] = legend[style->second.cls] = style->second.color;
      }
    }
    return out;
  }

  std::vector<std::string> files_;
  std::filesystem::path sim_;
  int epoch_ = -1;
  std::string color_ = "input";
  std::string out_;
  ViewParams view_;
};

}  // namespace

std::unique_ptr<Command> make_render_command() { return std::make_unique<RenderCommand>(); }

}  // namespace citymesh::app
