#include "stereo_fusion/ros/RobotMeshAssembly.h"

#include <algorithm>

#include "stereo_fusion/io/MeshExport.h"

namespace stereo_fusion {

RobotMeshAssembly::RobotMeshAssembly(const std::string& label, ros::NodeHandle inputs,
                                     ros::NodeHandle outputs, const RobotMeshAssemblyConfig& config)
    : log_name_(label.empty() ? "mesh_assembler" : "mesh_assembler[" + label + "]"),
      config_(config) {
  full_client_ = inputs.serviceClient<GetFullMesh>("get_full_mesh");
  if (config_.publish_markers) {
    // A new rviz gets every block, not only those that change after it connects.
    markers_pub_ = outputs.advertise<visualization_msgs::MarkerArray>(
        "mesh_markers", 10, [this](const ros::SingleSubscriberPublisher& p) {
          std::lock_guard<std::mutex> lock(mutex_);
          std::vector<BlockKey> all;
          for (const auto& [key, sub] : mesh_) all.push_back(key);
          p.publish(markers_.build(mesh_, all, {}, last_header_));
        });
  }
  save_srv_ = outputs.advertiseService("save_mesh", &RobotMeshAssembly::saveMesh, this);
  full_srv_ = outputs.advertiseService("get_full_mesh", &RobotMeshAssembly::getFullMesh, this);
  // Large queue: while a full mesh is fetched the updates wait here and are applied after it.
  update_sub_ = inputs.subscribe("mesh_update", 100, &RobotMeshAssembly::onUpdate, this);
  // A robot that has stopped changing its map sends no updates: fetch the mesh once anyway.
  join_timer_ = inputs.createWallTimer(ros::WallDuration(1.0), [this](const ros::WallTimerEvent&) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (synced_) {
      join_timer_.stop();
      return;
    }
    if (full_client_.exists()) fetchFullMesh();
  });
  ROS_INFO("%s: assembling %s (full mesh from %s)", log_name_.c_str(),
           update_sub_.getTopic().c_str(), full_client_.getService().c_str());
}

void RobotMeshAssembly::snapshot(Mesh* mesh, std::string* frame_id) const {
  std::lock_guard<std::mutex> lock(mutex_);
  *mesh = mesh_;
  *frame_id = last_header_.frame_id;
}

size_t RobotMeshAssembly::blocks() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return mesh_.size();
}

void RobotMeshAssembly::onUpdate(const MeshUpdate::ConstPtr& update) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (synced_ && update->session != session_) {
    // The robot's nodelet restarted: its sequence counts from 1 again and its mesh was rebuilt,
    // so sequence numbers say nothing about the mesh held. Start over from its full mesh.
    ++restarts_;
    ROS_WARN("%s: the robot restarted (session %llu, was %llu): fetching the full mesh",
             log_name_.c_str(), static_cast<unsigned long long>(update->session),
             static_cast<unsigned long long>(session_));
    synced_ = false;
  }
  if (update->full) {  // the robot was reset (or sends whole meshes): nothing before matters
    // ... unless it is older than what we hold (a late message of the same session).
    if (synced_ && update->sequence < last_sequence_) return;
    synced_ = apply(*update);
    last_sequence_ = update->sequence;
    session_ = update->session;
    return;
  }
  if (synced_ && update->sequence <= last_sequence_) return;  // already in the mesh we hold
  if (!synced_ || update->sequence != last_sequence_ + 1) {
    if (synced_) {
      ++gaps_;
      ROS_WARN("%s: update %llu after %llu: %llu missed, fetching the full mesh", log_name_.c_str(),
               static_cast<unsigned long long>(update->sequence),
               static_cast<unsigned long long>(last_sequence_),
               static_cast<unsigned long long>(update->sequence - last_sequence_ - 1));
    }
    if (!fetchFullMesh()) return;
    // An update of another run of the robot than the mesh fetched (sent just before or after a
    // restart): its sequence means nothing here; the next update of the fetched session goes on.
    if (update->session != session_) return;
    if (update->sequence <= last_sequence_) return;  // the full mesh already holds it
    if (update->sequence != last_sequence_ + 1) {    // still behind: the next update retries
      synced_ = false;
      return;
    }
  }
  if (apply(*update))
    last_sequence_ = update->sequence;
  else
    synced_ = false;  // our copy may now differ: repair from the next update
}

