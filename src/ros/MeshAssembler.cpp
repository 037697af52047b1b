#include "stereo_fusion/ros/MeshAssembler.h"

#include <pluginlib/class_list_macros.hpp>

#include <algorithm>

#include "stereo_fusion/io/MeshExport.h"
#include "stereo_fusion/mesh/MeshStore.h"

namespace stereo_fusion {

void MeshAssembler::onInit() {
  queues_.hold({&getSTCallbackQueue(), &getMTCallbackQueue()});
  ros::NodeHandle& nh = getNodeHandle();
  ros::NodeHandle& pnh = getPrivateNodeHandle();
  pnh.param("publish_markers", publish_markers_, publish_markers_);
  pnh.param("full_mesh_timeout_s", full_mesh_timeout_s_, full_mesh_timeout_s_);
  if (!(full_mesh_timeout_s_ > 0.0 && full_mesh_timeout_s_ <= 600.0)) {
    const std::string error =
        "parameter '" + pnh.resolveName("full_mesh_timeout_s") + "' must be in (0, 600] s";
    NODELET_FATAL("mesh_assembler: %s", error.c_str());
    throw std::invalid_argument(error);
  }
  const std::string encoding = pnh.param<std::string>("mesh_encoding", "float32");
  if (!parseMeshEncoding(encoding, &encoding_)) {
    const std::string error = "parameter '" + pnh.resolveName("mesh_encoding") +
                              "' must be float32 or compact, not '" + encoding + "'";
    NODELET_FATAL("mesh_assembler: %s", error.c_str());
    throw std::invalid_argument(error);
  }
  full_client_ = nh.serviceClient<GetFullMesh>("get_full_mesh");
  if (publish_markers_) {
    // A new rviz gets every block, not only those that change after it connects.
    markers_pub_ = pnh.advertise<visualization_msgs::MarkerArray>(
        "mesh_markers", 10, [this](const ros::SingleSubscriberPublisher& p) {
          std::lock_guard<std::mutex> lock(mutex_);
          std::vector<BlockKey> all;
          for (const auto& [key, sub] : mesh_) all.push_back(key);
          p.publish(markers_.build(mesh_, all, {}, last_header_));
        });
  }
  save_srv_ = pnh.advertiseService("save_mesh", &MeshAssembler::saveMesh, this);
  full_srv_ = pnh.advertiseService("get_full_mesh", &MeshAssembler::getFullMesh, this);
  // Large queue: while a full mesh is fetched the updates wait here and are applied after it.
  update_sub_ = nh.subscribe("mesh_update", 100, &MeshAssembler::onUpdate, this);
  // A robot that has stopped changing its map sends no updates: fetch the mesh once anyway.
  join_timer_ = nh.createWallTimer(ros::WallDuration(1.0), [this](const ros::WallTimerEvent&) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (synced_) {
      join_timer_.stop();
      return;
    }
    if (full_client_.exists()) fetchFullMesh();
  });
  // Nothing lost silently: gaps, restarts and malformed updates are repaired, and counted here.
  diagnostics_ = std::make_unique<diagnostic_updater::Updater>(nh, pnh);
  diagnostics_->setHardwareID("stereo_fusion");
  diagnostics_->add("mesh assembler", this, &MeshAssembler::diagnose);
  diagnostics_timer_ = nh.createWallTimer(
      ros::WallDuration(1.0), [this](const ros::WallTimerEvent&) { diagnostics_->force_update(); });
  NODELET_INFO("mesh_assembler: assembling %s (full mesh from %s)", update_sub_.getTopic().c_str(),
               full_client_.getService().c_str());
}

void MeshAssembler::onUpdate(const MeshUpdate::ConstPtr& update) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (synced_ && update->session != session_) {
    // The robot's nodelet restarted: its sequence counts from 1 again and its mesh was rebuilt,
    // so sequence numbers say nothing about the mesh held. Start over from its full mesh.
    ++restarts_;
    NODELET_WARN(
        "mesh_assembler: the robot restarted (session %llu, was %llu): fetching the full mesh",
        static_cast<unsigned long long>(update->session),
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
      NODELET_WARN("mesh_assembler: update %llu after %llu: %llu missed, fetching the full mesh",
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

void MeshAssembler::diagnose(diagnostic_updater::DiagnosticStatusWrapper& status) {
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
  status.add("full mesh requests", full_requests_);
  status.add("sequence gaps", gaps_);
  status.add("robot restarts", restarts_);
  status.add("malformed updates", malformed_);
}

bool MeshAssembler::fetchFullMesh() {
  ++full_requests_;
  if (!full_client_.waitForExistence(ros::Duration(full_mesh_timeout_s_))) {
    NODELET_WARN_THROTTLE(10.0, "mesh_assembler: %s is not available",
                          full_client_.getService().c_str());
    synced_ = false;
    return false;
  }
  GetFullMesh srv;
  if (!full_client_.call(srv)) {
    NODELET_WARN_THROTTLE(10.0, "mesh_assembler: calling %s failed",
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
  NODELET_INFO("mesh_assembler: full mesh at sequence %llu: %zu blocks",
               static_cast<unsigned long long>(last_sequence_), mesh_.size());
  return true;
}

bool MeshAssembler::apply(const MeshUpdate& update) {
  if (!applyMeshUpdate(update, &mesh_, &textures_)) {
    ++malformed_;
    NODELET_ERROR_THROTTLE(5.0, "mesh_assembler: malformed mesh update %llu ignored (%llu so far)",
                           static_cast<unsigned long long>(update.sequence),
                           static_cast<unsigned long long>(malformed_));
    return false;
  }
  voxel_size_m_ = update.voxel_size;
  last_header_ = update.header;
  if (!publish_markers_ || markers_pub_.getNumSubscribers() == 0) return true;
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

bool MeshAssembler::saveMesh(SaveMesh::Request& req, SaveMesh::Response& res) {
  {
    // The robot's formats and messages (srv/SaveMesh.srv), written under the lock.
    std::lock_guard<std::mutex> lock(mutex_);
    res.success = exportMesh(req.path, mesh_, textures_, &res.message);
  }
  if (res.success)
    NODELET_INFO("mesh_assembler: save_mesh: %s", res.message.c_str());
  else
    NODELET_ERROR("mesh_assembler: save_mesh: %s", res.message.c_str());
  return true;
}

bool MeshAssembler::getFullMesh(GetFullMesh::Request&, GetFullMesh::Response& res) {
  std::lock_guard<std::mutex> lock(mutex_);
  std::vector<BlockKey> all;
  for (const auto& [key, sub] : mesh_) all.push_back(key);
  std::sort(all.begin(), all.end());
  res.mesh = toMeshUpdate(mesh_, all, {}, last_header_, voxel_size_m_, last_sequence_, true,
                          encoding_, &textures_);
  res.mesh.session = session_;
  return true;
}

}  // namespace stereo_fusion

PLUGINLIB_EXPORT_CLASS(stereo_fusion::MeshAssembler, nodelet::Nodelet)
