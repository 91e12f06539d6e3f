// SPDX-License-Identifier: MIT
#include "mosaic_eval.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <functional>
#include <numbers>

#include "citymesh/core/error.h"
#include "citymesh/core/parallel.h"
#include "citymesh/mosaic/edges.h"
#include "citymesh/mosaic/proximity.h"
#include "citymesh/sim/simulate.h"
#include "detect_output.h"
#include "face_table.h"
#include "mosaic_output.h"

namespace citymesh::app {

nlohmann::json read_json(const std::filesystem::path& path, std::string_view what) {
  std::ifstream in(path);
  if (!in) throw InputError(fmt::format("{}: cannot open ({})", path.string(), what));
  try {
    return nlohmann::json::parse(in);
  } catch (const nlohmann::json::exception& e) {
    throw InputError(fmt::format("{}: {}", path.string(), e.what()));
  }
}

std::map<std::uint32_t, ObjectInfo> objects_by_id(const std::filesystem::path& sim) {
  std::map<std::uint32_t, ObjectInfo> objects;
  for (ObjectRecord& o : read_objects(sim)) objects[o.id] = {std::move(o.cls), std::move(o.fate)};
  return objects;
}

namespace {

/// The lookup both object_of overloads share (Map: the catalogue, const or not).
template <class Map>
auto& find_object(Map& objects, const std::vector<std::uint32_t>& truth, double source_face, const FaceOrigin& origin) {
  if (!(source_face >= 0 && source_face < static_cast<double>(truth.size()))) {
    throw InputError(fmt::format("{}: face {}: source_face {} is not a face of {} ({} faces)", origin.ply.string(),
                                 origin.face, source_face, origin.truth.string(), truth.size()));
  }
  const std::uint32_t id = truth[static_cast<std::size_t>(source_face)];
  const auto it = objects.find(id);
  if (it == objects.end())
    throw InputError(fmt::format("{}: object {} is not in objects.json", origin.truth.string(), id));
  return it->second;
}

}  // namespace

ObjectInfo& object_of(std::map<std::uint32_t, ObjectInfo>& objects, const std::vector<std::uint32_t>& truth,
                      double source_face, const FaceOrigin& origin) {
  return find_object(objects, truth, source_face, origin);
}

const ObjectInfo& object_of(const std::map<std::uint32_t, ObjectInfo>& objects, const std::vector<std::uint32_t>& truth,
                            double source_face, const FaceOrigin& origin) {
  return find_object(objects, truth, source_face, origin);
}

std::vector<std::size_t> by_date(const nlohmann::json& acquisitions) {
  std::vector<std::size_t> order(acquisitions.size());
  for (std::size_t k = 0; k < order.size(); ++k) order[k] = k;
  const auto date = [&](std::size_t k) { return acquisitions[k].value("date", std::string()); };
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return date(a) < date(b); });
  return order;
}

std::filesystem::path truth_file(const std::filesystem::path& truth_dir, const nlohmann::json& acquisition) {
  const std::filesystem::path input = acquisition.at("input").get<std::string>();
  return truth_dir / input.filename().replace_extension(".truth");
}

namespace {

/// A face whose centroid lies on output of another source (within this of its plane and
/// projecting inside it), with normals within kParallelDeg, doubles it: a few centimetres,
/// the scale of scan noise.
constexpr double kOverlapDistance = 0.03;
constexpr double kParallelDeg = 30.0;

Vec3d centroid(const TriangleCorners& c) { return (c[0] + c[1] + c[2]) / 3.0; }
double area(const TriangleCorners& c) { return 0.5 * doubled_area(c[0], c[1], c[2]); }
Vec3d unit_normal(const TriangleCorners& c) {
  const Vec3d n = cross(c[1] - c[0], c[2] - c[0]);
  const double len = norm(n);
  return len > 0 ? n / len : Vec3d{0, 0, 0};
}

/// Sums per block in block order: the same total whatever the thread count.
template <class Body>
double parallel_sum(std::size_t n, Body body) {
  constexpr std::size_t kGrain = 8192;
  std::vector<double> partial((n + kGrain - 1) / kGrain, 0.0);
  parallel_for_blocks(n, kGrain, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) partial[b / kGrain] += body(i);
  });
  double sum = 0;
  for (const double p : partial) sum += p;
  return sum;
}

struct OutputMesh {
  FaceTable table;
  Mesh local;
  std::vector<std::int32_t> source;  ///< per triangle: source acquisition or -1
  std::vector<Vec3d> normal;
};

OutputMesh read_output(const std::filesystem::path& ply) {
  OutputMesh o;
  o.table = read_face_table(ply, {kSourceAcqProperty, kSourceFaceProperty});
  const Vec3d origin = o.table.positions.empty() ? Vec3d{} : whole_metre_origin(o.table.positions.front());
  o.local = o.table.local_mesh(origin);
  for (std::size_t t = 0; t < o.table.triangles.size(); ++t) {
    o.source.push_back(static_cast<std::int32_t>(o.table.extras[0][t]));
    o.normal.push_back(unit_normal(o.table.corners(t)));
  }
  return o;
}