void RobotMeshAssembly::diagnose(diagnostic_updater::DiagnosticStatusWrapper& status) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!synced_)
    status.summary(diagnostic_msgs::DiagnosticStatus::WARN,
                   "not in sync with the robot's mesh (fetching it)");
  else if (gaps_ > 0 || malformed_ > 0)
    status.summary(diagnostic_msgs::DiagnosticStatus::WARN,
                   "in sync; updates were lost or malformed, see the counters");
  else
    status.summary(diagnostic_msgs::DiagnosticStatus::OK, "in sync");
  status.add("in sync", synced_);
  status.add("session", session_);
  status.add("last sequence", last_sequence_);
  status.add("blocks", mesh_.size());
  status.add("frame", last_header_.frame_id);
  status.add("full mesh requests", full_requests_);
  status.add("sequence gaps", gaps_);
  status.add("robot restarts", restarts_);
  status.add("malformed updates", malformed_);
}

bool RobotMeshAssembly::fetchFullMesh() {
  ++full_requests_;
  if (!full_client_.waitForExistence(ros::Duration(config_.full_mesh_timeout_s))) {
    ROS_WARN_THROTTLE(10.0, "%s: %s is not available", log_name_.c_str(),
                      full_client_.getService().c_str());
    synced_ = false;
    return false;
  }
  GetFullMesh srv;
  if (!full_client_.call(srv)) {
    ROS_WARN_THROTTLE(10.0, "%s: calling %s failed", log_name_.c_str(),
                      full_client_.getService().c_str());
    synced_ = false;
    return false;
  }
  srv.response.mesh.full = true;
  if (!apply(srv.response.mesh)) {
    synced_ = false;
    return false;
  }
  last_sequence_ = srv.response.mesh.sequence;
  session_ = srv.response.mesh.session;
  synced_ = true;
  ROS_INFO("%s: full mesh at sequence %llu: %zu blocks", log_name_.c_str(),
           static_cast<unsigned long long>(last_sequence_), mesh_.size());
  return true;
}

bool RobotMeshAssembly::apply(const MeshUpdate& update) {
  if (!applyMeshUpdate(update, &mesh_, &textures_)) {
    ++malformed_;
    ROS_ERROR_THROTTLE(5.0, "%s: malformed mesh update %llu ignored (%llu so far)",
                       log_name_.c_str(), static_cast<unsigned long long>(update.sequence),
                       static_cast<unsigned long long>(malformed_));
    return false;
  }
  voxel_size_m_ = update.voxel_size;
  last_header_ = update.header;
  if (!config_.publish_markers || markers_pub_.getNumSubscribers() == 0) return true;
  std::vector<BlockKey> changed, removed;
  for (const MeshBlock& b : update.blocks) changed.push_back({b.key[0], b.key[1], b.key[2]});
  for (size_t i = 0; i + 2 < update.removed_keys.size(); i += 3)
    removed.push_back(
        {update.removed_keys[i], update.removed_keys[i + 1], update.removed_keys[i + 2]});
  if (update.full) {
    markers_pub_.publish(markers_.clear(update.header));
    changed.clear();
    for (const auto& [key, sub] : mesh_) changed.push_back(key);
  }
  markers_pub_.publish(markers_.build(mesh_, changed, removed, update.header));
  return true;
}

bool RobotMeshAssembly::saveMesh(SaveMesh::Request& req, SaveMesh::Response& res) {
  {
    // The robot's formats and messages (srv/SaveMesh.srv), written under the lock.
    std::lock_guard<std::mutex> lock(mutex_);
    res.success = exportMesh(req.path, mesh_, textures_, &res.message);
  }
  if (res.success)
    ROS_INFO("%s: save_mesh: %s", log_name_.c_str(), res.message.c_str());
  else
    ROS_ERROR("%s: save_mesh: %s", log_name_.c_str(), res.message.c_str());
  return true;
}

bool RobotMeshAssembly::getFullMesh(GetFullMesh::Request&, GetFullMesh::Response& res) {
  std::lock_guard<std::mutex> lock(mutex_);
  std::vector<BlockKey> all;
  for (const auto& [key, sub] : mesh_) all.push_back(key);
  std::sort(all.begin(), all.end());
  res.mesh = toMeshUpdate(mesh_, all, {}, last_header_, voxel_size_m_, last_sequence_, true,
                          config_.encoding, &textures_);
  res.mesh.session = session_;
  return true;
}

}  // namespace stereo_fusion
