#include "simulator/SceneLibrary.h"

#include <algorithm>
#include <cmath>
#include <random>

namespace stereo_fusion::sim {

namespace {

/// Seeded draws. std::uniform_real_distribution is avoided on purpose: its output is
/// implementation-defined, while this mapping of mt19937's 32-bit words is not, so a seed
/// gives the same scene with any standard library.
class Draw {
 public:
  explicit Draw(uint32_t seed) : rng_(seed) {}
  double uniform(double lo, double hi) { return lo + (hi - lo) * (rng_() / 4294967296.0); }
  int integer(int lo, int hi_inclusive) {
    return lo + static_cast<int>(rng_() % static_cast<uint32_t>(hi_inclusive - lo + 1));
  }
  /// `rgb` with every channel shifted by up to ±`jitter`.
  Eigen::Vector3d color(const Eigen::Vector3d& rgb, double jitter = 20.0) {
    Eigen::Vector3d c;
    for (int k = 0; k < 3; ++k) c[k] = std::clamp(rgb[k] + uniform(-jitter, jitter), 40.0, 235.0);
    return c;
  }

 private:
  std::mt19937 rng_;
};

Eigen::Isometry3d at(const Eigen::Vector3d& t, double yaw_rad = 0.0) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  T.translation() = t;
  return T;
}

/// Adds the room shell: interior [-hx, hx] × [-hy, hy] × [0, height] (floor at z = 0).
Eigen::AlignedBox3d addRoom(AnalyticScene* scene, double hx, double hy, double height,
                            const Eigen::Vector3d& rgb) {
  scene->add(makeRoom(at({0, 0, height / 2}), {hx, hy, height / 2}), rgb);
  return Eigen::AlignedBox3d(Eigen::Vector3d(-hx, -hy, 0), Eigen::Vector3d(hx, hy, height));
}

/// A table: box top whose upper surface is at `top_z`, on four cylinder legs inset from the
/// corners.
void addTable(AnalyticScene* scene, const Eigen::Vector2d& centre_xy, double yaw_rad,
              const Eigen::Vector2d& half_top_m, double top_z, double leg_radius_m,
              const Eigen::Vector3d& top_rgb, const Eigen::Vector3d& leg_rgb) {
  constexpr double kTopHalfThickness = 0.02;
  const Eigen::Isometry3d T_world_table = at({centre_xy.x(), centre_xy.y(), 0.0}, yaw_rad);
  scene->add(makeBox(T_world_table * at({0, 0, top_z - kTopHalfThickness}),
                     {half_top_m.x(), half_top_m.y(), kTopHalfThickness}),
             top_rgb);
  const double leg_half_height = (top_z - 2 * kTopHalfThickness) / 2;
  const double inset = leg_radius_m + 0.04;
  for (const double sx : {-1.0, 1.0})
    for (const double sy : {-1.0, 1.0})
      scene->add(makeCylinder(T_world_table * at({sx * (half_top_m.x() - inset),
                                                  sy * (half_top_m.y() - inset), leg_half_height}),
                              leg_radius_m, leg_half_height),
                 leg_rgb);
}

}  // namespace

std::vector<std::string> presetNames() {
  return {"room", "tabletop", "hall", "building", "building_long"};
}

std::optional<ScenePreset> makePreset(const std::string& name, uint32_t seed) {
  if (name == "room") return makeRoomPreset(seed);
  if (name == "tabletop") return makeTabletopPreset(seed);
  if (name == "hall") return makeHallPreset(seed);
  if (name == "building") return makeBuildingPreset(seed);
  if (name == "building_long") return makeBuildingPreset(seed, kLongBuildingColumns);
  return std::nullopt;
}

