// SPDX-License-Identifier: MIT
// The default procedural street and its scripted changes over the epochs.
#include <fmt/format.h>

#include "citymesh/core/error.h"
#include "citymesh/sim/scene.h"
#include "rng.h"
#include "shapes.h"

namespace citymesh {

namespace {

using std::chrono::days;
using sim::add_blob;
using sim::add_box;
using sim::add_car;
using sim::add_quad;

constexpr float kRoadHalfWidth = 5.0f, kCurb = 0.15f, kFloor = 3.0f, kBay = 3.0f;

class StreetBuilder {
 public:
  StreetBuilder(const StreetParams& p) : p_(p), rng_(p.seed) {
    scene_.origin = p.origin;
    scene_.length = p.length;
    scene_.width = p.width;
    for (int d : epoch_days(p.epochs)) date_.push_back(p.first_date + days(d));
  }

  Scene build() {
    add_drives();
    add_ground();
    for (float side : {-1.0f, 1.0f}) add_facades(side);
    add_street_furniture();
    add_scripted_changes();
    return std::move(scene_);
  }

 private:
  SceneObject& object(ObjectClass type, TimePoint appear = TimePoint::min(), TimePoint disappear = TimePoint::max()) {
    SceneObject o;
    o.id = static_cast<std::uint32_t>(scene_.objects.size() + 1);
    o.type = type;
    o.appear = appear;
    o.disappear = disappear;
    scene_.objects.push_back(std::move(o));
    return scene_.objects.back();
  }

  void add_drives() {
    for (std::size_t k = 0; k < date_.size(); ++k) {
      EpochDrive d;
      d.date = date_[k];
      d.lane_offset = rng_.uniform(-3.5f, -1.5f);
      d.speed = rng_.uniform(4.5f, 7.0f);
      d.registration_error = {rng_.uniform(-0.01f, 0.01f), rng_.uniform(-0.01f, 0.01f), rng_.uniform(-0.01f, 0.01f)};
      scene_.epochs.push_back(d);
    }
  }

  void add_ground() {
    SceneObject& g = object(ObjectClass::ground);
    const float x0 = -15.0f, x1 = p_.length + 15.0f, edge = p_.width / 2 + 1.5f;
    for (float x = x0; x < x1; x += 5.0f) {  // 5 m strips keep triangles reasonably shaped
      const float xe = std::min(x + 5.0f, x1);
      add_quad(g, {x, -kRoadHalfWidth, 0}, {xe, -kRoadHalfWidth, 0}, {xe, kRoadHalfWidth, 0}, {x, kRoadHalfWidth, 0});
      for (float s : {-1.0f, 1.0f}) {
        const float yc = s * kRoadHalfWidth, yo = s * edge;
        // curb face, then sidewalk top (ordered so both face up/towards the road)
        if (s > 0) {
          add_quad(g, {x, yc, 0}, {xe, yc, 0}, {xe, yc, kCurb}, {x, yc, kCurb});
          add_quad(g, {x, yc, kCurb}, {xe, yc, kCurb}, {xe, yo, kCurb}, {x, yo, kCurb});
        } else {
          add_quad(g, {xe, yc, 0}, {x, yc, 0}, {x, yc, kCurb}, {xe, yc, kCurb});
          add_quad(g, {x, yo, kCurb}, {xe, yo, kCurb}, {xe, yc, kCurb}, {x, yc, kCurb});
        }
      }
    }
  }

  /// One facade cell [x, x + kBay] x [z, z + kFloor] at y = face, recessed opening or wall.
  void add_cell(SceneObject& b, float side, float face, float x, float z, bool opening, bool door) {
    const float ox0 = x + 0.8f, ox1 = x + kBay - 0.8f;
    const float oz0 = door ? z + kCurb : z + 0.9f, oz1 = door ? z + 2.4f : z + 2.4f;
    const float depth = door ? 0.4f : 0.25f, back = face + side * depth;
    auto quad = [&](float xa, float za, float xb, float zb, float y) {  // faces the street
      if (side > 0) add_quad(b, {xb, y, za}, {xa, y, za}, {xa, y, zb}, {xb, y, zb});
      else add_quad(b, {xa, y, za}, {xb, y, za}, {xb, y, zb}, {xa, y, zb});
    };
    if (!opening) {
      quad(x, z, x + kBay, z + kFloor, face);
      return;
    }
    quad(x, z, ox0, z + kFloor, face);          // left strip
    quad(ox1, z, x + kBay, z + kFloor, face);   // right strip
    quad(ox0, z, ox1, oz0, face);               // below the opening
    quad(ox0, oz1, ox1, z + kFloor, face);      // above
    quad(ox0, oz0, ox1, oz1, back);             // glass or door at the back of the recess
    // reveals: the four sides of the recess
    add_quad(b, {ox0, face, oz0}, {ox0, back, oz0}, {ox0, back, oz1}, {ox0, face, oz1});
    add_quad(b, {ox1, back, oz0}, {ox1, face, oz0}, {ox1, face, oz1}, {ox1, back, oz1});
    add_quad(b, {ox0, back, oz0}, {ox0, face, oz0}, {ox1, face, oz0}, {ox1, back, oz0});
    add_quad(b, {ox0, face, oz1}, {ox0, back, oz1}, {ox1, back, oz1}, {ox1, face, oz1});
  }

