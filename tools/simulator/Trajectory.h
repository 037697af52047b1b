#pragma once
// Camera trajectories for the simulator: T_world_camera of the left optical frame per frame,
// with timestamps. Deterministic given the seed.

#include <Eigen/Geometry>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "simulator/SceneLibrary.h"

namespace stereo_fusion::sim {

/// One camera pose with its timestamp.
struct TimedPose {
  double timestamp_s = 0.0;
  Eigen::Isometry3d T_world_camera = Eigen::Isometry3d::Identity();
};

/// A circle around `centre_m` at horizontal `radius_m` and `height_m` above it, always looking
/// at the centre. The seed picks the start angle, the direction of travel and a gentle
/// (±10 %) breathing of radius and height, so different seeds give different views.
struct OrbitParams {
  Eigen::Vector3d centre_m = Eigen::Vector3d::Zero();
  double radius_m = 1.0;
  double height_m = 0.5;
  double revolutions = 1.0;  ///< turns over the whole sequence
};

/// A smooth closed loop around the middle of the room through waypoints drawn at eye height,
/// keeping at least `clearance_m` from every solid (walls, furniture), walked at constant speed
/// (looping again when the sequence is longer than the loop). The camera looks ahead along the
/// path but turned towards the middle of the room (so the view goes across the room, not along
/// a wall), with a slow side-to-side sweep and a slight downward tilt.
struct WalkthroughParams {
  Eigen::AlignedBox3d free_space_m;  ///< region the camera may use (e.g. the room interior)
  double clearance_m = 0.6;          ///< minimum distance to every solid along the path
  double min_height_m = 1.3;
  double max_height_m = 1.7;
  int waypoints = 7;
  double speed_mps = 0.5;            ///< walking speed along the path
  double inward_turn_rad = 0.6;      ///< look direction turned this much from ahead, inwards
  double sweep_amplitude_rad = 0.5;  ///< side-to-side look amplitude
  double sweep_period_s = 8.0;       ///< duration of one side-to-side look
  double heading_window_m = 0.5;     ///< "ahead" is the path direction averaged over ±this
  double pitch_down_rad = 0.3;
  int max_attempts = 500;  ///< waypoint sets tried before giving up
};

/// A walk along a preset's route (ScenePreset::route_m: a closed loop of camera positions through
/// rooms and doorways) at constant speed, on a smooth curve through the route's points (centripetal
/// Catmull–Rom: no cusps or overshoot where points are unevenly spaced), looping again when the
/// sequence is longer than the loop. The camera looks ahead along the path, swept side to side
/// (into the rooms along a corridor) and nodding slowly up and down (the floor and the ceiling).
struct TourParams {
  std::vector<Eigen::Vector3d> route_m;
  double clearance_m = 0.35;          ///< minimum distance to every solid along the curve
  double speed_mps = 1.0;             ///< walking speed along the path
  double sweep_amplitude_rad = 0.45;  ///< side-to-side look amplitude
  double sweep_period_s = 6.0;        ///< duration of one side-to-side look
  double heading_window_m = 1.0;      ///< "ahead" is the path direction averaged over ±this
                                      ///< (wide: the U-turns at a corridor's ends stay gentle)
  double pitch_down_rad = 0.2;        ///< mean downward tilt
  double nod_amplitude_rad = 0.35;    ///< up-and-down look amplitude: the floor and the ceiling
                                      ///< come within ~1.6 m of the camera
  double nod_period_s = 7.0;
};

/// `frames` poses of an orbit, timestamps k / rate_hz.
std::vector<TimedPose> makeOrbit(const OrbitParams& params, int frames, double rate_hz,
                                 uint32_t seed);

/// `frames` poses of a walkthrough of `scene`, timestamps k / rate_hz. std::nullopt with a
/// reason when no waypoint set keeps the clearance (room too cluttered or too small).
std::optional<std::vector<TimedPose>> makeWalkthrough(const AnalyticScene& scene,
                                                      const WalkthroughParams& params, int frames,
                                                      double rate_hz, uint32_t seed,
                                                      std::string* error);

/// `frames` poses of a tour of `scene` along `params.route_m`, timestamps k / rate_hz. The seed
/// picks the phases of the sweep and the nod. std::nullopt with a reason when the route has fewer
/// than 3 points or its curve comes nearer than the clearance to a solid.
std::optional<std::vector<TimedPose>> makeTour(const AnalyticScene& scene, const TourParams& params,
                                               int frames, double rate_hz, uint32_t seed,
                                               std::string* error);

/// Length in metres of the closed curve a tour follows through `route_m` (0 for fewer than 3
/// points).
double tourLengthM(const std::vector<Eigen::Vector3d>& route_m);

/// Frames of one whole lap of `preset`'s route at the walkthrough's default speed and `rate_hz`:
/// the last frame is less than one step before the first. 0 when the preset has no route.
int fullTourFrames(const ScenePreset& preset, double rate_hz);

/// Names accepted by makeTrajectory().
std::vector<std::string> trajectoryNames();

/// Trajectory `name` ("orbit" or "walkthrough") with the preset's defaults (orbit around its
/// focus, `revolutions` times; walkthrough of its room, or a tour along its route when it has one:
/// the building). std::nullopt with a reason on failure.
std::optional<std::vector<TimedPose>> makeTrajectory(const std::string& name,
                                                     const ScenePreset& preset, int frames,
                                                     double rate_hz, uint32_t seed,
                                                     std::string* error, double revolutions = 1.0);

/// `truth` as drifting odometry reports it: pose k becomes D(k) · T_k, where D grows linearly from
/// the identity at the first pose to, at the last, `yaw_deg` of rotation about the vertical (z)
/// through the first camera and an offset of `metres` along (2, 1, 0)/√5.
std::vector<TimedPose> addOdometryDrift(const std::vector<TimedPose>& truth, double yaw_deg,
                                        double metres);

}  // namespace stereo_fusion::sim
