// SPDX-License-Identifier: MIT
// `citymesh eval OUTPUT --truth SIMDIR`: scores a run's output against the simulator's ground
// truth, object by object.
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <fstream>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>

#include "citymesh/core/atomic_file.h"
#include "citymesh/core/error.h"
#include "citymesh/io/ply_reader.h"
#include "citymesh/sim/simulate.h"
#include "command.h"
#include "detect_output.h"
#include "face_table.h"
#include "mosaic_eval.h"

namespace citymesh::app {

namespace {

/// Adds the area of every face of one labelled PLY to its ground-truth object.
void score_acquisition(const std::filesystem::path& ply, const std::filesystem::path& truth_file,
                       std::map<std::uint32_t, ObjectInfo>& objects) {
  const std::vector<std::uint32_t> truth = read_truth(truth_file);
  const FaceTable table = read_face_table(ply, {kSourceFaceProperty, kKeptProperty});
  for (std::size_t t = 0; t < table.triangles.size(); ++t) {
    ObjectInfo& o = object_of(objects, truth, table.extras[0][t], {ply, truth_file, table.faces[t]});
    const TriangleCorners c = table.corners(t);
    const double area = 0.5 * doubled_area(c[0], c[1], c[2]);
    o.area += area;
    o.kept_area += table.extras[1][t] != 0 ? area : 0.0;
    ++o.triangles;
  }
}

struct Totals {
  double area = 0, kept = 0;
};

nlohmann::json evaluate(const std::map<std::uint32_t, ObjectInfo>& objects) {
  std::map<std::string, Totals> by_fate;
  std::map<std::pair<std::string, std::string>, Totals> by_class;
  nlohmann::json per_object = nlohmann::json::array();
  double worst_removed = 2.0;  // above any fraction: the first object sets it
  std::uint32_t worst_id = 0;
  double all_kept = 0;
  for (const auto& [id, o] : objects) {
    if (o.triangles == 0) continue;
    by_fate[o.fate].area += o.area;
    by_fate[o.fate].kept += o.kept_area;
    by_class[{o.cls, o.fate}].area += o.area;
    by_class[{o.cls, o.fate}].kept += o.kept_area;
    all_kept += o.kept_area;
    const double kept_fraction = o.area > 0 ? o.kept_area / o.area : 1.0;
    per_object.push_back({{"id", id},
                          {"class", o.cls},
                          {"fate", o.fate},
                          {"triangles", o.triangles},
                          {"area", o.area},
                          {"kept_fraction", kept_fraction}});
    if (o.fate == "remove" && 1.0 - kept_fraction < worst_removed) {  // ties: the lowest id
      worst_removed = 1.0 - kept_fraction;
      worst_id = id;
    }
  }
  double total_area = 0;
  for (const auto& [fate, t] : by_fate) total_area += t.area;
  nlohmann::json classes = nlohmann::json::array();
  for (const auto& [key, t] : by_class) {
    classes.push_back({{"class", key.first},
                       {"fate", key.second},
                       {"area", t.area},
                       {"kept_fraction", t.area > 0 ? t.kept / t.area : 1.0}});
  }
  const auto fraction = [&](const std::string& fate) {
    const Totals& t = by_fate[fate];
    return t.area > 0 ? t.kept / t.area : 1.0;
  };
  if (worst_removed > 1.0) worst_removed = 1.0;  // no object must go
  return {{"stage", "detect"},
          {"static_completeness", fraction("keep")},
          {"dynamic_residue", all_kept > 0 ? by_fate["remove"].kept / all_kept : 0.0},
          {"dynamic_removed_overall", 1.0 - fraction("remove")},
          {"dynamic_removed_worst_object", worst_removed},
          {"worst_dynamic_object", worst_id},
          {"unconfirmed_kept", fraction("unconfirmed")},
          {"no_surface_fraction", total_area > 0 ? by_fate["none"].area / total_area : 0.0},
          {"no_surface_kept", fraction("none")},
          {"classes", classes},
          {"objects", per_object}};
}

void print_summary(const nlohmann::json& e, std::ostream& out) {
  out << fmt::format("{:<14} {:<12} {:>10} {:>8}\n", "class", "fate", "area m2", "kept %");
  for (const auto& c : e["classes"]) {
    out << fmt::format("{:<14} {:<12} {:>10.1f} {:>8.2f}\n", c["class"].get<std::string>(),
                       c["fate"].get<std::string>(), c["area"].get<double>(), 100 * c["kept_fraction"].get<double>());
  }
  out << fmt::format("static completeness     {:.2f} % of the area of objects that must stay is kept\n",
                     100 * e["static_completeness"].get<double>());
  out << fmt::format("dynamic removal         {:.2f} % overall; worst object {} {:.2f} %\n",
                     100 * e["dynamic_removed_overall"].get<double>(), e["worst_dynamic_object"].get<std::uint32_t>(),
                     100 * e["dynamic_removed_worst_object"].get<double>());
  out << fmt::format("dynamic residue         {:.3f} % of the kept area belongs to objects that must go\n",
                     100 * e["dynamic_residue"].get<double>());
  out << fmt::format("unconfirmed kept        {:.2f} % (objects first seen less than Ts before the last scan)\n",
                     100 * e["unconfirmed_kept"].get<double>());
  out << fmt::format(
      "on no surface           {:.2f} % of the area (faces bridging depth jumps; {:.2f} % of them kept)\n",
      100 * e["no_surface_fraction"].get<double>(), 100 * e["no_surface_kept"].get<double>());
}

void print_mosaic_summary(const nlohmann::json& m, std::ostream& out) {
  out << fmt::format("mosaic ({}): {} triangles, {:.1f} m2\n", m["method"].get<std::string>(),
                     m["triangles"].get<std::uint64_t>(), m["area"].get<double>());
  out << fmt::format("  static completeness   {:.2f} % of the static input area lies within the distance threshold\n",
                     100 * m["static_completeness"].get<double>());
  if (m.contains("static_uncovered")) {
    const nlohmann::json& u = m["static_uncovered"];
    const double dropped = u["dropped_by_change_step"].get<double>(), absent = u["kept_not_in_output"].get<double>(),
                 cut = u["in_output_cut_back"].get<double>();
    out << fmt::format(
        "    the rest            {:.1f} m2: {:.1f} dropped by the change step, {:.1f} kept but not in the "
        "output, {:.1f} in the output but cut back\n",
        dropped + absent + cut, dropped, absent, cut);
  }
  out << fmt::format("  dynamic residue       {:.3f} % of the output area belongs to objects that must go\n",
                     100 * m["dynamic_residue"].get<double>());
  out << fmt::format("  overlap ratio         {:.3f} % of the output area doubles output of another source\n",
                     100 * m["overlap_ratio"].get<double>());
  if (m.contains("layered_ratio")) {
    out << fmt::format("  layered ratio         {:.3f} % of the output area doubles output of its own source\n",
                       100 * m["layered_ratio"].get<double>());
  }
  out << fmt::format("  hole ratio            {:.3f} % of the static input area has no output over it\n",
                     100 * m["hole_ratio"].get<double>());
  out << fmt::format("  seams                 {:.1f} m open between sources ({:.1f} m of open boundary in all)\n",
                     m["seam_length"].get<double>(), m["open_boundary_length"].get<double>());
  out << fmt::format("  mean edge length      {:.3f} m, {:.2f} x the finest input's\n",
                     m["mean_edge_length"].get<double>(), m["edge_length_ratio"].get<double>());
}

class EvalCommand final : public Command {
 public:
  std::string_view name() const override { return "eval"; }
  std::string_view summary() const override { return "score a run's output against a simulation's ground truth"; }