/// Boundary edges of the output (used by one triangle) and the part of them lying within
/// `reach` of output from another source: the seams left open.
std::pair<double, double> boundary_and_seam_length(const OutputMesh& o, const MeshProximity& near, double reach) {
  const std::vector<EdgeUse> boundary = boundary_edges(o.table.triangles);
  double total = 0;
  const double seam = parallel_sum(boundary.size(), [&](std::size_t i) {
    const EdgeUse& e = boundary[i];
    const double length = norm(o.table.positions[e.lo] - o.table.positions[e.hi]);
    const Vec3d mid = (Vec3d(o.local.positions[e.lo]) + Vec3d(o.local.positions[e.hi])) * 0.5;
    const std::int32_t own = o.source[e.triangle];
    return near.any_within(mid, reach, [&](std::uint32_t u) { return o.source[u] != own; }) ? length : 0.0;
  });
  for (const EdgeUse& e : boundary) total += norm(o.table.positions[e.lo] - o.table.positions[e.hi]);
  return {total, seam};
}

/// The output area of input triangles (source >= 0) whose centroid lies on another output
/// triangle u with doubles(t, u) (within kOverlapDistance of its plane, projecting inside it,
/// normals within kParallelDeg): surface the output holds twice.
double area_doubled(const OutputMesh& out, const MeshProximity& near,
                    const std::function<bool(std::size_t, std::uint32_t)>& doubles) {
  const double cos_parallel = std::cos(kParallelDeg * std::numbers::pi / 180.0);
  return parallel_sum(out.source.size(), [&](std::size_t t) {
    if (out.source[t] < 0) return 0.0;
    const TriangleCorners c = out.table.corners(t);
    const Vec3d p = centroid(c) - out.local.origin;
    const bool covered = near.any_over(p, kOverlapDistance, [&](std::uint32_t u) {
      return doubles(t, u) && std::abs(dot(out.normal[u], out.normal[t])) >= cos_parallel;
    });
    return covered ? area(c) : 0.0;
  });
}

/// Where the static input area the output does not cover went (m²): faces the change step
/// dropped, faces it kept that are not in the output (the mosaic did not select them, or
/// clipping removed them whole: the output cannot tell which), and faces in the output whose
/// centroid it no longer covers (clipping or snapping cut them back).
struct UncoveredStatic {
  double dropped = 0, not_in_output = 0, cut_back = 0;
};

}  // namespace

