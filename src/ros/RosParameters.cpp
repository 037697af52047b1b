#include "stereo_fusion/ros/RosParameters.h"

#include <XmlRpcValue.h>

#include <sstream>

namespace stereo_fusion {

namespace {

/// The textual form setMapperParameter() parses, whatever type the YAML gave the value.
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

}  // namespace

bool loadParameters(const ros::NodeHandle& nh, MapperConfig* mapper, NodeConfig* node, std::string* error) {
  for (const ParameterSpec& spec : mapperParameterSpecs()) {
    XmlRpc::XmlRpcValue value;
    if (!nh.getParam(spec.name, value)) continue;
    std::string text;
    if (!toText(value, &text)) {
      *error = "parameter '" + nh.resolveName(spec.name) + "' must be a single value";
      return false;
    }
    if (!setMapperParameter(mapper, spec.name, text, error)) {
      // Name the parameter as ROS knows it (with its namespace).
      const std::string local = "'" + spec.name + "'";
      const size_t at = error->find(local);
      if (at != std::string::npos) error->replace(at, local.size(), "'" + nh.resolveName(spec.name) + "'");
      return false;
    }
  }
  for (const std::string& e : validateMapperConfig(*mapper)) {
    *error = e;
    return false;
  }
  nh.param("world_frame", node->world_frame, node->world_frame);
  nh.param("queue_size", node->queue_size, node->queue_size);
  std::string policy = node->drop_oldest ? "drop_oldest" : "drop_newest";
  nh.param("queue_policy", policy, policy);
  nh.param("approximate_sync", node->approximate_sync, node->approximate_sync);
  nh.param("sync_queue_size", node->sync_queue_size, node->sync_queue_size);
  nh.param("tf_timeout_s", node->tf_timeout_s, node->tf_timeout_s);
  nh.param("max_stamp_ahead_s", node->max_stamp_ahead_s, node->max_stamp_ahead_s);
  nh.param("mesh_publish_rate_hz", node->mesh_publish_rate_hz, node->mesh_publish_rate_hz);
  nh.param("publish_markers", node->publish_markers, node->publish_markers);
  nh.param("publish_path", node->publish_path, node->publish_path);
  nh.param("publish_frustum", node->publish_frustum, node->publish_frustum);
  nh.param("frustum_depth_m", node->frustum_depth_m, node->frustum_depth_m);
  nh.param("publish_block_bounds", node->publish_block_bounds, node->publish_block_bounds);
  std::string encoding = node->mesh_encoding == MeshEncoding::kCompact ? "compact" : "float32";
  nh.param("mesh_encoding", encoding, encoding);
  nh.param("loop_closure_max_frames", node->loop_closure_max_frames, node->loop_closure_max_frames);
  nh.param("trajectory_frame", node->trajectory_frame, node->trajectory_frame);
  auto fail = [&](const std::string& name, const std::string& why) {
    *error = "parameter '" + nh.resolveName(name) + "' " + why;
    return false;
  };
  if (node->world_frame.empty()) return fail("world_frame", "must not be empty");
  if (node->queue_size < 1 || node->queue_size > 1000) return fail("queue_size", "must be in [1, 1000]");
  if (policy != "drop_oldest" && policy != "drop_newest") return fail("queue_policy", "must be drop_oldest or drop_newest");
  node->drop_oldest = policy == "drop_oldest";
  if (node->sync_queue_size < 1 || node->sync_queue_size > 1000) return fail("sync_queue_size", "must be in [1, 1000]");
  if (!(node->tf_timeout_s >= 0.0 && node->tf_timeout_s <= 10.0)) return fail("tf_timeout_s", "must be in [0, 10] s");
  if (!(node->max_stamp_ahead_s >= 0.0 && node->max_stamp_ahead_s <= 1e6))
    return fail("max_stamp_ahead_s", "must be in [0, 1e6] s");
  if (!(node->mesh_publish_rate_hz >= 0.0 && node->mesh_publish_rate_hz <= 1000.0))
    return fail("mesh_publish_rate_hz", "must be in [0, 1000] Hz");
  if (!(node->frustum_depth_m > 0.0 && node->frustum_depth_m <= 100.0))
    return fail("frustum_depth_m", "must be in (0, 100] m");
  if (!parseMeshEncoding(encoding, &node->mesh_encoding)) return fail("mesh_encoding", "must be float32 or compact");
  if (node->loop_closure_max_frames < 0 || node->loop_closure_max_frames > 100000)
    return fail("loop_closure_max_frames", "must be in [0, 100000]");
  return true;
}

}  // namespace stereo_fusion
