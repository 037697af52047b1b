#pragma once
#include <ros/node_handle.h>

#include <string>
#include <vector>

#include "stereo_fusion/MapperConfig.h"
#include "stereo_fusion/ParameterTable.h"
#include "stereo_fusion/ros/MeshMessages.h"

namespace stereo_fusion {

/// What the node's measurement topic carries (FrameInput).
enum class InputMode {
  kDisparity,  ///< `disparity`: stereo_msgs/DisparityImage (a stereo pipeline)
  kDepth,      ///< `depth`: sensor_msgs/Image, 16UC1 mm or 32FC1 m (an RGB-D camera, REP 118)
};

/// Settings of the ROS node itself (the mapping parameters are in MapperConfig). Their names,
/// units, ranges and meanings are the node parameter registry (nodeParameterSpecs(),
/// src/ros/RosParameters.cpp); the defaults here are the single source of truth, printed into
/// doc/parameters.md's node table.
struct NodeConfig {
  std::string world_frame = "map";          ///< fixed frame of the map and the mesh (REP 105's map)
  InputMode input = InputMode::kDisparity;  ///< the measurement topic's kind
  /// Baseline of the virtual stereo rig a depth image is converted for (DepthToDisparity).
  double depth_baseline_m = 0.05;
  /// image_transport of the colour image and of the depth image ("raw", "compressed", ...).
  std::string image_transport = "raw";
  std::string depth_image_transport = "raw";
  int queue_size = 5;             ///< frames waiting for the worker (≥ 1)
  bool drop_oldest = true;        ///< queue full: drop the oldest (true) or the newest frame
  bool approximate_sync = false;  ///< ApproximateTime instead of ExactTime synchronisation
  int sync_queue_size = 10;       ///< message_filters synchroniser queue
  double tf_timeout_s = 0.2;      ///< how long the worker waits for T_world_camera
  /// A frame stamped more than this ahead of the node's clock is dropped (0 = no check).
  double max_stamp_ahead_s = 10.0;
  double mesh_publish_rate_hz = 2.0;  ///< 0 = publish after every frame
  bool publish_markers = true;        ///< ~mesh_markers for rviz
  /// Rate of ~mesh_markers, the mesh's changes since the last one merged; 0 = with every
  /// ~mesh_update. Below the mesh rate: rviz's triangle lists cost ~40 B per corner to build.
  double markers_publish_rate_hz = 2.0;
  bool publish_path = true;           ///< ~camera_path (nav_msgs/Path) of the fused frames
  bool publish_frustum = true;        ///< ~frustum: the newest fused frame's view (Marker)
  double frustum_depth_m = 1.0;       ///< depth at which ~frustum is drawn
  bool publish_block_bounds = false;  ///< ~block_bounds: edges of every meshed block (debug)
  MeshEncoding mesh_encoding = MeshEncoding::kFloat32;  ///< how ~mesh_update carries the mesh
  /// Frames kept for loop closures (their images: ~2.1 MB each at 640×480); 0 = none, and a
  /// trajectory can then correct nothing.
  int loop_closure_max_frames = 300;
  /// The frame whose poses the trajectory topic carries; empty = the camera frame of the
  /// disparity messages. Another frame (e.g. base_link) is related to the camera through tf.
  std::string trajectory_frame;
  /// Rate of the planning layer's update and of its topics (built only while subscribed).
  double planning_publish_rate_hz = 1.0;
  /// Height of ~esdf_slice in world_frame (m).
  double esdf_slice_height_m = 1.0;
  /// Largest ~get_esdf_box grid (samples) and ~get_distance request (points).
  int planning_max_box_cells = 1000000;
  int planning_max_query_points = 1000000;
  /// How long a service request waits for the map held by a frame or a meshing pass before it
  /// answers busy (SessionConfig::max_request_wait_s).
  double max_request_wait_s = 2.0;
  /// Span of the input rates and of the drop count on /diagnostics (InputHealthConfig).
  double diagnostics_window_s = 10.0;
  /// No frame for this long after the first one turns /diagnostics ERROR (stale input); 0 = off.
  double input_timeout_s = 2.0;
  /// A name in the node's namespace that no registry knows: false = an error, the node does not
  /// start; true = a warning per name, and the node starts.
  bool allow_unknown_parameters = false;
};

/// All parameters of NodeConfig, in the order of the node table of doc/parameters.md.
const std::vector<ParameterSpec>& nodeParameterSpecs();

/// Sets node parameter `name` from its textual value. False with a message naming the parameter
/// (and its range and unit) when the name is unknown, the value does not parse or is out of range.
bool setNodeParameter(NodeConfig* config, const std::string& name, const std::string& value,
                      std::string* error);
/// Textual value of node parameter `name` (as setNodeParameter accepts it); empty if unknown.
std::string getNodeParameter(const NodeConfig& config, const std::string& name);

/// Checks every node parameter's range. One message per violation (empty = valid).
std::vector<std::string> validateNodeConfig(const NodeConfig& config);

/// Names the node's private namespace may hold beside both registries' (diagnostic_updater's
/// `diagnostic_period`).
const std::vector<std::string>& foreignNodeParameterNames();

/// Reads every parameter of both registries (mapperParameterSpecs(), nodeParameterSpecs()) from
/// the private namespace of `nh` (missing keys keep their values in *mapper and *node) and
/// validates both. False with a message naming the parameter as ROS knows it (with its
/// namespace) and its range and unit when a value has the wrong type or is out of range; then
/// *mapper and *node are unchanged. A name in the namespace that neither registry (nor
/// foreignNodeParameterNames()) knows — a misspelt key — is refused the same way, the message
/// naming it and the nearest known name; with allow_unknown_parameters: true each such name
/// is one line of *warnings instead (when given) and the load goes on.
bool loadParameters(const ros::NodeHandle& private_nh, MapperConfig* mapper, NodeConfig* node,
                    std::string* error, std::vector<std::string>* warnings = nullptr);

}  // namespace stereo_fusion