nlohmann::json evaluate_mosaic(const std::filesystem::path& output, const std::filesystem::path& truth_dir,
                               const nlohmann::json& detect_summary,
                               const std::map<std::uint32_t, ObjectInfo>& objects) {
  const std::filesystem::path dir = output / "mosaic";
  const nlohmann::json summary = read_json(dir / "summary.json", "run citymesh run first");
  const double reach = summary.at("distance_threshold").get<double>();
  const std::filesystem::path output_ply = dir / kMosaicFile;
  if (summary.value("ply", std::string(kMosaicFile)).empty()) {
    throw InputError(
        fmt::format("{}: the run wrote no mosaic ([output] mosaic_ply = false); run citymesh run with "
                    "--set output.mosaic_ply=true to score it",
                    output_ply.string()));
  }
  const OutputMesh out = read_output(output_ply);
  const MeshProximity near(out.local, reach);
  const auto& acquisitions = detect_summary.at("acquisitions");

  // The output's own faces: dynamic residue, overlap, edge length.
  std::vector<std::filesystem::path> truth_paths;
  std::vector<std::vector<std::uint32_t>> truths;
  for (const auto& a : acquisitions) {
    truth_paths.push_back(truth_file(truth_dir, a));
    truths.push_back(read_truth(truth_paths.back()));
  }
  double out_area = 0, out_dynamic = 0, out_edges = 0;
  std::uint64_t out_edge_count = 0;
  // Per acquisition and source face, 1 when an output face comes from it.
  std::vector<std::vector<std::uint8_t>> in_output(truths.size());
  for (std::size_t k = 0; k < truths.size(); ++k) in_output[k].assign(truths[k].size(), 0);
  for (std::size_t t = 0; t < out.source.size(); ++t) {
    const std::int32_t a = out.source[t];
    if (a < 0) continue;
    if (static_cast<std::size_t>(a) >= truths.size()) {
      throw InputError(fmt::format("{}: face {}: source_acq {} is not an acquisition of the run", output_ply.string(),
                                   out.table.faces[t], a));
    }
    const TriangleCorners c = out.table.corners(t);
    const auto k = static_cast<std::size_t>(a);
    const ObjectInfo& o =
        object_of(objects, truths[k], out.table.extras[1][t], {output_ply, truth_paths[k], out.table.faces[t]});
    in_output[k][static_cast<std::size_t>(out.table.extras[1][t])] = 1;  // checked by object_of
    out_area += area(c);
    out_dynamic += o.fate == "remove" ? area(c) : 0.0;
    out_edges += norm(c[1] - c[0]) + norm(c[2] - c[1]) + norm(c[0] - c[2]);
    out_edge_count += 3;
  }
  const double overlap = area_doubled(
      out, near, [&](std::size_t t, std::uint32_t u) { return out.source[u] >= 0 && out.source[u] != out.source[t]; });
  // Two layers of one source: its own triangles that are not neighbours (a pass whose turns
  // overlap, kept whole).
  const auto neighbours = [&](std::size_t t, std::uint32_t u) {
    for (const std::uint32_t v : out.table.triangles[t]) {
      for (const std::uint32_t w : out.table.triangles[u]) {
        if (v == w) return true;
      }
    }
    return false;
  };
  const double layered = area_doubled(out, near, [&](std::size_t t, std::uint32_t u) {
    return u != t && out.source[u] == out.source[t] && !neighbours(t, u);
  });

  // The inputs: how much of the static structure and of what the change step kept the
  // output still covers, and the finest input resolution.
  double static_area = 0, static_covered = 0, static_open = 0, finest_edge = 0;
  UncoveredStatic uncovered;
  for (const std::size_t k : by_date(acquisitions)) {
    if (acquisitions[k].value("withdrawn", false)) continue;  // not an input of the run
    const std::filesystem::path ply = output / "detect" / acquisitions[k].at("ply").get<std::string>();
    const FaceTable in = read_face_table(ply, {kSourceFaceProperty, kKeptProperty});
    std::vector<double> face_area(in.triangles.size()), covered(in.triangles.size()), under(in.triangles.size());
    double edges = 0;
    std::uint64_t edge_count = 0;
    parallel_for_blocks(in.triangles.size(), 8192, [&](std::size_t b, std::size_t e) {
      for (std::size_t t = b; t < e; ++t) {
        const TriangleCorners c = in.corners(t);
        face_area[t] = area(c);
        covered[t] = near.any_within(centroid(c) - out.local.origin, reach) ? 1.0 : 0.0;
        under[t] = near.any_over(centroid(c) - out.local.origin, reach) ? 1.0 : 0.0;
      }
    });
    for (std::size_t t = 0; t < in.triangles.size(); ++t) {
      const ObjectInfo& o = object_of(objects, truths[k], in.extras[0][t], {ply, truth_paths[k], in.faces[t]});
      if (o.fate == "keep") {
        static_area += face_area[t];
        static_covered += covered[t] * face_area[t];
        static_open += (1.0 - under[t]) * face_area[t];
        if (covered[t] == 0) {
          const double face = in.extras[0][t];  // checked against the truth file by object_of
          const bool kept = in.extras[1][t] != 0, selected = in_output[k][static_cast<std::size_t>(face)] != 0;
          (kept ? (selected ? uncovered.cut_back : uncovered.not_in_output) : uncovered.dropped) += face_area[t];
        }
      }
      if (in.extras[1][t] != 0) {
        const TriangleCorners c = in.corners(t);
        edges += norm(c[1] - c[0]) + norm(c[2] - c[1]) + norm(c[0] - c[2]);
        edge_count += 3;
      }
    }
    if (edge_count > 0) {
      const double mean = edges / double(edge_count);
      finest_edge = finest_edge == 0 ? mean : std::min(finest_edge, mean);
    }
  }
  const auto [boundary, seam] = boundary_and_seam_length(out, near, reach);
  const double mean_edge = out_edge_count > 0 ? out_edges / double(out_edge_count) : 0.0;
  return {{"method", summary.value("method", "")},
          {"triangles", out.table.triangles.size()},
          {"area", out_area},
          {"overlap_ratio", out_area > 0 ? overlap / out_area : 0.0},
          {"layered_ratio", out_area > 0 ? layered / out_area : 0.0},
          {"seam_length", seam},
          {"open_boundary_length", boundary},
          {"hole_ratio", static_area > 0 ? static_open / static_area : 0.0},
          {"static_completeness", static_area > 0 ? static_covered / static_area : 1.0},
          {"static_area", static_area},
          {"static_uncovered",
           {{"dropped_by_change_step", uncovered.dropped},
            {"kept_not_in_output", uncovered.not_in_output},
            {"in_output_cut_back", uncovered.cut_back}}},
          {"dynamic_residue", out_area > 0 ? out_dynamic / out_area : 0.0},
          {"mean_edge_length", mean_edge},
          {"finest_mean_edge_length", finest_edge},
          {"edge_length_ratio", finest_edge > 0 ? mean_edge / finest_edge : 0.0}};
}

}  // namespace citymesh::app