  void declare(CLI::App& app) override {
    app.add_option("output", output_, "the run's output folder (holds detect/summary.json)")
        ->required()
        ->check(CLI::ExistingDirectory);
    app.add_option("--truth", truth_, "the citymesh simulate folder the run read")
        ->required()
        ->check(CLI::ExistingDirectory);
    app.footer(
        "Writes <output>/eval.json and prints a summary. Example:\n"
        "  citymesh simulate --out sim && citymesh detect sim/config.toml && citymesh eval sim/out --truth sim");
  }

  void run() override {
    const std::filesystem::path detect = std::filesystem::path(output_) / "detect";
    const nlohmann::json summary =
        read_json(detect / "summary.json", "run citymesh detect first, or citymesh run with [output] labels = true");
    const std::map<std::uint32_t, ObjectInfo> catalogue = objects_by_id(truth_);
    std::map<std::uint32_t, ObjectInfo> objects = catalogue;  // areas added up per object
    try {
      const nlohmann::json& acquisitions = summary.at("acquisitions");
      for (const std::size_t k : by_date(acquisitions)) {
        const nlohmann::json& a = acquisitions[k];
        if (a.value("withdrawn", false)) continue;  // no labels to score
        score_acquisition(detect / a.at("ply").get<std::string>(), truth_file(truth_, a), objects);
      }
    } catch (const nlohmann::json::exception& e) {
      throw InputError(fmt::format("{}: {}", (detect / "summary.json").string(), e.what()));
    }
    nlohmann::json result = evaluate(objects);
    const bool mosaic = std::filesystem::exists(std::filesystem::path(output_) / "mosaic" / "summary.json");
    if (mosaic) {
      try {
        result["mosaic"] = evaluate_mosaic(output_, truth_, summary, catalogue);
      } catch (const nlohmann::json::exception& e) {
        throw InputError(fmt::format("{}: {}", (std::filesystem::path(output_) / "mosaic").string(), e.what()));
      }
    }
    write_file_atomically(std::filesystem::path(output_) / "eval.json", result.dump(1) + "\n");
    print_summary(result, std::cout);
    if (mosaic) print_mosaic_summary(result["mosaic"], std::cout);
  }

 private:
  std::string output_, truth_;
};

}  // namespace

std::unique_ptr<Command> make_eval_command() { return std::make_unique<EvalCommand>(); }

}  // namespace citymesh::app
