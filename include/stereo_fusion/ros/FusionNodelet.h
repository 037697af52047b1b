#pragma once
// The ROS face of stereo_fusion: wiring only. The mapping session (ROS-free) owns the map, the
// kept frames, clears and corrections; the adapters around it are FrameInput (synchronised
// DisparityImage or depth Image + Image + CameraInfo in, images through image_transport, pose
// from tf2), TrajectoryInput (a SLAM's corrected
// poses), MeshPublisher (MeshUpdate, rviz markers, path, frustum), PlanningPublisher (occupancy
// grid, ESDF slice, occupied cells), MapServices and FusionDiagnostics.

#include <nodelet/nodelet.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>

#include <memory>
#include <optional>

#include "stereo_fusion/ros/CallbackQueueHold.h"
#include "stereo_fusion/ros/FrameInput.h"
#include "stereo_fusion/ros/FusionDiagnostics.h"
#include "stereo_fusion/ros/NodeStats.h"
#include "stereo_fusion/ros/MapServices.h"
#include "stereo_fusion/ros/MeshPublisher.h"
#include "stereo_fusion/ros/PlanningServices.h"
#include "stereo_fusion/ros/PlanningPublisher.h"
#include "stereo_fusion/ros/RosParameters.h"
#include "stereo_fusion/ros/TrajectoryInput.h"
#include "stereo_fusion/session/MappingSession.h"
#include "stereo_fusion/session/OutputCadence.h"

namespace stereo_fusion {

/// Nodelet `stereo_fusion/FusionNodelet`; its topics, services and parameters are in
/// doc/ros_interface.md.
class FusionNodelet : public nodelet::Nodelet {
 public:
  ~FusionNodelet() override;

 private:
  void onInit() override;

  CallbackQueueHold queues_;  // first: destroyed after everything registered on the queues
  NodeConfig node_config_;
  MapperConfig mapper_config_;
  std::unique_ptr<MappingSession> session_;
  NodeStats stats_;
  std::optional<OutputCadence> cadence_;  // when to mesh, publish and plan
  std::unique_ptr<tf2_ros::Buffer> tf_buffer_;
  std::unique_ptr<tf2_ros::TransformListener> tf_listener_;
  std::unique_ptr<MeshPublisher> publisher_;
  std::unique_ptr<PlanningPublisher> planning_;
  std::unique_ptr<MapServices> services_;
  std::unique_ptr<PlanningServices> planning_services_;
  std::unique_ptr<TrajectoryInput> trajectory_input_;
  std::unique_ptr<FrameInput> frame_input_;
  std::unique_ptr<FusionDiagnostics> diagnostics_;
};

}  // namespace stereo_fusion
