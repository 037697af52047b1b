#include "stereo_fusion/ros/RosParameters.h"

#include <XmlRpcValue.h>

#include <algorithm>
#include <functional>
#include <sstream>

namespace stereo_fusion {

namespace {

using Table = ParameterTable<NodeConfig>;

template <typename T>
Table::Field<T> member(T NodeConfig::*m) {
  return Table::member(m);
}

/// The node parameter registry: one definition per parameter (the defaults are NodeConfig's).
const Table& table() {
  static const Table parameters = [] {
    Table t;
    t.addString(
        "world_frame", false, "a tf frame, not empty",
        "Fixed frame of the map, the mesh, the path and the clear services' corners; tf must "
        "give it → the disparity's frame_id.",
        member(&NodeConfig::world_frame));
    t.addEnum<InputMode>(
        "input", {{"disparity", InputMode::kDisparity}, {"depth", InputMode::kDepth}},
        "The measurement topic: disparity (stereo_msgs/DisparityImage on `disparity`, a stereo "
        "pipeline) or depth (sensor_msgs/Image on `depth`, 16UC1 in mm or 32FC1 in m as REP 118 "
        "has it, registered to the colour image: an RGB-D camera). Depth is fused as the "
        "disparity fx·depth_baseline_m/z of a virtual stereo rig "
        "([method](method.md#depth-cameras)).",
        member(&NodeConfig::input));
    t.addDouble(
        "depth_baseline_m", "m", 0.0, false, 10.0,
        "input: depth: the baseline of the virtual stereo rig the depth is converted for, "
        "d = fx·B/z. The geometry does not depend on it (z comes back exactly); the noise model "
        "does: σ_z = z²·disparity_noise_px/(fx·B), which picks the levels and the contradiction "
        "margin, and the pixel thresholds (edge_reject_jump_px) act on that disparity. Set the "
        "camera's own: its stereo pair's (RealSense D435 0.05, D455 0.095) or projector–camera "
        "baseline (Kinect v1 0.075).",
        member(&NodeConfig::depth_baseline_m));
    t.addString("image_transport", false, "an image_transport name",
                "How the colour image is subscribed (image_transport): raw, or compressed "
                "(`<image>/compressed`, JPEG or PNG, decoded by the package's own plugin where "
                "compressed_image_transport is not installed); any installed transport.",
                member(&NodeConfig::image_transport));
    t.addString(
        "depth_image_transport", false, "an image_transport name",
        "input: depth: how the depth image is subscribed: raw, or compressedDepth "
        "(`<depth>/compressedDepth`, PNG, as compressed_depth_image_transport publishes it); any "
        "installed transport.",
        member(&NodeConfig::depth_image_transport));
    t.addInt("queue_size", "frames", 1, 1000, "Frames waiting for the worker that fuses them.",
             member(&NodeConfig::queue_size));
    t.addEnum<bool>("queue_policy", {{"drop_oldest", true}, {"drop_newest", false}},
                    "Which frame a full queue drops (counted as `dropped: queue full`): the oldest "
                    "waiting one, or the one arriving.",
                    member(&NodeConfig::drop_oldest));
    t.addBool(
        "approximate_sync",
        "Synchronise disparity, image and camera_info with ApproximateTime instead of ExactTime "
        "(for drivers without hardware sync).",
        member(&NodeConfig::approximate_sync));
    t.addInt("sync_queue_size", "messages", 1, 1000, "Queue of the message_filters synchroniser.",
             member(&NodeConfig::sync_queue_size));
    t.addDouble(
        "tf_timeout_s", "s", 0.0, true, 10.0,
        "How long the worker waits for T_world_camera at the disparity's stamp before it drops "
        "the frame (`dropped: tf timeout`).",
        member(&NodeConfig::tf_timeout_s));
    t.addDouble(
        "max_stamp_ahead_s", "s", 0.0, true, 1e6,
        "A frame stamped more than this ahead of the node's clock is dropped (`dropped: bad "
        "timestamp`). 0 = no check.",
        member(&NodeConfig::max_stamp_ahead_s));
    t.addDouble(
        "mesh_publish_rate_hz", "Hz", 0.0, true, 1000.0,
        "Rate of meshing and of `~mesh_update` (`~mesh_markers`: markers_publish_rate_hz), on "
        "average: a pass falls due a period after the previous one fell due, and one due while "
        "frames wait in the queue waits for them (up to a period). 0 = mesh and publish after "
        "every frame; with texture = patches it meshes after every frame whatever the rate (a "
        "patch is cut from the frame that changed its submesh).",
        member(&NodeConfig::mesh_publish_rate_hz));
    t.addBool("publish_markers", "Publish `~mesh_markers` (rviz).",
              member(&NodeConfig::publish_markers));
    t.addDouble(
        "markers_publish_rate_hz", "Hz", 0.0, true, 1000.0,
        "Rate of `~mesh_markers`: each carries every block changed or removed since the last "
        "(none is missed). 0 = with every `~mesh_update`. rviz's triangle lists take ~40 bytes "
        "per triangle corner to build and send, ~8 times `~mesh_update`'s bytes: at 1 cm and "
        "a mesh rate of 10 Hz they would cost the worker about as much as fusion.",
        member(&NodeConfig::markers_publish_rate_hz));
    t.addBool("publish_path", "Publish `~camera_path`, the poses of the fused frames.",
              member(&NodeConfig::publish_path));
    t.addBool("publish_frustum", "Publish `~frustum`, the newest fused frame's view.",
              member(&NodeConfig::publish_frustum));
    t.addDouble("frustum_depth_m", "m", 0.0, false, 100.0, "Depth at which `~frustum` is drawn.",
                member(&NodeConfig::frustum_depth_m));
    t.addBool("publish_block_bounds",
              "Publish `~block_bounds` (debug; costs a pass over all blocks per update).",
              member(&NodeConfig::publish_block_bounds));
    // The labels parseMeshEncoding() accepts (test:
    // NodeParameters.MeshEncodingLabelsAreTheMessages).
    t.addEnum<MeshEncoding>(
        "mesh_encoding", {{"float32", MeshEncoding::kFloat32}, {"compact", MeshEncoding::kCompact}},
        "How `~mesh_update` and `~get_full_mesh` carry the mesh: float32, or compact "
        "(quantised, about half the bytes; see [Messages](ros_interface.md#messages)).",
        member(&NodeConfig::mesh_encoding));
    t.addInt(
        "loop_closure_max_frames", "frames", 0, 100000,
        "Frames kept so that a trajectory can move them (their disparity and colour images: 2.1 MB "
        "per 640×480 frame, 0.53 MB at 320×240); older frames are fused into a base map once more "
        "at "
        "the best pose known when they leave and are no longer moved. 0 = keep none (the "
        "trajectory "
        "is ignored).",
        member(&NodeConfig::loop_closure_max_frames));
    t.addString(
        "trajectory_frame", true, "a tf frame, or empty",
        "The frame whose poses `trajectory` carries; empty = the camera frame of the disparity "
        "messages. Another frame (e.g. base_link, the IMU) is related to the camera through tf "
        "(its static transform).",
        member(&NodeConfig::trajectory_frame));
    t.addDouble(
        "planning_publish_rate_hz", "Hz", 0.0, false, 100.0,
        "Rate of the planning layer's update (occupancy and distances) and of its topics "
        "(`~occupancy_grid`, `~occupancy_grid_updates`, `~esdf_slice`, `~occupied_voxels`), each "
        "built only while someone subscribes. The services answer from the latest update.",
        member(&NodeConfig::planning_publish_rate_hz));
    t.addDouble("esdf_slice_height_m", "m", -1e4, true, 1e4,
                "Height (z in world_frame) of the horizontal slice `~esdf_slice` publishes.",
                member(&NodeConfig::esdf_slice_height_m));
    t.addInt("planning_max_box_cells", "samples", 1, 100000000,
             "Largest grid `~get_esdf_box` answers; a larger request gets `success: false`.",
             member(&NodeConfig::planning_max_box_cells));
    t.addInt("planning_max_query_points", "points", 1, 100000000,
             "Most points one `~get_distance` request may ask; more get `success: false`.",
             member(&NodeConfig::planning_max_query_points));
    t.addDouble(
        "max_request_wait_s", "s", 0.0, false, 60.0,
        "How long a service request (`~clear_box`, `~clear_sphere`, `~reset`, `~load_map`, "
        "`~save_map`, `~save_mesh`, `~get_full_mesh`, the planning queries) waits for the map "
        "while a frame, a meshing or a planning pass holds it, before it answers busy "
        "(`success: false`, nothing done).",
        member(&NodeConfig::max_request_wait_s));
    t.addDouble(
        "diagnostics_window_s", "s", 0.0, false, 3600.0,
        "Span of the rates and of the drop count /diagnostics reports (`input rate, window (Hz)`, "
        "`frames dropped in the window`): the status is WARN while frames were dropped within "
        "it and OK again once the window has passed them. The totals since start are reported "
        "beside.",
        member(&NodeConfig::diagnostics_window_s));
    t.addDouble(
        "input_timeout_s", "s", 0.0, true, 3600.0,
        "No frame (disparity, image and camera_info matched) for this long after the first one "
        "turns /diagnostics ERROR, `input stale` (a camera or driver that died), and OK again "
        "with the next frame; checked once a second. 0 = off.",
        member(&NodeConfig::input_timeout_s));
    t.addBool(
        "allow_unknown_parameters",
        "A name in the node's namespace that is no parameter here (a misspelt key) is an error "
        "naming it and the nearest known name, and the nodelet does not start; true: a warning "
        "per name, and it starts.",
        member(&NodeConfig::allow_unknown_parameters));
    return t;
  }();
  return parameters;
}

/// The textual form the registries parse, whatever type the YAML gave the value.
bool toText(XmlRpc::XmlRpcValue& v, std::string* text) {
  std::ostringstream os;
  os.precision(17);
  switch (v.getType()) {
    case XmlRpc::XmlRpcValue::TypeBoolean: os << (static_cast<bool>(v) ? "true" : "false"); break;
    case XmlRpc::XmlRpcValue::TypeInt: os << static_cast<int>(v); break;
    case XmlRpc::XmlRpcValue::TypeDouble: os << static_cast<double>(v); break;
    case XmlRpc::XmlRpcValue::TypeString: os << static_cast<std::string>(v); break;
    default: return false;
  }
  *text = os.str();
  return true;
}

/// A registry's message names the parameter as 'name': name it as ROS knows it (with its
/// namespace).
std::string withResolvedName(const ros::NodeHandle& nh, const std::string& name,
                             std::string message) {
  const std::string local = "'" + name + "'";
  const size_t at = message.find(local);
  if (at != std::string::npos) message.replace(at, local.size(), "'" + nh.resolveName(name) + "'");
  return message;
}

/// The first component of every parameter name under `nh`'s namespace, each once, sorted.
std::vector<std::string> namesInNamespace(const ros::NodeHandle& nh) {
  std::vector<std::string> all, names;
  if (!nh.getParamNames(all)) return names;
  const std::string prefix = nh.getNamespace() == "/" ? "/" : nh.getNamespace() + "/";
  for (const std::string& full : all) {
    if (full.compare(0, prefix.size(), prefix) != 0 || full.size() == prefix.size()) continue;
    const std::string rest = full.substr(prefix.size());
    names.push_back(rest.substr(0, rest.find('/')));
  }
  std::sort(names.begin(), names.end());
  names.erase(std::unique(names.begin(), names.end()), names.end());
  return names;
}

/// One message per name under `nh` that no registry knows, each with the nearest known name.
std::vector<std::string> unknownNames(const ros::NodeHandle& nh) {
  std::vector<std::string> known;
  for (const ParameterSpec& spec : mapperParameterSpecs()) known.push_back(spec.name);
  for (const ParameterSpec& spec : nodeParameterSpecs()) known.push_back(spec.name);
  const std::vector<std::string>& foreign = foreignNodeParameterNames();
  std::vector<std::string> messages;
  for (const std::string& name : namesInNamespace(nh)) {
    if (std::find(known.begin(), known.end(), name) != known.end() ||
        std::find(foreign.begin(), foreign.end(), name) != foreign.end())
      continue;
    messages.push_back(parameter_text::unknownParameterMessage(nh.resolveName(name), name, known));
  }
  return messages;
}

/// Reads every parameter of one registry that `nh` holds through `set`.
bool readRegistry(
    const ros::NodeHandle& nh, const std::vector<ParameterSpec>& specs,
    const std::function<bool(const std::string&, const std::string&, std::string*)>& set,
    std::string* error) {
  for (const ParameterSpec& spec : specs) {
    XmlRpc::XmlRpcValue value;
    if (!nh.getParam(spec.name, value)) continue;
    std::string text;
    if (!toText(value, &text)) {
      *error = "parameter '" + nh.resolveName(spec.name) + "' must be a single value";
      return false;
    }
    if (!set(spec.name, text, error)) {
      *error = withResolvedName(nh, spec.name, *error);
      return false;
    }
  }
  return true;
}

}  // namespace

const std::vector<ParameterSpec>& nodeParameterSpecs() { return table().specs(); }

const std::vector<std::string>& foreignNodeParameterNames() {
  static const std::vector<std::string> names{"diagnostic_period"};
  return names;
}

bool setNodeParameter(NodeConfig* config, const std::string& name, const std::string& value,
                      std::string* error) {
  return table().set(config, name, value, error);
}

std::string getNodeParameter(const NodeConfig& config, const std::string& name) {
  return table().get(config, name);
}

std::vector<std::string> validateNodeConfig(const NodeConfig& config) {
  return table().rangeErrors(config);
}

bool loadParameters(const ros::NodeHandle& nh, MapperConfig* mapper, NodeConfig* node,
                    std::string* error, std::vector<std::string>* warnings) {
  MapperConfig mapper_read = *mapper;
  NodeConfig node_read = *node;
  const bool read = readRegistry(
                        nh, mapperParameterSpecs(),
                        [&](const std::string& name, const std::string& text, std::string* why) {
                          return setMapperParameter(&mapper_read, name, text, why);
                        },
                        error) &&
                    readRegistry(
                        nh, nodeParameterSpecs(),
                        [&](const std::string& name, const std::string& text, std::string* why) {
                          return setNodeParameter(&node_read, name, text, why);
                        },
                        error);
  if (!read) return false;
  for (const std::string& e : validateMapperConfig(mapper_read)) {
    *error = e;
    return false;
  }
  const std::vector<std::string> node_errors = validateNodeConfig(node_read);
  if (!node_errors.empty()) {
    *error = node_errors.front();
    for (const ParameterSpec& spec : nodeParameterSpecs()) {
      if (error->find("'" + spec.name + "'") == std::string::npos) continue;
      *error = withResolvedName(nh, spec.name, *error);
      break;
    }
    return false;
  }
  const std::vector<std::string> unknown = unknownNames(nh);
  if (!unknown.empty() && !node_read.allow_unknown_parameters) {
    *error = unknown.front();
    for (size_t i = 1; i < unknown.size(); ++i) *error += "; " + unknown[i];
    *error += " (allow_unknown_parameters: true only warns)";
    return false;
  }
  if (warnings) warnings->insert(warnings->end(), unknown.begin(), unknown.end());
  *mapper = mapper_read;
  *node = node_read;
  return true;
}

}  // namespace stereo_fusion
