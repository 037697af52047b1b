#include "stereo_fusion/ros/FusionNodelet.h"

#include <pluginlib/class_list_macros.hpp>

namespace stereo_fusion {

FusionNodelet::~FusionNodelet() {
  // Inputs first (no frame or trajectory reaches a half-destroyed node), then the session and
  // its correction thread (which calls the publisher), then the rest.
  diagnostics_.reset();
  trajectory_input_.reset();
  frame_input_.reset();
  if (planning_) planning_->stop();  // its timer uses the session; the session's thread calls it
  planning_services_.reset();
  services_.reset();
  session_.reset();
}

void FusionNodelet::onInit() {
  queues_.hold({&getSTCallbackQueue(), &getMTCallbackQueue()});
  ros::NodeHandle& nh = getNodeHandle();
  ros::NodeHandle& pnh = getPrivateNodeHandle();
  std::string error;
  std::vector<std::string> warnings;
  if (!loadParameters(pnh, &mapper_config_, &node_config_, &error, &warnings)) {
    NODELET_FATAL("stereo_fusion: %s", error.c_str());
    throw std::invalid_argument(error);
  }
  for (const std::string& w : warnings)
    NODELET_WARN("stereo_fusion: %s (ignored: allow_unknown_parameters is true)", w.c_str());
  SessionConfig session;
  session.loop_closure_max_frames = static_cast<size_t>(node_config_.loop_closure_max_frames);
  session.max_request_wait_s = node_config_.max_request_wait_s;
  session.background_corrections = true;
  session_ = std::make_unique<MappingSession>(mapper_config_, session);
  tf_buffer_ = std::make_unique<tf2_ros::Buffer>(ros::Duration(30.0));
  tf_listener_ = std::make_unique<tf2_ros::TransformListener>(*tf_buffer_, nh);

  cadence_ = OutputCadence::atRates(
      node_config_.mesh_publish_rate_hz, node_config_.markers_publish_rate_hz,
      node_config_.planning_publish_rate_hz, mapper_config_.texture == TextureMode::kPatches);
  publisher_ =
      std::make_unique<MeshPublisher>(pnh, node_config_, session_.get(), &*cadence_, &stats_);
  planning_ = std::make_unique<PlanningPublisher>(
      getMTPrivateNodeHandle(), node_config_, mapper_config_, *cadence_, session_.get(), &stats_);
  session_->setMapReplacedListener([this](const MapReplaced& replaced) {
    publisher_->onMapReplaced(replaced);
    planning_->onMapReplaced(replaced);
  });
  // Services run on the manager's multi-threaded queue, not on the single-threaded one of the
  // frame subscribers. Each locks what it touches.
  services_ =
      std::make_unique<MapServices>(getMTPrivateNodeHandle(), session_.get(), publisher_.get());
  planning_services_ =
      std::make_unique<PlanningServices>(getMTPrivateNodeHandle(), node_config_, session_.get());
  frame_input_ =
      std::make_unique<FrameInput>(nh, pnh, node_config_, session_.get(), tf_buffer_.get(),
                                   &*cadence_, publisher_.get(), &stats_);
  trajectory_input_ =
      std::make_unique<TrajectoryInput>(nh, node_config_, session_.get(), tf_buffer_.get(),
                                        [this] { return frame_input_->cameraFrame(); });
  diagnostics_ = std::make_unique<FusionDiagnostics>(
      nh, pnh, node_config_, session_.get(), frame_input_.get(), trajectory_input_.get(), &stats_);
  if (mapper_config_.keepsMapStore()) {
    // After the publishers: a resumed map goes out whole, as a loaded one.
    const Mapper::StoreOpening opened = session_->openMapStore();
    if (opened.ok)
      NODELET_INFO("stereo_fusion: map store: %s", opened.message.c_str());
    else
      NODELET_ERROR("stereo_fusion: map store: %s", opened.message.c_str());
  }
  NODELET_INFO("stereo_fusion: fusing %s into frame '%s' (voxel %.3f m, %d threads)",
               frame_input_->topics().c_str(), node_config_.world_frame.c_str(),
               mapper_config_.voxel_size_m, mapper_config_.num_threads);
}

}  // namespace stereo_fusion

PLUGINLIB_EXPORT_CLASS(stereo_fusion::FusionNodelet, nodelet::Nodelet)