ScenePreset makeRoomPreset(uint32_t seed) {
  Draw draw(seed);
  ScenePreset preset;
  preset.name = "room";
  AnalyticScene& scene = preset.scene;
  constexpr double kHx = 2.5, kHy = 1.5, kHeight = 2.6;
  preset.room_interior = addRoom(&scene, kHx, kHy, kHeight, draw.color({215, 205, 185}, 15));

  // A thin rug gives the floor a second colour and a small step edge.
  scene.add(makeBox(at({draw.uniform(-0.4, 0.4), draw.uniform(-0.3, 0.1), 0.005},
                       draw.uniform(-0.2, 0.2)),
                    {draw.uniform(0.9, 1.2), draw.uniform(0.5, 0.7), 0.005}),
            draw.color({150, 60, 55}));

  // Sofa against the +y wall: seat and backrest.
  const double sofa_x = draw.uniform(-1.0, 0.0);
  const Eigen::Vector3d sofa_rgb = draw.color({90, 110, 150});
  scene.add(makeBox(at({sofa_x, kHy - 0.45, 0.22}), {0.9, 0.45, 0.22}), sofa_rgb);
  scene.add(makeBox(at({sofa_x, kHy - 0.1, 0.45}), {0.9, 0.1, 0.45}), sofa_rgb * 0.85);

  // Low table in front of the sofa, a ring lying on it.
  const Eigen::Vector2d table_xy(sofa_x + draw.uniform(-0.2, 0.2), kHy - 1.25);
  const double table_top_z = 0.45;
  addTable(&scene, table_xy, draw.uniform(-0.15, 0.15), {0.5, 0.3}, table_top_z, 0.025,
           draw.color({165, 115, 75}), draw.color({90, 70, 55}));
  scene.add(makeTorus(at({table_xy.x() + draw.uniform(-0.25, 0.25),
                          table_xy.y() + draw.uniform(-0.1, 0.1), table_top_z + 0.03}),
                      0.1, 0.03),
            draw.color({200, 170, 60}));

  // Cabinet against the +x wall with a ball on it.
  const double cabinet_y = draw.uniform(-0.6, 0.6);
  scene.add(makeBox(at({kHx - 0.25, cabinet_y, 0.55}), {0.25, 0.4, 0.55}),
            draw.color({120, 140, 110}));
  const double small_ball_r = draw.uniform(0.08, 0.13);
  scene.add(makeSphere({kHx - 0.25, cabinet_y + draw.uniform(-0.2, 0.2), 1.1 + small_ball_r},
                       small_ball_r),
            draw.color({190, 80, 160}));

  // Bookshelf against the -x wall.
  scene.add(makeBox(at({-kHx + 0.2, draw.uniform(-0.2, 0.7), 0.9}), {0.2, 0.5, 0.9}),
            draw.color({140, 100, 70}));

  // Floor-to-ceiling column near the (-x, -y) corner.
  scene.add(
      makeCylinder(at({-kHx + draw.uniform(0.45, 0.7), -kHy + draw.uniform(0.4, 0.6), kHeight / 2}),
                   0.15, kHeight / 2),
      draw.color({200, 200, 205}));

  // Ball on the floor near the -y wall, and a stool (cylinder) beside it.
  const double ball_r = draw.uniform(0.15, 0.22);
  scene.add(makeSphere({draw.uniform(0.3, 1.5), -kHy + 0.35, ball_r}, ball_r),
            draw.color({210, 90, 60}));
  scene.add(makeCylinder(at({draw.uniform(-1.2, -0.2), -kHy + 0.3, 0.23}), 0.18, 0.23),
            draw.color({70, 150, 140}));

  // Orbits look across the room's middle at the furniture and walls beyond.
  preset.focus_m = Eigen::Vector3d(0, 0, 0.9);
  preset.orbit_radius_m = 0.9;
  preset.orbit_height_m = 0.5;
  return preset;
}