  void add_facades(float side) {
    float x = -15.0f;
    while (x < p_.length + 15.0f) {
      const int bays = rng_.integer(3, 6);
      const int floors = rng_.integer(3, 8);
      const float setback = rng_.uniform(0.0f, 1.0f);
      const float face = side * (p_.width / 2 + 1.5f + setback), top = static_cast<float>(floors) * kFloor;
      SceneObject& b = object(ObjectClass::building);
      const int door_bay = rng_.integer(0, bays - 1);
      for (int f = 0; f < floors; ++f) {
        for (int bay = 0; bay < bays; ++bay) {
          const bool door = f == 0 && bay == door_bay;
          const bool opening = door || (f > 0 && rng_.unit() < 0.8);
          add_cell(b, side, face, x + static_cast<float>(bay) * kBay, kCurb + static_cast<float>(f) * kFloor, opening, door);
        }
        if (f > 0 && rng_.unit() < 0.3) {  // a balcony slab across two bays
          const float bx = x + kBay * static_cast<float>(rng_.integer(0, std::max(0, bays - 2)));
          const float y0 = face, y1 = face - side * 1.0f;
          add_box(b, {bx + 0.2f, std::min(y0, y1), kCurb + static_cast<float>(f) * kFloor - 0.15f},
                  {bx + 2 * kBay - 0.2f, std::max(y0, y1), kCurb + static_cast<float>(f) * kFloor}, true);
        }
      }
      const float x1 = x + static_cast<float>(bays) * kBay, depth = side * 12.0f;
      // end walls, so that a setback step between blocks is closed, and the roof
      add_quad(b, {x, face, kCurb}, {x, face + depth, kCurb}, {x, face + depth, top}, {x, face, top});
      add_quad(b, {x1, face + depth, kCurb}, {x1, face, kCurb}, {x1, face, top}, {x1, face + depth, top});
      add_quad(b, {x, face, top}, {x1, face, top}, {x1, face + depth, top}, {x, face + depth, top});
      x = x1;
    }
  }

  void add_street_furniture() {
    for (float x = 5.0f; x < p_.length; x += 15.0f) {
      for (float side : {-1.0f, 1.0f}) {
        const float y = side * (kRoadHalfWidth + 0.6f);
        add_box(object(ObjectClass::pole), {x - 0.08f, y - 0.08f, kCurb}, {x + 0.08f, y + 0.08f, 5.0f});
      }
    }
    for (float x = 12.0f; x < p_.length; x += 20.0f) {
      SceneObject& t = object(ObjectClass::tree);
      const float y = kRoadHalfWidth + 1.8f;
      add_box(t, {x - 0.15f, y - 0.15f, kCurb}, {x + 0.15f, y + 0.15f, 3.2f});
      add_blob(t, {x, y, 4.6f}, {1.8f, 1.6f, 1.5f});
    }
  }

  TimePoint epoch(std::size_t k) const { return date_[k]; }
  /// Present for the epochs [first, last] only (a day of margin around each).
  std::pair<TimePoint, TimePoint> during(std::size_t first, std::size_t last) const {
    return {epoch(first) - days(1), epoch(last) + days(1)};
  }

  struct ParkedCar {
    float x = 0, side = 1;
  };
  static constexpr float kCarLength = 4.2f;

  /// 2-3 cars per epoch, alternating sides. A car never takes a space used by a car of the
  /// previous, the next or the last epoch (nor by the car seen twice): two cars in one space
  /// with no scan in between showing it empty look like one permanent object to any method,
  /// which would make the ground truth ambiguous. A car that finds no free space is left out.
  std::vector<std::vector<ParkedCar>> parking_plan() {
    const std::size_t last = date_.size() - 1;
    std::vector<std::vector<ParkedCar>> plan(date_.size());
    plan[1].push_back({twice_seen_x(), -1.0f});
    plan[2].push_back({twice_seen_x(), -1.0f});
    const auto is_free = [&](std::size_t k, const ParkedCar& car) {
      for (std::size_t other : {k == 0 ? k : k - 1, k, std::min(k + 1, last), last}) {
        for (const ParkedCar& c : plan[other]) {
          if (c.side == car.side && std::abs(c.x - car.x) < kCarLength + 1.5f) return false;
        }
      }
      return true;
    };
    std::vector<std::size_t> order{last};
    for (std::size_t k = 0; k < last; ++k) order.push_back(k);
    std::vector<std::vector<ParkedCar>> chosen(date_.size());
    for (std::size_t k : order) {
      for (int c = 0, n = rng_.integer(2, 3); c < n; ++c) {
        for (int attempt = 0; attempt < 50; ++attempt) {
          const ParkedCar car{rng_.uniform(5, p_.length - 5), c % 2 == 0 ? 1.0f : -1.0f};
          if (!is_free(k, car)) continue;
          plan[k].push_back(car);
          chosen[k].push_back(car);
          break;
        }
      }
    }
    return chosen;
  }

