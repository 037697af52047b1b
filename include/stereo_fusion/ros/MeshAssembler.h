#pragma once
// The base station: one robot's ~mesh_update stream followed (the default), or a fleet's — N
// robots, each followed by its own RobotMeshAssembly in its own map frame, placed in one
// operator frame by tf — with the fleet costmap beside it.

#include <diagnostic_updater/diagnostic_updater.h>
#include <nodelet/nodelet.h>
#include <ros/ros.h>
#include <stereo_fusion/SaveMesh.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>

#include <memory>
#include <string>
#include <vector>

#include "stereo_fusion/ros/CallbackQueueHold.h"
#include "stereo_fusion/ros/FleetConfig.h"
#include "stereo_fusion/ros/FleetCostmap.h"
#include "stereo_fusion/ros/RobotMeshAssembly.h"

namespace stereo_fusion {

/// Nodelet `stereo_fusion/MeshAssembler` (standalone: `mesh_assembler_node`).
///
/// One robot (`~robots` empty, the default): in, topic `mesh_update` (remap to the robot's
/// `/stereo_fusion/mesh_update`) and service client `get_full_mesh` (remap to
/// `/stereo_fusion/get_full_mesh`); out, `~mesh_markers` (the same markers as the robot's, built
/// here so rviz on the base station costs the link nothing), services `~save_mesh` (.ply: welded
/// PLY; .obj: OBJ + MTL + atlas PNGs with the robot's texture patches, as the robot's save_mesh)
/// and `~get_full_mesh` (the assembled mesh with its texture patches, the sequence of the last
/// update applied and the robot's session). See RobotMeshAssembly for how the stream is followed.
///
/// A fleet (`~robots: [robot1, ...]`, FleetConfig): per robot K, in `/K/<robot_node>/mesh_update`
/// and `get_full_mesh`, out `~K/mesh_markers` (in the robot's own frame: rviz places them by tf),
/// `~K/save_mesh`, `~K/get_full_mesh`; and `~save_mesh` writes the operator mesh: each robot's
/// welded mesh carried into `operator_frame` by tf's latest transform operator_frame → the
/// robot's frame at the moment of the call (so a new alignment re-places a robot's mesh without
/// anything re-sent). With `grid_publish_rate_hz` > 0 the fleet costmap (FleetCostmap):
/// `~occupancy_grid`, `~occupancy_grid_updates`, `~save_grid`.
///
/// Parameters: `~publish_markers` (bool, default true), `~full_mesh_timeout_s` (double, default
/// 5), `~mesh_encoding` ("float32" | "compact", default float32: encoding of its own
/// ~get_full_mesh), and FleetConfig's. Diagnostics: `/diagnostics`, task "mesh assembler" (one
/// robot) or "mesh assembler K" per robot, and "fleet costmap", once a second.
class MeshAssembler : public nodelet::Nodelet {
 private:
  void onInit() override;
  bool saveOperatorMesh(SaveMesh::Request& req, SaveMesh::Response& res);

  CallbackQueueHold queues_;  // first: destroyed after everything registered on the queues
  FleetConfig fleet_;
  std::unique_ptr<tf2_ros::Buffer> tf_buffer_;
  std::unique_ptr<tf2_ros::TransformListener> tf_listener_;
  std::vector<std::unique_ptr<RobotMeshAssembly>> robots_;  // fleet_.robots' order
  std::unique_ptr<FleetCostmap> costmap_;
  ros::ServiceServer save_srv_;
  std::unique_ptr<diagnostic_updater::Updater> diagnostics_;
  ros::WallTimer diagnostics_timer_;
};

}  // namespace stereo_fusion
