// SPDX-License-Identifier: MIT
// A procedural street scene for the simulator: objects with a class and a lifespan, and the
// epochs (dates) at which the street is scanned.
#pragma once

#include <cstdint>
#include <string_view>
#include <vector>

#include "citymesh/core/mesh.h"
#include "citymesh/core/time.h"

namespace citymesh {

enum class ObjectClass : std::uint8_t {
  ground, building, pole, tree, parked_car, pedestrian, moving_car, market_stall, kiosk, wall, planter
};
[[nodiscard]] std::string_view object_class_name(ObjectClass c);

/// A rigid object of the scene: triangles in the scene's local frame (metres; x along the
/// street, y across, z up, road surface at z = 0), present during [appear, disappear).
struct SceneObject {
  std::uint32_t id = 0;
  ObjectClass type = ObjectClass::ground;
  TimePoint appear = TimePoint::min();
  TimePoint disappear = TimePoint::max();
  std::vector<Vec3f> vertices;
  std::vector<Triangle> triangles;

  [[nodiscard]] bool present_at(TimePoint t) const { return appear <= t && t < disappear; }
};

/// How the scanning vehicle drives in one epoch: resolution and viewpoint differ per epoch.
struct EpochDrive {
  TimePoint date{};
  float lane_offset = -2.5f;  ///< y of the sensor track, metres
  float speed = 5.0f;         ///< metres per second
  /// Small rigid registration error of the whole epoch (metres), applied to its output.
  Vec3f registration_error{};
};

struct Scene {
  Vec3d origin;  ///< where the local frame's (0, 0, 0) lies in the project CRS
  float length = 60.0f;
  float width = 20.0f;
  std::vector<SceneObject> objects;
  std::vector<EpochDrive> epochs;  ///< in date order
};

struct StreetParams {
  float length = 60.0f;  ///< metres of street scanned
  float width = 20.0f;   ///< facade to facade, metres
  std::uint64_t seed = 1;
  int epochs = 6;        ///< at least 6: the scripted changes need them
  TimePoint first_date = parse_iso8601("2026-01-05T10:00:00Z", "first_date");
  Vec3d origin{651000.0, 6860700.0, 35.0};  ///< Lambert-93, Paris 6th; z orthometric
};

/// Builds the default street: ground with road, curbs and sidewalks; facades of varying
/// heights and setbacks with recessed windows, doors and balconies; poles; trees; and the
/// scripted changes over the epochs (parked cars, a car seen twice a few days apart,
/// pedestrians, a moving car, a one-week market stall, a kiosk built mid-series, a wall
/// demolished mid-series, a planter that appears in the last epoch only).
/// Throws ConfigError when the parameters are out of range.
Scene make_street_scene(const StreetParams& params);

/// Day offsets of the epochs from the first date, for `count` epochs (count >= 6).
std::vector<int> epoch_days(int count);

}  // namespace citymesh
