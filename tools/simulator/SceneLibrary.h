#pragma once
// Preset scenes for the stereo sequence simulator: a furnished room and a tabletop, built from
// analytic primitives so that depth, disparity and the ground-truth mesh are exact.

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
};

/// Names accepted by makePreset().
std::vector<std::string> presetNames();

/// Builds preset `name` ("room", "tabletop" or "hall"); the seed varies object placement, sizes and
/// colours (same seed, same scene). Returns std::nullopt for an unknown name.
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

}  // namespace stereo_fusion::sim