ScenePreset makeTabletopPreset(uint32_t seed) {
  Draw draw(seed);
  ScenePreset preset;
  preset.name = "tabletop";
  AnalyticScene& scene = preset.scene;
  preset.room_interior = addRoom(&scene, 3.0, 3.0, 3.0, draw.color({210, 205, 195}, 15));

  constexpr double kTopZ = 0.75;
  const Eigen::Vector2d half_top(0.6, 0.4);
  addTable(&scene, {0, 0}, 0.0, half_top, kTopZ, 0.03, draw.color({165, 115, 75}),
           draw.color({80, 60, 45}));

  // Objects: one torus, one each of sphere, box, cylinder, then 0–2 more of those three.
  enum Kind { kTorus, kSphere, kBox, kCylinder };
  std::vector<Kind> kinds = {kTorus, kSphere, kBox, kCylinder};
  const int extra = draw.integer(0, 2);
  for (int i = 0; i < extra; ++i) kinds.push_back(static_cast<Kind>(draw.integer(1, 3)));
  const std::vector<Eigen::Vector3d> palette = {{200, 60, 50},  {60, 170, 70},  {60, 90, 200},
                                                {220, 190, 50}, {230, 130, 40}, {150, 70, 190}};

  // Rejection sampling of footprints (circles) inside the top, away from its edge.
  std::vector<Eigen::Vector3d> placed;  // x, y, footprint radius
  for (size_t i = 0; i < kinds.size(); ++i) {
    const Kind kind = kinds[i];
    double footprint = 0, a = 0, b = 0, c = 0;
    switch (kind) {
      case kTorus:
        a = draw.uniform(0.08, 0.11);
        b = draw.uniform(0.02, 0.035);
        footprint = a + b;
        break;
      case kSphere:
        a = draw.uniform(0.05, 0.1);
        footprint = a;
        break;
      case kBox:
        a = draw.uniform(0.04, 0.09);
        b = draw.uniform(0.04, 0.09);
        c = draw.uniform(0.04, 0.1);
        footprint = std::hypot(a, b);
        break;
      case kCylinder:
        a = draw.uniform(0.03, 0.07);
        b = draw.uniform(0.05, 0.12);
        footprint = a;
        break;
    }
    const double yaw = draw.uniform(-M_PI, M_PI);
    bool ok = false;
    Eigen::Vector2d xy;
    for (int attempt = 0; attempt < 200 && !ok; ++attempt) {
      xy = {draw.uniform(-half_top.x() + footprint + 0.03, half_top.x() - footprint - 0.03),
            draw.uniform(-half_top.y() + footprint + 0.03, half_top.y() - footprint - 0.03)};
      ok = std::all_of(placed.begin(), placed.end(), [&](const Eigen::Vector3d& o) {
        return (xy - o.head<2>()).norm() > footprint + o.z() + 0.03;
      });
    }
    if (!ok) continue;  // the top is full: fewer objects rather than overlapping ones
    placed.emplace_back(xy.x(), xy.y(), footprint);
    const Eigen::Vector3d rgb = draw.color(palette[i % palette.size()]);
    switch (kind) {
      case kTorus: scene.add(makeTorus(at({xy.x(), xy.y(), kTopZ + b}, yaw), a, b), rgb); break;
      case kSphere: scene.add(makeSphere({xy.x(), xy.y(), kTopZ + a}, a), rgb); break;
      case kBox: scene.add(makeBox(at({xy.x(), xy.y(), kTopZ + c}, yaw), {a, b, c}), rgb); break;
      case kCylinder:
        scene.add(makeCylinder(at({xy.x(), xy.y(), kTopZ + b}, yaw), a, b), rgb);
        break;
    }
  }

  preset.focus_m = Eigen::Vector3d(0, 0, kTopZ + 0.05);
  preset.orbit_radius_m = 1.1;
  preset.orbit_height_m = 0.6;
  return preset;
}

ScenePreset makeHallPreset(uint32_t seed) {
  Draw draw(seed);
  ScenePreset preset;
  preset.name = "hall";
  AnalyticScene& scene = preset.scene;
  // 6 × 6 m (± 0.5 m by seed) and 2.6 m high: from near the middle, walls are 3–4.5 m away.
  const double hx = draw.uniform(2.75, 3.25), hy = draw.uniform(2.75, 3.25), height = 2.6;
  preset.room_interior = addRoom(&scene, hx, hy, height, draw.color({205, 200, 190}, 20));

  // Furniture against the walls only, so what the camera sees is mostly far: shelves and
  // cabinets (boxes), a column in a corner, a table with a ball on it, a crate on the floor.
  for (int wall = 0; wall < 4; ++wall) {
    const bool along_x = wall % 2 == 0;
    const double sign = wall < 2 ? 1.0 : -1.0;
    const double half_len = along_x ? hx : hy;
    const int pieces = draw.integer(1, 2);
    for (int p = 0; p < pieces; ++p) {
      const double centre = draw.uniform(-half_len + 0.8, half_len - 0.8);
      const double depth = draw.uniform(0.2, 0.45), width = draw.uniform(0.3, 0.7),
                   tall = draw.uniform(0.4, 1.0);
      const Eigen::Vector3d at_wall = along_x ? Eigen::Vector3d(centre, sign * (hy - depth), tall)
                                              : Eigen::Vector3d(sign * (hx - depth), centre, tall);
      const Eigen::Vector3d half =
          along_x ? Eigen::Vector3d(width, depth, tall) : Eigen::Vector3d(depth, width, tall);
      scene.add(makeBox(at(at_wall), half), draw.color({130, 110, 90}, 40));
    }
  }
  const double column_r = draw.uniform(0.15, 0.25);
  scene.add(makeCylinder(at({-hx + 0.6, hy - 0.6, height / 2}), column_r, height / 2),
            draw.color({200, 200, 205}));
  const Eigen::Vector2d table_xy(draw.uniform(0.5, hx - 1.2), -hy + 1.0);
  addTable(&scene, table_xy, draw.uniform(-0.3, 0.3), {0.6, 0.4}, 0.75, 0.03,
           draw.color({165, 115, 75}), draw.color({80, 60, 45}));
  const double ball_r = draw.uniform(0.1, 0.18);
  scene.add(makeSphere({table_xy.x(), table_xy.y(), 0.75 + ball_r}, ball_r),
            draw.color({60, 90, 200}));
  scene.add(makeBox(at({-hx + 1.2, -hy + 1.0, 0.25}, draw.uniform(-0.5, 0.5)), {0.3, 0.3, 0.25}),
            draw.color({180, 150, 60}));

  // A small orbit near the middle looking out level: the floor enters the view only beyond
  // ~3 m (camera 1.4 m up, 22.6° half vertical field of view at f = 576 px, 480 rows).
  preset.focus_m = Eigen::Vector3d(0, 0, 1.3);
  preset.orbit_radius_m = 0.6;
  preset.orbit_height_m = 0.1;
  return preset;
}

