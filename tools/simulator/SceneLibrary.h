#pragma once
// Preset scenes for the stereo sequence simulator: a furnished room, a tabletop, a far-range hall
// and a building of rooms along a corridor, built from analytic primitives so that depth,
// disparity and the ground-truth mesh are exact.

#include <Eigen/Geometry>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "simulator/AnalyticScene.h"

namespace stereo_fusion::sim {

/// A scene plus what trajectories need to know about it.
struct ScenePreset {
  std::string name;
  AnalyticScene scene;
  /// Free interior of the room (world frame, metres); cameras must stay inside it.
  Eigen::AlignedBox3d room_interior;
  /// Point of interest that orbits circle and look at (room centre near the floor, or the
  /// middle of the table top).
  Eigen::Vector3d focus_m = Eigen::Vector3d::Zero();
  /// Orbit radius (horizontal, metres) and height above `focus_m` that frame the scene well
  /// and keep clear of every object.
  double orbit_radius_m = 1.0;
  double orbit_height_m = 0.5;
  /// A closed loop of camera positions through the scene (the walkthrough follows it; empty: the
  /// walkthrough draws its own loop inside `room_interior`). The building's tour.
  std::vector<Eigen::Vector3d> route_m;
  /// The interior of each room (floor to ceiling) when the scene has several, in the order the
  /// route first enters them; empty for the one-room presets.
  std::vector<Eigen::AlignedBox3d> rooms_m;
};

/// Names accepted by makePreset().
std::vector<std::string> presetNames();

/// Builds preset `name` ("room", "tabletop", "hall", "building" or "building_long"); the seed
/// varies object placement, sizes and colours (same seed, same scene). Returns std::nullopt for an
/// unknown name.
std::optional<ScenePreset> makePreset(const std::string& name, uint32_t seed);

/// The inside of a ~5 × 3 × 2.6 m room (floor at z = 0, centred on the origin in x and y)
/// with furniture along the walls: a sofa-like pair of boxes, a cabinet, a low table on
/// cylinder legs, a column, a ball on the floor and a ring on the table, leaving the middle free.
ScenePreset makeRoomPreset(uint32_t seed);

/// A table (box top on four cylinder legs) in the middle of a 6 × 6 × 3 m room with 4–6 objects
/// on it (spheres, boxes, cylinders, a torus), placed without overlapping.
ScenePreset makeTabletopPreset(uint32_t seed);

/// The far-range class: a ~6 × 6 × 2.6 m hall with sparse furniture against its walls, orbited
/// from near its middle, so most surfaces are 3–4.5 m from the camera (where stereo is coarse
/// and the truncation band is wide). Seeds vary the hall's size and the furniture.
ScenePreset makeHallPreset(uint32_t seed);

/// The large-map class (benches of the memory cap and paging): eight furnished rooms, four on each
/// side of a 2 m wide corridor, each entered through a 1.2 m wide, 2.1 m high doorway, under one
/// 2.4 m ceiling; every wall is a 10 cm solid box. Rooms are 3.8–4.4 m wide and 3.6–4.4 m deep
/// (by seed), with a bed and its headboard against the back wall, a cabinet and a wardrobe on one
/// side, a table with a ball on it on the other and a crate beside the doorway, the middle kept
/// free. `route_m` is the tour: from the back of the first room (`rooms_m[0]`) out into the
/// corridor, into and around each room on the way east, across, back west into and around each
/// room on the other side, and into the first room again to end where it started. Seeds vary the
/// room sizes, doorway positions, furniture and colours. `columns` rooms on each side:
/// kBuildingColumns for "building", kLongBuildingColumns for "building_long" (the same class at
/// twice the length, so its uncapped map at 1 cm is ten times a cap that holds a frame's reach).
constexpr int kBuildingColumns = 4;
constexpr int kLongBuildingColumns = 8;
ScenePreset makeBuildingPreset(uint32_t seed, int columns = kBuildingColumns);

}  // namespace stereo_fusion::sim
