#pragma once
// Command line of stereo_fusion_simulate: every setting with its default, and their usage text.

#include <cstdint>
#include <string>

#include "readers/DatasetReader.h"          // SgbmParams
#include "stereo_fusion/ros/BagSequence.h"  // BagTopics

namespace CLI {
class App;
}

namespace stereo_fusion::sim {

struct SimulateOptions {
  std::string preset = "room";
  std::string trajectory = "walkthrough";
  int frames = 100;
  bool frames_given = false;  ///< --frames was passed (else the building's walkthrough: one tour)
  int width_px = 640;
  int height_px = 480;
  double fx_px = 525.0;
  double fy_px = -1.0;  ///< < 0: same as fx
  double baseline_m = 0.1;
  std::string disparity = "sgbm";
  double noise_px = 0.3;
  double outlier_fraction = 0.01;
  double matcher_noise_px = 0.0;
  double mismatch_fraction = 0.0;
  int mismatch_views = 5;
  uint32_t seed = 0;
  double rate_hz = 10.0;
  std::string bag;  ///< also write the frames as a rosbag here (empty: no bag)
  /// disparity (matched) | pair (left/right raw images only) | rectified-pair (rectified images
  /// only)
  std::string bag_content = "disparity";
  /// The bag's /tf parent frame (the nodelet's world_frame; default BagTopics', REP 105's map).
  std::string bag_world_frame = BagTopics{}.world_frame;
  bool bag_world_frame_given = false;
  /// A fleet robot's bag (--bag-robot): topics under /<name>, frames <name>/map and
  /// <name>/left_optical, so several robots' bags play through one player (empty: none).
  std::string bag_robot;
  double gt_max_edge_m = 0.03;
  double revolutions = 1.0;
  std::string dynamic = "none";
  double drift_yaw_deg = 0.0;  ///< --drift: odometry yaw error at the last frame
  double drift_m = 0.0;        ///< --drift: odometry position error at the last frame
  int keyframe_every = 5;
  SgbmParams sgbm;
  std::string out;
};

/// Adds the simulator's options and usage text to `app`, parsed into `options` (which must
/// outlive the parse). Values out of range, unknown names and a missing --out end the parse with
/// a CLI11 error (exit code 2).
void addSimulateArguments(CLI::App* app, SimulateOptions* options);

}  // namespace stereo_fusion::sim