ScenePreset makeBuildingPreset(uint32_t seed, int columns) {
  Draw draw(seed);
  ScenePreset preset;
  preset.name = columns == kBuildingColumns ? "building" : "building_long";
  AnalyticScene& scene = preset.scene;
  // Plan (floor at z = 0): the corridor runs along x over [0, length] × [-kCorridorHalf,
  // kCorridorHalf]; four columns of rooms cross it, a room on each side (north: +y, south: -y);
  // every wall is a solid box kWall thick, so rooms, doorways and corridor are one free space.
  constexpr double kWall = 0.1, kHeight = 2.4, kCorridorHalf = 1.0;
  constexpr double kDoorHalf = 0.6, kDoorHeight = 2.1;
  const int column_count = std::max(1, columns);
  std::vector<double> widths(column_count);
  for (double& w : widths) w = draw.uniform(3.8, 4.4);
  const double depth_north = draw.uniform(3.6, 4.4), depth_south = draw.uniform(3.6, 4.4);
  std::vector<double> column_x(column_count);  // west edge of each column's rooms
  double length = 0;
  for (int j = 0; j < column_count; ++j) {
    column_x[j] = length;
    length += widths[j] + (j + 1 < column_count ? kWall : 0.0);
  }
  const double north_back = kCorridorHalf + kWall + depth_north;
  const double south_back = -kCorridorHalf - kWall - depth_south;
  auto box = [&](const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, const Eigen::Vector3d& rgb) {
    scene.add(makeBox(at((lo + hi) / 2), (hi - lo) / 2), rgb);
  };

  // Floor and ceiling slabs over the whole plan; the two end walls.
  box({-kWall, south_back - kWall, -kWall}, {length + kWall, north_back + kWall, 0.0},
      draw.color({170, 150, 125}, 20));
  box({-kWall, south_back - kWall, kHeight}, {length + kWall, north_back + kWall, kHeight + kWall},
      draw.color({225, 225, 220}, 10));
  box({-kWall, south_back, 0}, {0, north_back, kHeight}, draw.color({200, 190, 170}, 25));
  box({length, south_back, 0}, {length + kWall, north_back, kHeight},
      draw.color({200, 190, 170}, 25));
  // The corridor's walls and the walls between columns, a colour per room.
  const std::vector<Eigen::Vector3d> wall_palette = {
      {215, 200, 170}, {175, 200, 215}, {200, 215, 180}, {220, 185, 185},
      {205, 195, 220}, {225, 210, 160}, {180, 215, 205}, {215, 190, 210}};

  struct Room {
    Eigen::Isometry3d T_world_room;  // origin at the floor's centre, +y away from the corridor
    double half_w, half_d, door_u;   // door_u: the doorway's centre along the room's x
  };
  std::vector<Room> rooms;  // the route's order: north west to east, then south east to west
  for (int side = 0; side < 2; ++side) {
    const double s = side == 0 ? 1.0 : -1.0;
    const double depth = side == 0 ? depth_north : depth_south;
    for (int k = 0; k < column_count; ++k) {
      const int j = side == 0 ? k : column_count - 1 - k;
      const double x0 = column_x[j], x1 = column_x[j] + widths[j];
      const double front = s * (kCorridorHalf + kWall), back = s * (kCorridorHalf + kWall + depth);
      const Eigen::Vector3d rgb = draw.color(wall_palette[rooms.size() % wall_palette.size()], 15);
      const double door_x = (x0 + x1) / 2 + draw.uniform(-0.3, 0.3);
      // Back wall; the wall to the next column east (the end walls close the last ones).
      const double y_lo = std::min(back, back + s * kWall), y_hi = std::max(back, back + s * kWall);
      box({x0 - kWall, y_lo, 0}, {x1 + kWall, y_hi, kHeight}, rgb);
      if (j + 1 < column_count)
        box({x1, std::min(s * kCorridorHalf, back), 0},
            {x1 + kWall, std::max(s * kCorridorHalf, back), kHeight}, rgb);
      // The corridor wall with the doorway: two jambs and a lintel.
      const double c_lo = std::min(s * kCorridorHalf, front),
                   c_hi = std::max(s * kCorridorHalf, front);
      box({x0, c_lo, 0}, {door_x - kDoorHalf, c_hi, kHeight}, rgb);
      box({door_x + kDoorHalf, c_lo, 0}, {x1, c_hi, kHeight}, rgb);
      box({door_x - kDoorHalf, c_lo, kDoorHeight}, {door_x + kDoorHalf, c_hi, kHeight}, rgb);
      // The room's frame: turned by 180° on the south side, so "forward" (+y) leads away from
      // the corridor and the furniture rule below is the same for every room.
      const Eigen::Vector3d centre((x0 + x1) / 2, (front + back) / 2, 0.0);
      const double yaw = side == 0 ? 0.0 : M_PI;
      rooms.push_back({at(centre, yaw), widths[j] / 2, depth / 2, s * (door_x - centre.x())});
      preset.rooms_m.emplace_back(Eigen::Vector3d(x0, std::min(front, back), 0),
                                  Eigen::Vector3d(x1, std::max(front, back), kHeight));
    }
  }

  // Furniture against the side and back walls, in the room's frame (u = x, v = y; the doorway
  // is in the wall v = -half_d), leaving |u| < hw - 0.65 and v < hd - 1.0 free for the tour.
  // Every draw is its own statement: the order of a call's arguments is unspecified, and the
  // scene must not depend on the compiler.
  for (const Room& room : rooms) {
    const double hw = room.half_w, hd = room.half_d;
    auto place = [&](double u, double v, double z, double yaw_rad = 0.0) {
      return room.T_world_room * at({u, v, z}, yaw_rad);
    };
    // A bed (or sofa) with a headboard against the back wall.
    const double bed_hu = draw.uniform(0.6, 0.9), bed_hv = draw.uniform(0.35, 0.5),
                 bed_hz = draw.uniform(0.2, 0.3);
    const double bed_u = draw.uniform(-hw + 0.7 + bed_hu, hw - 0.7 - bed_hu);
    const double head_hz = draw.uniform(0.4, 0.55);
    const Eigen::Vector3d bed_rgb = draw.color({100, 120, 160}, 40);
    scene.add(makeBox(place(bed_u, hd - bed_hv, bed_hz), {bed_hu, bed_hv, bed_hz}), bed_rgb);
    scene.add(makeBox(place(bed_u, hd - 0.05, head_hz), {bed_hu, 0.05, head_hz}), bed_rgb * 0.8);
    // A cabinet against one side wall, a table with a ball on it against the other.
    const double side = draw.uniform(0, 1) < 0.5 ? -1.0 : 1.0;
    const double cab_hu = draw.uniform(0.2, 0.25), cab_hv = draw.uniform(0.3, 0.6),
                 cab_hz = draw.uniform(0.4, 0.9), cab_v = draw.uniform(-0.3, 0.6);
    const Eigen::Vector3d cab_rgb = draw.color({130, 100, 75}, 35);
    scene.add(makeBox(place(side * (hw - cab_hu), cab_v, cab_hz), {cab_hu, cab_hv, cab_hz}),
              cab_rgb);
    const double table_v = draw.uniform(-0.3, 0.4), table_top = draw.uniform(0.72, 0.78);
    const Eigen::Vector3d top_rgb = draw.color({165, 115, 75}), leg_rgb = draw.color({80, 60, 45});
    const Eigen::Isometry3d T_table = place(-side * (hw - 0.4), table_v, 0.0, M_PI / 2);
    addTable(&scene, T_table.translation().head<2>(), std::atan2(T_table(1, 0), T_table(0, 0)),
             {0.45, 0.25}, table_top, 0.025, top_rgb, leg_rgb);
    const double ball_r = draw.uniform(0.08, 0.14), ball_v = table_v + draw.uniform(-0.2, 0.2);
    const Eigen::Vector3d ball_rgb = draw.color({200, 80, 70}, 50);
    scene.add(
        makeSphere(place(-side * (hw - 0.4), ball_v, table_top + ball_r).translation(), ball_r),
        ball_rgb);
    // A crate in a front corner, beside the doorway.
    const double crate = draw.uniform(0.18, 0.28), crate_yaw = draw.uniform(-0.4, 0.4);
    const Eigen::Vector3d crate_rgb = draw.color({180, 150, 60}, 30);
    scene.add(
        makeBox(place(side * (hw - 0.35), -hd + 0.35, crate, crate_yaw), {crate, crate, crate}),
        crate_rgb);
    // A wardrobe in the back corner on the cabinet's side.
    const double wardrobe_hz = draw.uniform(0.85, 1.0);
    const Eigen::Vector3d wardrobe_rgb = draw.color({150, 130, 110}, 35);
    scene.add(makeBox(place(side * (hw - 0.32), hd - 0.32, wardrobe_hz), {0.3, 0.3, wardrobe_hz}),
              wardrobe_rgb);
  }

  // The tour: in each room a loop from the doorway round the free middle and back (a teardrop:
  // doorway, left, back, right, doorway); along the corridor in lanes 0.45 m either side of its
  // axis, east on the north side, west on the south side. It starts at the back of the first
  // room, so the loop closes there after entering it again.
  constexpr double kLane = 0.45, kApproach = 0.8;
  auto eye = [&] { return draw.uniform(1.4, 1.6); };
  auto in_room = [&](const Room& r, double u, double v) {
    return r.T_world_room * Eigen::Vector3d(u, v, eye());
  };
  auto doorway = [&](const Room& r) { return in_room(r, r.door_u, -r.half_d - kWall / 2); };
  // Corridor points before and after a doorway, on the side's lane, in the direction of travel.
  auto lane_point = [&](const Room& r, double along) {
    return in_room(r, r.door_u + along, -r.half_d - kWall - kCorridorHalf + kLane);
  };
  std::vector<Eigen::Vector3d>& route = preset.route_m;
  const Room& first = rooms.front();
  route.push_back(in_room(first, 0.0, 0.75));
  route.push_back(in_room(first, 0.65, 0.0));
  route.push_back(doorway(first));
  route.push_back(lane_point(first, kApproach));
  for (size_t i = 1; i < rooms.size(); ++i) {
    const Room& r = rooms[i];
    if (i == static_cast<size_t>(column_count))  // the east end: across the corridor
      route.emplace_back(length - 0.5, 0.0, eye());
    route.push_back(lane_point(r, -kApproach));
    route.push_back(doorway(r));
    route.push_back(in_room(r, -0.65, 0.0));
    route.push_back(in_room(r, 0.0, 0.75));
    route.push_back(in_room(r, 0.65, 0.0));
    route.push_back(doorway(r));
    route.push_back(lane_point(r, kApproach));
  }
  route.emplace_back(0.5, 0.0, eye());  // the west end: across, back to the first room
  route.push_back(lane_point(first, -kApproach));
  route.push_back(doorway(first));
  route.push_back(in_room(first, -0.65, 0.0));

  preset.room_interior = Eigen::AlignedBox3d(Eigen::Vector3d(0, south_back, 0),
                                             Eigen::Vector3d(length, north_back, kHeight));
  // Orbits circle the first room's free middle.
  preset.focus_m = first.T_world_room * Eigen::Vector3d(0, 0.1, 0.9);
  preset.orbit_radius_m = 0.55;
  preset.orbit_height_m = 0.6;
  return preset;
}

}  // namespace stereo_fusion::sim
