// SPDX-License-Identifier: MIT
#include "citymesh/sim/simulate.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <nlohmann/json.hpp>
#include <set>

#include "citymesh/config/config.h"
#include "citymesh/core/error.h"
#include "citymesh/core/parallel.h"
#include "citymesh/io/mesh_io.h"
#include "citymesh/sim/scanner.h"
#include "test_support.h"

namespace citymesh {
namespace {

SimulateParams small_street(const std::filesystem::path& out) {
  SimulateParams p;
  p.street.length = 40.0f;
  p.out = out;
  return p;
}

/// Brute force: the largest x-y distance from a triangle's centroid to a corner over the
/// simulated passes.
double largest_reach(const SimulationReport& report) {
  double largest = 0;
  for (const SimulatedEpoch& e : report.epochs) {
    const Mesh mesh = read_mesh(e.ply).mesh;
    for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
      const auto corners = mesh.corners(t);
      const Vec3d centroid = (corners[0] + corners[1] + corners[2]) / 3.0;
      for (const Vec3d& q : corners) largest = std::max(largest, std::hypot(q.x - centroid.x, q.y - centroid.y));
    }
  }
  return largest;
}

/// The written config's halo against the one the passes need (`run` warns below it).
void expect_halo_that_tiles_need(const SimulationReport& report, const std::filesystem::path& dir) {
  const Config config = load_config(dir / "config.toml");
  const double needed = largest_reach(report) + config.change.distance_threshold;
  if (needed <= TilingParams{}.halo) {
    EXPECT_EQ(config.tiling.halo, TilingParams{}.halo);
    return;
  }
  EXPECT_GE(config.tiling.halo, needed);
  EXPECT_LE(config.tiling.halo, needed + 0.1 + 1e-6);  // rounded up to 10 cm
}

TEST(StreetScene, ScriptedChangesHaveTheExpectedFates) {
  const Scene scene = make_street_scene({});
  const Duration ts = std::chrono::days(30);
  std::map<ObjectClass, std::set<Fate>> fates;
  for (const SceneObject& o : scene.objects) fates[o.type].insert(fate_of(o, scene.epochs, ts));
  EXPECT_EQ(fates[ObjectClass::ground], std::set<Fate>{Fate::keep});
  EXPECT_EQ(fates[ObjectClass::building], std::set<Fate>{Fate::keep});
  EXPECT_EQ(fates[ObjectClass::kiosk], std::set<Fate>{Fate::keep});
  EXPECT_EQ(fates[ObjectClass::wall], std::set<Fate>{Fate::remove});
  EXPECT_EQ(fates[ObjectClass::market_stall], std::set<Fate>{Fate::remove});
  EXPECT_EQ(fates[ObjectClass::moving_car], std::set<Fate>{Fate::remove});
  EXPECT_EQ(fates[ObjectClass::planter], std::set<Fate>{Fate::unconfirmed});
  EXPECT_TRUE(fates[ObjectClass::parked_car].count(Fate::remove));
  // The car seen twice, four days apart, is not sustainable: every parked car but those of
  // the last epoch must go.
  for (const SceneObject& o : scene.objects) {
    if (o.type != ObjectClass::parked_car) continue;
    int seen = 0;
    for (const EpochDrive& e : scene.epochs) seen += o.present_at(e.date);
    EXPECT_GE(seen, 1);
    EXPECT_LE(seen, 2);
  }
  EXPECT_EQ(scene.epochs.size(), 6u);
  EXPECT_EQ(scene.epochs[2].date - scene.epochs[1].date, std::chrono::days(4));
}

TEST(StreetScene, RefusesTooFewEpochs) {
  StreetParams p;
  p.epochs = 5;
  EXPECT_THROW(make_street_scene(p), ConfigError);
}

TEST(Simulate, GroundTruthIsConsistentWithTheScene) {
  test::TempDir dir;
  const SimulateParams p = small_street(dir.path());
  const SimulationReport report = simulate(p);
  const Scene scene = make_street_scene(p.street);
  std::map<std::uint32_t, const SceneObject*> by_id;
  for (const SceneObject& o : scene.objects) by_id[o.id] = &o;
  ASSERT_EQ(report.epochs.size(), 6u);
  std::set<ObjectClass> seen_classes;
  for (std::size_t k = 0; k < report.epochs.size(); ++k) {
    const MeshReadResult m = read_mesh(report.epochs[k].ply);
    const std::vector<std::uint32_t> truth = read_truth(report.epochs[k].truth);
    ASSERT_EQ(truth.size(), m.mesh.triangle_count()) << "every face has an object";
    EXPECT_TRUE(m.mesh.has_sensor_positions());
    std::size_t no_surface = 0;
    for (std::uint32_t id : truth) {
      if (id == kNoSurface) {
        ++no_surface;  // a facet bridging a depth jump
        continue;
      }
      ASSERT_TRUE(by_id.count(id)) << id;
      const SceneObject& o = *by_id[id];
      ASSERT_TRUE(o.present_at(scene.epochs[k].date)) << "object " << id << " seen in epoch " << k << " outside its lifespan";
      seen_classes.insert(o.type);
    }
    EXPECT_LT(no_surface, truth.size() / 4) << "most faces lie on a surface";
    EXPECT_GT(no_surface, 0u) << "sensor meshing bridges some depth jumps";
  }
  for (ObjectClass c : {ObjectClass::ground, ObjectClass::building, ObjectClass::parked_car, ObjectClass::pedestrian,
                        ObjectClass::kiosk, ObjectClass::wall, ObjectClass::planter, ObjectClass::pole}) {
    EXPECT_TRUE(seen_classes.count(c)) << object_class_name(c) << " never scanned";
  }
  const auto objects = nlohmann::json::parse(test::read_text(dir / "objects.json"));
  EXPECT_EQ(objects["objects"].size(), scene.objects.size());
  // The shared reader gives every object in file order, then the no-surface record.
  const std::vector<ObjectRecord> records = read_objects(dir.path());
  ASSERT_EQ(records.size(), scene.objects.size() + 1);
  for (std::size_t i = 0; i < scene.objects.size(); ++i) {
    EXPECT_EQ(records[i].id, scene.objects[i].id);
    EXPECT_EQ(records[i].cls, object_class_name(scene.objects[i].type));
  }
  EXPECT_EQ(records.back().id, kNoSurface);
  EXPECT_EQ(records.back().fate, "none");
  test::write_text(dir / "objects.json", "{\"objects\": [{\"id\": 1}]}");
  EXPECT_THROW(read_objects(dir.path()), InputError);
}

TEST(Simulate, SameSeedSameBytesWhateverTheThreadCount) {
  test::TempDir a, b, c;
  {
    ThreadLimit one(1);
    simulate(small_street(a.path()));
  }
  {
    ThreadLimit two(2);
    simulate(small_street(b.path()));
  }
  for (const char* f : {"acq_0.ply", "acq_3.ply", "acq_5.truth", "objects.json", "config.toml"}) {
    EXPECT_EQ(test::read_text(a / f), test::read_text(b / f)) << f;
  }
  SimulateParams other = small_street(c.path());
  other.street.seed = 2;
  other.scanner.seed = 2;
  simulate(other);
  EXPECT_NE(test::read_text(a / "acq_0.ply"), test::read_text(c / "acq_0.ply"));
}

TEST(Simulate, WrittenConfigIsValid) {
  test::TempDir dir;
  expect_halo_that_tiles_need(simulate(small_street(dir.path())), dir.path());
  const auto r = test::run_citymesh("config --check " + (dir / "config.toml").string());
  EXPECT_EQ(r.exit_code, 0) << r.err;
  const Config config = load_config(dir / "config.toml");
  EXPECT_EQ(config.tiling.halo, TilingParams{}.halo);  // a profiler's triangles are short
}

TEST(Simulate, CityModeKeepsObjectIdsUniqueAndStreetsApart) {
  test::TempDir dir;
  SimulateParams p = small_street(dir.path());
  p.streets = 3;
  p.street.length = 30.0f;
  const SimulationReport r = simulate(p);
  const auto objects = nlohmann::json::parse(test::read_text(dir / "objects.json"));
  std::set<std::uint32_t> ids;
  for (const auto& o : objects["objects"]) EXPECT_TRUE(ids.insert(o["id"].get<std::uint32_t>()).second);
  EXPECT_EQ(objects["streets"].size(), 3u);
  const std::vector<std::uint32_t> truth = read_truth(r.epochs[0].truth);
  std::set<std::uint32_t> streets_seen;
  for (std::uint32_t id : truth) {
    if (id == kNoSurface) continue;
    ASSERT_TRUE(ids.count(id)) << id;
    streets_seen.insert(id / 1'000'000);
  }
  EXPECT_EQ(streets_seen, (std::set<std::uint32_t>{0, 1, 2}));
  // The third street lies two spacings north of the first.
  const MeshReadResult m = read_mesh(r.epochs[0].ply);
  Box3d box;
  for (std::size_t v = 0; v < m.mesh.vertex_count(); ++v) box.extend(m.mesh.world_position(v));
  EXPECT_GT(box.max.y - box.min.y, 2 * p.street_spacing);
  EXPECT_LT(box.max.y - box.min.y, 2 * p.street_spacing + 2 * p.street.width + 10);
}

TEST(Simulate, SpinningScannerMeshesEachTurnConsistently) {
  test::TempDir a, b;
  SimulateParams p = small_street(a.path());
  p.scanner.mode = ScannerParams::Mode::spinning;
  p.scanner.rings = 16;
  p.scanner.columns = 256;
  p.scanner.rotation_rate = 1.0f;
  const SimulationReport r = simulate(p);
  const Scene scene = make_street_scene(p.street);
  for (std::size_t k = 0; k < r.epochs.size(); ++k) {
    EXPECT_EQ(r.epochs[k].rays % (16u * 256u), 0u);  // whole turns
    const MeshReadResult m = read_mesh(r.epochs[k].ply);
    const std::vector<std::uint32_t> truth = read_truth(r.epochs[k].truth);
    ASSERT_EQ(truth.size(), m.mesh.triangle_count());
    EXPECT_GT(m.mesh.triangle_count(), 1000u);
  }
  // Its far, grazing triangles are long: the config asks for the halo they need.
  ASSERT_GT(largest_reach(r) + 0.1, TilingParams{}.halo);
  expect_halo_that_tiles_need(r, a.path());
  {
    ThreadLimit one(1);
    p.out = b.path();
    simulate(p);
  }
  EXPECT_EQ(test::read_text(a / "acq_2.ply"), test::read_text(b / "acq_2.ply"));
}

TEST(Truth, RoundTripsAndDetectsCorruption) {
  test::TempDir dir;
  const std::vector<std::uint32_t> ids{5, 1, 9, 9, 2};
  write_truth(dir / "t.truth", ids);
  EXPECT_EQ(read_truth(dir / "t.truth"), ids);
  std::string bytes = test::read_text(dir / "t.truth");
  bytes[20] ^= 1;
  test::write_text(dir / "bad.truth", bytes);
  EXPECT_THROW(read_truth(dir / "bad.truth"), InputError);
  test::write_text(dir / "short.truth", bytes.substr(0, 20));
  EXPECT_THROW(read_truth(dir / "short.truth"), InputError);
}

}  // namespace
}  // namespace citymesh