  float twice_seen_x() const { return p_.length * 0.55f; }

  void add_scripted_changes() {
    const std::size_t last = date_.size() - 1;
    const float park = kRoadHalfWidth - 1.0f;  // parking lane, both sides
    const std::vector<std::vector<ParkedCar>> parked = parking_plan();
    for (std::size_t k = 0; k < date_.size(); ++k) {
      for (const ParkedCar& car : parked[k]) {  // cars parked in this epoch only
        auto [a, d] = during(k, k);
        add_car(object(ObjectClass::parked_car, a, d), car.x, car.side * park, kCarLength, 1.8f);
      }
      for (int c = 0; c < 3; ++c) {  // pedestrians on the sidewalks
        auto [a, d] = during(k, k);
        const float x = rng_.uniform(3, p_.length - 3), y = (c % 2 == 0 ? 1.0f : -1.0f) * rng_.uniform(6.0f, 8.5f);
        add_box(object(ObjectClass::pedestrian, a, d), {x - 0.25f, y - 0.2f, kCurb}, {x + 0.25f, y + 0.2f, kCurb + 1.75f});
      }
    }
    {  // a car seen in epochs 1 and 2, four days apart: not sustainable at Ts = 30 d
      auto [a, d] = during(1, 2);
      add_car(object(ObjectClass::parked_car, a, d), twice_seen_x(), -park, 4.5f, 1.9f);
    }
    {  // a car driving in the far lane during epoch 3
      auto [a, d] = during(3, 3);
      add_car(object(ObjectClass::moving_car, a, d), p_.length * 0.3f, 2.0f, 4.4f, 1.8f);
    }
    // a market stall for one week around epochs 1 and 2
    add_box(object(ObjectClass::market_stall, epoch(1) - days(2), epoch(1) + days(5)),
            {p_.length * 0.7f, kRoadHalfWidth + 1.0f, kCurb}, {p_.length * 0.7f + 3.0f, kRoadHalfWidth + 3.0f, 2.3f});
    // a kiosk built between epochs 2 and 3, then there for good
    add_box(object(ObjectClass::kiosk, epoch(2) + days(10)), {p_.length * 0.2f, -kRoadHalfWidth - 3.0f, kCurb},
            {p_.length * 0.2f + 2.2f, -kRoadHalfWidth - 1.0f, 2.8f});
    // a garden wall on the far sidewalk, demolished between epochs 3 and 4
    add_box(object(ObjectClass::wall, TimePoint::min(), epoch(3) + days(10)),
            {p_.length * 0.4f, kRoadHalfWidth + 2.6f, kCurb}, {p_.length * 0.4f + 7.0f, kRoadHalfWidth + 2.9f, 2.0f});
    // a planter that appears in the last epoch only
    add_box(object(ObjectClass::planter, epoch(last) - days(1)), {p_.length * 0.85f, -kRoadHalfWidth - 1.5f, kCurb},
            {p_.length * 0.85f + 1.2f, -kRoadHalfWidth - 0.6f, 0.9f});
  }

  const StreetParams& p_;
  sim::Rng rng_;
  Scene scene_;
  std::vector<TimePoint> date_;
};

}  // namespace

std::string_view object_class_name(ObjectClass c) {
  switch (c) {
    case ObjectClass::ground: return "ground";
    case ObjectClass::building: return "building";
    case ObjectClass::pole: return "pole";
    case ObjectClass::tree: return "tree";
    case ObjectClass::parked_car: return "parked_car";
    case ObjectClass::pedestrian: return "pedestrian";
    case ObjectClass::moving_car: return "moving_car";
    case ObjectClass::market_stall: return "market_stall";
    case ObjectClass::kiosk: return "kiosk";
    case ObjectClass::wall: return "wall";
    case ObjectClass::planter: return "planter";
  }
  return "?";
}

std::vector<int> epoch_days(int count) {
  std::vector<int> d{0, 30, 34, 70, 110, 150};
  while (static_cast<int>(d.size()) < count) d.push_back(d.back() + 30);
  d.resize(static_cast<std::size_t>(std::max(count, 0)));
  return d;
}

Scene make_street_scene(const StreetParams& params) {
  if (params.epochs < 6 || params.epochs > 100) {
    throw ConfigError(fmt::format("simulate: {} epochs; the scripted changes need 6 to 100", params.epochs));
  }
  if (!(params.length >= 30 && params.length <= 5000) || !(params.width >= 14 && params.width <= 60)) {
    throw ConfigError(fmt::format("simulate: street length {} m (30..5000) or width {} m (14..60) out of range",
                                  params.length, params.width));
  }
  return StreetBuilder(params).build();
}

}  // namespace citymesh
