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

namespace citymesh::app {

namespace {

nlohmann::json read_json(const std::filesystem::path& path, std::string_view what) {
  std::ifstream in(path);
  if (!in) throw InputError(fmt::format("{}: cannot open ({})", path.string(), what));
  try {
    return nlohmann::json::parse(in);
  } catch (const nlohmann::json::exception& e) {
    throw InputError(fmt::format("{}: {}", path.string(), e.what()));
  }
}

struct ObjectInfo {
  std::string cls, fate;
  double area = 0, kept_area = 0;
  std::uint64_t triangles = 0;
};

std::map<std::uint32_t, ObjectInfo> objects_by_id(const std::filesystem::path& sim) {
  std::map<std::uint32_t, ObjectInfo> objects;
  for (ObjectRecord& o : read_objects(sim)) objects[o.id] = {std::move(o.cls), std::move(o.fate)};
  return objects;
}

/// Adds the area of every face of one labelled PLY to its ground-truth object.
void score_acquisition(const std::filesystem::path& ply, const std::filesystem::path& truth_file,
                       std::map<std::uint32_t, ObjectInfo>& objects) {
  const std::vector<std::uint32_t> truth = read_truth(truth_file);
  PlyReadParams params;
  params.require_sensor_origin = false;
  params.extra_face_properties = {kSourceFaceProperty, kKeptProperty};
  PlyReader reader(ply, params);
  PlyVertexChunk vertices;
  PlyFaceChunk faces;
  std::vector<Vec3d> positions;
  for (auto kind = reader.next(vertices, faces); kind != PlyReader::ChunkKind::end;
       kind = reader.next(vertices, faces)) {
    if (kind == PlyReader::ChunkKind::vertices) {
      positions.insert(positions.end(), vertices.positions.begin(), vertices.positions.end());
      continue;
    }
    for (std::size_t t = 0; t < faces.triangles.size(); ++t) {
      const double source = faces.extras[0][t];
      if (!(source >= 0 && source < static_cast<double>(truth.size()))) {
        throw InputError(fmt::format("{}: face {}: source_face {} is not a face of {} ({} faces)", ply.string(),
                                     faces.faces[t], source, truth_file.string(), truth.size()));
      }
      const auto it = objects.find(truth[static_cast<std::size_t>(source)]);
      if (it == objects.end()) {
        throw InputError(fmt::format("{}: object {} is not in objects.json", truth_file.string(),
                                     truth[static_cast<std::size_t>(source)]));
      }
      const Triangle& tri = faces.triangles[t];
      const double area = 0.5 * doubled_area(positions[tri[0]], positions[tri[1]], positions[tri[2]]);
      it->second.area += area;
      it->second.kept_area += faces.extras[1][t] != 0 ? area : 0.0;
      ++it->second.triangles;
    }
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
    const nlohmann::json summary = read_json(detect / "summary.json", "run citymesh detect first");
    std::map<std::uint32_t, ObjectInfo> objects = objects_by_id(truth_);
    try {
      for (const auto& a : summary.at("acquisitions")) {
        const std::filesystem::path input = a.at("input").get<std::string>();
        const std::filesystem::path truth =
            std::filesystem::path(truth_) / input.filename().replace_extension(".truth");
        score_acquisition(detect / a.at("ply").get<std::string>(), truth, objects);
      }
    } catch (const nlohmann::json::exception& e) {
      throw InputError(fmt::format("{}: {}", (detect / "summary.json").string(), e.what()));
    }
    const nlohmann::json result = evaluate(objects);
    write_file_atomically(std::filesystem::path(output_) / "eval.json", result.dump(1) + "\n");
    print_summary(result, std::cout);
  }

 private:
  std::string output_, truth_;
};

}  // namespace

std::unique_ptr<Command> make_eval_command() { return std::make_unique<EvalCommand>(); }

}  // namespace citymesh::app
