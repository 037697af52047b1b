#include "stereo_fusion/ros/MeshAssembler.h"

#include <pluginlib/class_list_macros.hpp>
#include <tf2_eigen/tf2_eigen.h>

#include <filesystem>
#include <sstream>

#include "stereo_fusion/io/OperatorMeshExport.h"
#include "stereo_fusion/mesh/MeshStore.h"

namespace stereo_fusion {

namespace {

/// Throws (after a FATAL naming the parameter) when `ok` is false: a base station with a bad
/// parameter must not start and look healthy.
void require(bool ok, const std::string& error) {
  if (ok) return;
  ROS_FATAL("mesh_assembler: %s", error.c_str());
  throw std::invalid_argument(error);
}

}  // namespace

void MeshAssembler::onInit() {
  queues_.hold({&getSTCallbackQueue(), &getMTCallbackQueue()});
  ros::NodeHandle& nh = getNodeHandle();
  ros::NodeHandle& pnh = getPrivateNodeHandle();
  RobotMeshAssemblyConfig robot_config;
  pnh.param("publish_markers", robot_config.publish_markers, robot_config.publish_markers);
  pnh.param("full_mesh_timeout_s", robot_config.full_mesh_timeout_s,
            robot_config.full_mesh_timeout_s);
  require(robot_config.full_mesh_timeout_s > 0.0 && robot_config.full_mesh_timeout_s <= 600.0,
          "parameter '" + pnh.resolveName("full_mesh_timeout_s") + "' must be in (0, 600] s");
  const std::string encoding = pnh.param<std::string>("mesh_encoding", "float32");
  require(parseMeshEncoding(encoding, &robot_config.encoding),
          "parameter '" + pnh.resolveName("mesh_encoding") + "' must be float32 or compact, not '" +
              encoding + "'");

  // Not param(): a robots that is not a list of strings would silently mean "one robot".
  require(!pnh.hasParam("robots") || pnh.getParam("robots", fleet_.robots),
          "parameter '" + pnh.resolveName("robots") + "' must be a list of robot names");
  pnh.param("robot_node", fleet_.robot_node, fleet_.robot_node);
  pnh.param("operator_frame", fleet_.operator_frame, fleet_.operator_frame);
  pnh.param("grid_publish_rate_hz", fleet_.grid_publish_rate_hz, fleet_.grid_publish_rate_hz);
  pnh.param("grid_resolution_m", fleet_.grid.resolution_m, fleet_.grid.resolution_m);
  int max_cells = static_cast<int>(fleet_.grid.max_cells);
  pnh.param("grid_max_cells", max_cells, max_cells);
  fleet_.grid.max_cells = max_cells;
  pnh.param("grid_max_tilt_rad", fleet_.grid.max_tilt_rad, fleet_.grid.max_tilt_rad);
  const std::vector<std::string> errors = validateFleetConfig(fleet_);
  std::ostringstream joined;
  for (const std::string& e : errors) joined << (joined.tellp() > 0 ? "; " : "") << e;
  require(errors.empty(), "parameters of " + pnh.getNamespace() + ": " + joined.str());

  diagnostics_ = std::make_unique<diagnostic_updater::Updater>(nh, pnh);
  diagnostics_->setHardwareID("stereo_fusion");
  if (!fleet_.fleet()) {
    // One robot, as remapped by the launch file: the topics and services of old.
    robots_.push_back(std::make_unique<RobotMeshAssembly>("", nh, pnh, robot_config));
    diagnostics_->add("mesh assembler", robots_.back().get(), &RobotMeshAssembly::diagnose);
  } else {
    tf_buffer_ = std::make_unique<tf2_ros::Buffer>();
    tf_listener_ = std::make_unique<tf2_ros::TransformListener>(*tf_buffer_, nh);
    for (const std::string& robot : fleet_.robots) {
      robots_.push_back(std::make_unique<RobotMeshAssembly>(
          robot, ros::NodeHandle(nh, fleet_.robotNamespace(robot)), ros::NodeHandle(pnh, robot),
          robot_config));
      diagnostics_->add("mesh assembler " + robot, robots_.back().get(),
                        &RobotMeshAssembly::diagnose);
    }
    save_srv_ = pnh.advertiseService("save_mesh", &MeshAssembler::saveOperatorMesh, this);
    if (fleet_.grid_publish_rate_hz > 0.0) {
      costmap_ = std::make_unique<FleetCostmap>(fleet_, nh, pnh, tf_buffer_.get());
      diagnostics_->add("fleet costmap", costmap_.get(), &FleetCostmap::diagnose);
    }
    NODELET_INFO("mesh_assembler: %zu robots in %s", fleet_.robots.size(),
                 fleet_.operator_frame.c_str());
  }
  // Nothing lost silently: gaps, restarts and malformed updates are repaired, and counted here.
  diagnostics_timer_ = nh.createWallTimer(
      ros::WallDuration(1.0), [this](const ros::WallTimerEvent&) { diagnostics_->force_update(); });
}

bool MeshAssembler::saveOperatorMesh(SaveMesh::Request& req, SaveMesh::Response& res) {
  if (std::filesystem::path(req.path).extension() != ".ply") {  // the operator mesh is PLY only
    res.success = false;
    res.message =
        "save_mesh: '" + req.path + "' does not end in .ply (the operator mesh is written as PLY)";
    ROS_ERROR("base station: %s", res.message.c_str());
    return true;
  }
  // Each robot's mesh as held now, welded in its own frame, placed by its alignment of now.
  std::vector<TriangleMesh> welded(robots_.size());
  std::vector<PlacedMesh> placed;
  std::string empty_robots;
  for (size_t k = 0; k < robots_.size(); ++k) {
    RobotMeshAssembly::Mesh mesh;
    std::string frame;
    robots_[k]->snapshot(&mesh, &frame);
    if (mesh.empty()) {
      empty_robots += " " + fleet_.robots[k];
      continue;
    }
    try {
      const geometry_msgs::TransformStamped t =
          tf_buffer_->lookupTransform(fleet_.operator_frame, frame, ros::Time(0));
      welded[k] = weldSubmeshes(mesh);
      placed.push_back({&welded[k], tf2::transformToEigen(t)});
    } catch (const tf2::TransformException& e) {
      // Refused as a whole: an operator map silently missing a robot would pass for complete.
      res.success = false;
      res.message = "not saved: no transform " + fleet_.operator_frame + " -> " + frame +
                    " for robot " + fleet_.robots[k] + " (" + e.what() + ")";
      NODELET_ERROR("mesh_assembler: save_mesh: %s", res.message.c_str());
      return true;
    }
  }
  res.success = exportOperatorMesh(req.path, placed, &res.message);
  if (res.success && !empty_robots.empty()) res.message += "; no mesh yet from" + empty_robots;
  if (res.success)
    NODELET_INFO("mesh_assembler: save_mesh: %s", res.message.c_str());
  else
    NODELET_ERROR("mesh_assembler: save_mesh: %s", res.message.c_str());
  return true;
}

}  // namespace stereo_fusion

PLUGINLIB_EXPORT_CLASS(stereo_fusion::MeshAssembler, nodelet::Nodelet)
