#include "stereo_fusion/ros/FusionNodelet.h"

#include <pluginlib/class_list_macros.hpp>
#include <tf2_eigen/tf2_eigen.h>

#include <algorithm>

#include "stereo_fusion/io/MapFile.h"
#include "stereo_fusion/io/MeshExport.h"
#include "stereo_fusion/util/Percentile.h"
#include "stereo_fusion/ros/DebugMarkers.h"
#include "stereo_fusion/ros/MessageConversions.h"

namespace stereo_fusion {

FusionNodelet::~FusionNodelet() {
  {
    std::lock_guard<std::mutex> lock(correction_mutex_);
    correction_stopping_ = true;
  }
  correction_cv_.notify_all();
  if (correction_thread_.joinable()) correction_thread_.join();
  {
    std::lock_guard<std::mutex> lock(queue_mutex_);
    stopping_ = true;
  }
  queue_cv_.notify_all();
  if (worker_.joinable()) worker_.join();
}

void FusionNodelet::onInit() {
  ros::NodeHandle& nh = getNodeHandle();
  ros::NodeHandle& pnh = getPrivateNodeHandle();
  std::string error;
  if (!loadParameters(pnh, &mapper_config_, &node_config_, &error)) {
    NODELET_FATAL("stereo_fusion: %s", error.c_str());
    throw std::invalid_argument(error);
  }
  mapper_ = std::make_unique<Mapper>(mapper_config_);
  publisher_ = mapper_->subscribeToMeshChanges("mesh_update publisher");
  window_ = std::make_unique<CorrectionWindow>(mapper_config_, static_cast<size_t>(node_config_.loop_closure_max_frames));
  started_ = ros::WallTime::now();
  session_ = started_.toNSec();
  last_publish_ = ros::WallTime(0, 0);

  tf_buffer_ = std::make_unique<tf2_ros::Buffer>(ros::Duration(30.0));
  tf_listener_ = std::make_unique<tf2_ros::TransformListener>(*tf_buffer_, nh);

  mesh_update_pub_ = pnh.advertise<MeshUpdate>("mesh_update", 10);
  // A new rviz gets the whole mesh, not only the blocks that change after it connects.
  markers_pub_ = pnh.advertise<visualization_msgs::MarkerArray>(
      "mesh_markers", 10, [this](const ros::SingleSubscriberPublisher&) {
        std::lock_guard<std::mutex> lock(map_mutex_);
        markers_full_pending_ = true;
      });
  if (node_config_.publish_path) path_pub_ = pnh.advertise<nav_msgs::Path>("camera_path", 1, true);
  path_.header.frame_id = node_config_.world_frame;
  if (node_config_.publish_frustum) frustum_pub_ = pnh.advertise<visualization_msgs::Marker>("frustum", 1, true);
  if (node_config_.publish_block_bounds)
    block_bounds_pub_ = pnh.advertise<visualization_msgs::Marker>("block_bounds", 1, true);
  // Services run on the manager's multi-threaded queue, not on the single-threaded one of the
  // frame subscribers: writing a large map or mesh (seconds on a robot's flash) must not stop
  // frames from arriving. Each service locks what it touches.
  ros::NodeHandle& service_nh = getMTPrivateNodeHandle();
  save_srv_ = service_nh.advertiseService("save_mesh", &FusionNodelet::saveMesh, this);
  full_srv_ = service_nh.advertiseService("get_full_mesh", &FusionNodelet::getFullMesh, this);
  reset_srv_ = service_nh.advertiseService("reset", &FusionNodelet::reset, this);
  save_map_srv_ = service_nh.advertiseService("save_map", &FusionNodelet::saveMap, this);
  load_map_srv_ = service_nh.advertiseService("load_map", &FusionNodelet::loadMap, this);
  clear_box_srv_ = service_nh.advertiseService("clear_box", &FusionNodelet::clearBox, this);
  clear_sphere_srv_ = service_nh.advertiseService("clear_sphere", &FusionNodelet::clearSphere, this);

  diagnostics_ = std::make_unique<diagnostic_updater::Updater>(nh, pnh);
  diagnostics_->setHardwareID("stereo_fusion");
  diagnostics_->add("fusion", this, &FusionNodelet::diagnose);
  diagnostics_timer_ = nh.createWallTimer(ros::WallDuration(1.0), [this](const ros::WallTimerEvent&) {
    diagnostics_->force_update();
  });

  worker_ = std::thread([this] { workerLoop(); });
  correction_thread_ = std::thread([this] { correctionLoop(); });
  trajectory_sub_ = nh.subscribe("trajectory", 5, &FusionNodelet::onTrajectory, this);

  // The synchroniser is fed by hand so that the first message of a stamp on each topic wins: it
  // would let a second one replace the first while the set is incomplete (see RecentStamps).
  // roscpp runs one subscription's callbacks one at a time, so disparity_seq_ needs no lock.
  const size_t stamp_window = static_cast<size_t>(std::max(8, 2 * node_config_.sync_queue_size));
  disparity_stamps_ = RecentStamps(stamp_window);
  image_stamps_ = RecentStamps(stamp_window);
  info_stamps_ = RecentStamps(stamp_window);
  if (node_config_.approximate_sync) {
    approx_sync_ = std::make_unique<message_filters::Synchronizer<ApproxPolicy>>(ApproxPolicy(node_config_.sync_queue_size));
    approx_sync_->registerCallback(&FusionNodelet::onFrame, this);
  } else {
    exact_sync_ = std::make_unique<message_filters::Synchronizer<ExactPolicy>>(ExactPolicy(node_config_.sync_queue_size));
    exact_sync_->registerCallback(&FusionNodelet::onFrame, this);
  }

  // Callbacks first, subscriptions after: a message arriving in between would reach no callback
  // and be lost uncounted (a player that starts on the first subscription sends one at once).
  disparity_sub_.registerCallback([this](const DisparityMsg::ConstPtr& disparity) {
    ++disparities_in_;
    disparities_missed_ += disparity_seq_.next(disparity->header.seq);
    if (!passToSync(&disparity_stamps_, disparity->header.stamp)) {
      ++dropped_sync_duplicate_;
      NODELET_WARN_THROTTLE(5.0, "stereo_fusion: a second disparity stamped %.3f arrived before its frame was "
                                 "matched; the first is kept, this one dropped (%llu so far)",
                            disparity->header.stamp.toSec(),
                            static_cast<unsigned long long>(dropped_sync_duplicate_.load()));
      return;
    }
    addToSync<0>(disparity);
  });
  image_sub_.registerCallback([this](const ImageMsg::ConstPtr& image) {
    if (passToSync(&image_stamps_, image->header.stamp)) addToSync<1>(image);
    else ++ignored_duplicate_parts_;
  });
  info_sub_.registerCallback([this](const InfoMsg::ConstPtr& info) {
    if (passToSync(&info_stamps_, info->header.stamp)) addToSync<2>(info);
    else ++ignored_duplicate_parts_;
  });
  disparity_sub_.subscribe(nh, "disparity", 5);
  image_sub_.subscribe(nh, "image", 5);
  info_sub_.subscribe(nh, "camera_info", 5);
  NODELET_INFO("stereo_fusion: fusing %s + %s + %s into frame '%s' (voxel %.3f m, %d threads)",
               disparity_sub_.getTopic().c_str(), image_sub_.getTopic().c_str(), info_sub_.getTopic().c_str(),
               node_config_.world_frame.c_str(), mapper_config_.voxel_size_m, mapper_config_.num_threads);
}

void FusionNodelet::onFrame(const DisparityMsg::ConstPtr& d, const ImageMsg::ConstPtr& i,
                            const InfoMsg::ConstPtr& c) {
  ++received_;
  {
    std::lock_guard<std::mutex> lock(stamps_mutex_);
    disparity_stamps_.forget(d->header.stamp.toNSec());
    image_stamps_.forget(i->header.stamp.toNSec());
    info_stamps_.forget(c->header.stamp.toNSec());
  }
  {
    std::lock_guard<std::mutex> lock(queue_mutex_);
    if (queue_.size() >= static_cast<size_t>(node_config_.queue_size)) {
      ++dropped_queue_;
      NODELET_WARN_THROTTLE(5.0, "stereo_fusion: frame queue full (%d), dropping the %s frame (%llu so far)",
                            node_config_.queue_size, node_config_.drop_oldest ? "oldest" : "newest",
                            static_cast<unsigned long long>(dropped_queue_.load()));
      if (!node_config_.drop_oldest) return;
      queue_.pop_front();
    }
    queue_.push_back({d, i, c, map_epoch_.load(), clear_epoch_.load()});
  }
  queue_cv_.notify_one();
}

void FusionNodelet::workerLoop() {
  while (true) {
    QueuedFrame frame;
    {
      std::unique_lock<std::mutex> lock(queue_mutex_);
      queue_cv_.wait_for(lock, std::chrono::milliseconds(100), [this] { return stopping_ || !queue_.empty(); });
      if (stopping_) return;
      if (queue_.empty()) {
        lock.unlock();
        publishPending(ros::Time(0), false);  // flush a rate-limited update
        continue;
      }
      frame = queue_.front();
      queue_.pop_front();
    }
    try {
      processFrame(frame);
    } catch (const std::exception& e) {
      // One bad frame (or an allocation failure) must not take the nodelet manager down.
      ++dropped_bad_input_;
      NODELET_ERROR_THROTTLE(5.0, "stereo_fusion: frame dropped after an error: %s", e.what());
    }
  }
}

void FusionNodelet::processFrame(const QueuedFrame& f) {
  const std_msgs::Header& header = f.disparity->header;
  // A stamp of 0 would make tf return its latest pose, whatever time the image is from; a stamp
  // far ahead of the clock is a broken driver clock. Neither may reach the map.
  const ros::Time now = ros::Time::now();
  if (header.stamp.isZero() ||
      (node_config_.max_stamp_ahead_s > 0.0 && !now.isZero() &&
       (header.stamp - now).toSec() > node_config_.max_stamp_ahead_s)) {
    ++dropped_bad_stamp_;
    NODELET_WARN_THROTTLE(5.0, "stereo_fusion: frame stamped %.3f s %s, frame dropped (%llu so far)",
                          header.stamp.toSec(),
                          header.stamp.isZero() ? "(no time: its pose cannot be looked up)"
                                                : "is ahead of the clock by more than max_stamp_ahead_s",
                          static_cast<unsigned long long>(dropped_bad_stamp_.load()));
    return;
  }
  std::string tf_error;
  // Wait in wall time: under simulated time a paused or finished bag stops the ROS clock, and a
  // ROS-time timeout would then never expire. Shutdown interrupts the wait.
  const ros::WallTime tf_deadline = ros::WallTime::now() + ros::WallDuration(node_config_.tf_timeout_s);
  bool have_tf = false;
  while (true) {
    tf_error.clear();
    have_tf = tf_buffer_->canTransform(node_config_.world_frame, header.frame_id, header.stamp, &tf_error);
    if (have_tf || ros::WallTime::now() >= tf_deadline) break;
    {
      std::lock_guard<std::mutex> lock(queue_mutex_);
      if (stopping_) return;
    }
    ros::WallDuration(0.005).sleep();
  }
  if (!have_tf) {
    ++dropped_tf_;
    NODELET_WARN_THROTTLE(5.0, "stereo_fusion: no transform %s <- %s at %.3f within %.2f s, frame dropped (%llu so far): %s",
                          node_config_.world_frame.c_str(), header.frame_id.c_str(), header.stamp.toSec(),
                          node_config_.tf_timeout_s, static_cast<unsigned long long>(dropped_tf_.load()),
                          tf_error.c_str());
    return;
  }
  Eigen::Isometry3d T_world_camera;
  try {
    T_world_camera = tf2::transformToEigen(tf_buffer_->lookupTransform(node_config_.world_frame, header.frame_id, header.stamp));
  } catch (const tf2::TransformException& e) {
    ++dropped_tf_;
    NODELET_WARN_THROTTLE(5.0, "stereo_fusion: %s", e.what());
    return;
  }
  StereoFrame frame;
  std::string error;
  if (!toStereoFrame(*f.disparity, *f.image, *f.info, T_world_camera, &frame, &error)) {
    ++dropped_bad_input_;
    NODELET_ERROR_THROTTLE(5.0, "stereo_fusion: bad input, frame dropped (%llu so far): %s",
                           static_cast<unsigned long long>(dropped_bad_input_.load()), error.c_str());
    return;
  }
  IntegrationResult result;
  {
    std::lock_guard<std::mutex> lock(map_mutex_);
    if (f.map_epoch != map_epoch_.load()) {  // a reset or load_map came in while it waited for tf
      ++dropped_superseded_;
      return;
    }
    try {
      // The mesh is brought up to date when it is published (publishPending()), at most
      // mesh_publish_rate_hz; with rate 0, after every frame. Texture patches are cut from the
      // frame that changed a submesh, so with textures the mesh follows every frame.
      const bool deferred = node_config_.mesh_publish_rate_hz > 0 && mapper_config_.texture != TextureMode::kPatches;
      const MeshTiming timing = deferred ? MeshTiming::kDeferred : MeshTiming::kNow;
      result = mapper_->integrate(frame, timing);
      if (result.accepted) reapplyClearsLocked(f, header.stamp, timing);
    } catch (const std::exception&) {
      // A throw mid-frame (e.g. bad_alloc) can leave the fused voxels and the mesh out of step:
      // re-mesh from the map and send subscribers a full update before the frame is counted.
      if (mapper_config_.mesh_enabled) {
        try {
          publishFullLocked(mapper_->rebuildMesh().removed);
        } catch (const std::exception& e) {
          NODELET_ERROR_THROTTLE(5.0, "stereo_fusion: re-meshing after a failed frame failed too: %s", e.what());
        }
      }
      throw;
    }
    blocks_evicted_ += result.evicted_blocks.size();
    if (result.accepted) {
      pixels_rejected_speckle_ += result.rejected.speckle_pixels;
      pixels_rejected_edge_ += result.rejected.edge_pixels;
      window_->add(frame);  // kept for a loop closure (shares the images)
      ++window_frames_added_;
      camera_frame_ = header.frame_id;
      unpublished_stamps_.push_back(header.stamp);
      // Free-space carving counts as fusion: it is the frame's update of the map.
      frame_ms_.push_back({result.lookup_ms, result.fusion_ms + result.carve_ms,
                           result.lookup_ms + result.fusion_ms + result.carve_ms + result.mesh.meshing_ms +
                               result.texture.texture_ms});
      if (frame_ms_.size() > 1000) frame_ms_.pop_front();
      if (!result.mesh.changed.empty() || !result.mesh.removed.empty() || result.mesh.blocks_meshed > 0)
        recordMeshPassLocked(result.mesh.meshing_ms, result.texture.texture_ms);
      if (node_config_.publish_path) {
        geometry_msgs::PoseStamped pose;
        pose.header = header;
        pose.header.frame_id = node_config_.world_frame;
        pose.pose = tf2::toMsg(T_world_camera);
        path_.poses.push_back(pose);
        // Bounded: keep the newest kMaxPathPoses, thinning the older half when full.
        if (path_.poses.size() > kMaxPathPoses) {
          std::vector<geometry_msgs::PoseStamped> thinned;
          for (size_t k = 0; k < path_.poses.size() / 2; k += 2) thinned.push_back(path_.poses[k]);
          thinned.insert(thinned.end(), path_.poses.begin() + path_.poses.size() / 2, path_.poses.end());
          path_.poses.swap(thinned);
        }
        path_.header.stamp = header.stamp;
        if (path_pub_.getNumSubscribers() > 0) path_pub_.publish(correctedPathLocked());
      }
      if (node_config_.publish_frustum) {
        std_msgs::Header world_header = header;
        world_header.frame_id = node_config_.world_frame;
        frustum_pub_.publish(frustumMarker(frame.camera, T_world_camera, node_config_.frustum_depth_m, world_header));
      }
    }
  }
  if (!result.accepted) {
    std::atomic<uint64_t>& counter = result.reason == RejectReason::kTimestampBackwards ? dropped_backwards_
                                     : result.reason == RejectReason::kDuplicateTimestamp ? dropped_duplicate_
                                     : result.reason == RejectReason::kPoseJump          ? dropped_pose_jump_
                                     : result.reason == RejectReason::kTimestampJump     ? dropped_timestamp_jump_
                                     : result.reason == RejectReason::kAllocationBudget  ? dropped_allocation_budget_
                                     : result.reason == RejectReason::kIncoherentDisparity ? dropped_incoherent_
                                                                                          : dropped_bad_input_;
    ++counter;
    NODELET_ERROR_THROTTLE(5.0, "stereo_fusion: frame rejected (%s, %llu so far): %s", rejectReasonName(result.reason),
                           static_cast<unsigned long long>(counter.load()), result.error.c_str());
    return;
  }
  ++fused_;
  if (result.reanchored) {
    ++reanchored_;
    NODELET_WARN("stereo_fusion: %s", result.note.c_str());
  }
  publishPending(header.stamp, false);
}

void FusionNodelet::recordMeshPassLocked(double meshing_ms, double texture_ms) {
  mesh_pass_ms_.push_back({meshing_ms, texture_ms});
  if (mesh_pass_ms_.size() > 1000) mesh_pass_ms_.pop_front();
  ++mesh_passes_;
}

void FusionNodelet::catchUpMeshLocked() {
  if (mapper_->blocksAwaitingMesh() == 0) return;
  const MeshPass pass = mapper_->updateMesh();
  recordMeshPassLocked(pass.mesh.meshing_ms, pass.texture.texture_ms);
  // The planning layer follows the map at the mesh's rate (its topics and services are the
  // planning-on-ROS work's); it reads the same changes.
  mapper_->updatePlanning();
}

void FusionNodelet::publishPending(const ros::Time& stamp, bool force) {
  std::lock_guard<std::mutex> lock(map_mutex_);
  if (mapper_->blocksAwaitingMesh() == 0 && mapper_->pendingMeshChanges(publisher_) == 0 && !markers_full_pending_)
    return;
  const ros::WallTime now = ros::WallTime::now();
  if (!force && node_config_.mesh_publish_rate_hz > 0 &&
      (now - last_publish_).toSec() < 1.0 / node_config_.mesh_publish_rate_hz)
    return;
  last_publish_ = now;
  // The mesher catches up with the blocks fusion changed since the last publish.
  catchUpMeshLocked();
  std_msgs::Header header;
  header.frame_id = node_config_.world_frame;
  header.stamp = stamp.isZero() && !unpublished_stamps_.empty() ? unpublished_stamps_.back() : stamp;
  const BlockChangeLog::Changes pending = mapper_->takeMeshChanges(publisher_);
  const std::vector<BlockKey>& changed = pending.updated;
  const std::vector<BlockKey>& removed = pending.erased;
  // Every flush of changes gets a sequence number, sent or not: a subscriber that was not
  // connected for one sees the gap and asks ~get_full_mesh. Publish only what someone hears.
  if (!changed.empty() || !removed.empty()) {
    ++sequence_;
    if (mesh_update_pub_.getNumSubscribers() > 0) {
      MeshUpdate update = toMeshUpdate(mapper_->mesh().submeshes(), changed, removed, header,
                                       mapper_config_.voxel_size_m, sequence_, false, node_config_.mesh_encoding,
                                       &mapper_->textures());
      update.session = session_;
      mesh_update_pub_.publish(update);
    }
  }
  if (node_config_.publish_markers && markers_pub_.getNumSubscribers() > 0) {
    if (markers_full_pending_) {
      std::vector<BlockKey> all;
      for (const auto& [key, sub] : mapper_->mesh().submeshes()) all.push_back(key);
      markers_pub_.publish(markers_.build(mapper_->mesh().submeshes(), all, removed, header));
      markers_full_pending_ = false;
    } else {
      markers_pub_.publish(markers_.build(mapper_->mesh().submeshes(), changed, removed, header));
    }
  }
  // Latched and opt-in (debug): published even unheard, so a display ticked later shows it.
  if (node_config_.publish_block_bounds)
    block_bounds_pub_.publish(blockBoundsMarker(mapper_->mesh().submeshes(), 8.0 * mapper_config_.voxel_size_m, header));
  const ros::Time ros_now = ros::Time::now();
  for (const ros::Time& t : unpublished_stamps_) {
    latencies_s_.push_back((ros_now - t).toSec());
    if (latencies_s_.size() > 1000) latencies_s_.pop_front();
  }
  unpublished_stamps_.clear();
}

bool FusionNodelet::saveMesh(SaveMesh::Request& req, SaveMesh::Response& res) {
  // Only the copy of the mesh holds the map; the file is written while frames are fused (a slow
  // disk, or a target that blocks, must not stop fusion).
  std::unordered_map<BlockKey, SubMesh, BlockKeyHash> submeshes;
  std::unordered_map<BlockKey, TexturePatch, BlockKeyHash> patches;
  {
    std::lock_guard<std::mutex> lock(map_mutex_);
    // The mesh of every frame fused so far (the publisher sends these changes at its next turn).
    catchUpMeshLocked();
    submeshes = mapper_->mesh().submeshes();
    patches = mapper_->textures().patches();
  }
  res.success = exportMesh(req.path, submeshes, patches, &res.message);
  if (res.success)
    NODELET_INFO("stereo_fusion: save_mesh: %s", res.message.c_str());
  else
    NODELET_ERROR("stereo_fusion: save_mesh: %s", res.message.c_str());
  return true;
}

bool FusionNodelet::getFullMesh(GetFullMesh::Request&, GetFullMesh::Response& res) {
  // Frames already fused are in the answer even if their meshing waits for the publish rate:
  // their changes go out as an update first, so the full mesh's sequence covers them.
  publishPending(ros::Time(0), true);
  std::lock_guard<std::mutex> lock(map_mutex_);
  std::vector<BlockKey> all;
  for (const auto& [key, sub] : mapper_->mesh().submeshes()) all.push_back(key);
  std::sort(all.begin(), all.end());
  std_msgs::Header header;
  header.frame_id = node_config_.world_frame;
  header.stamp = ros::Time::now();
  // The sequence of the last published update: apply updates with a larger sequence on top.
  res.mesh = toMeshUpdate(mapper_->mesh().submeshes(), all, {}, header, mapper_config_.voxel_size_m, sequence_,
                          true, node_config_.mesh_encoding, &mapper_->textures());
  res.mesh.session = session_;
  return true;
}

void FusionNodelet::startMapEpochLocked() {
  std::lock_guard<std::mutex> lock(queue_mutex_);
  ++map_epoch_;
  dropped_superseded_ += queue_.size();
  queue_.clear();
}

bool FusionNodelet::reset(std_srvs::Empty::Request&, std_srvs::Empty::Response&) {
  std::lock_guard<std::mutex> lock(map_mutex_);
  startMapEpochLocked();
  mapper_->reset();
  cleared_regions_.clear();
  dropCorrectionStateLocked();
  path_.poses.clear();
  frame_ms_.clear();
  mesh_pass_ms_.clear();
  mapper_->takeMeshChanges(publisher_);  // the empty full update below says it all
  unpublished_stamps_.clear();
  std_msgs::Header header;
  header.frame_id = node_config_.world_frame;
  header.stamp = ros::Time::now();
  markers_pub_.publish(markers_.clear(header));
  MeshUpdate empty =
      toMeshUpdate(mapper_->mesh().submeshes(), {}, {}, header, mapper_config_.voxel_size_m, ++sequence_, true);
  empty.session = session_;
  mesh_update_pub_.publish(empty);
  NODELET_INFO("stereo_fusion: map reset");
  return true;
}

void FusionNodelet::reapplyClearsLocked(const QueuedFrame& f, const ros::Time& stamp, MeshTiming timing) {
  bool recleared = false;
  for (const ClearedRegion& cleared : cleared_regions_) {
    if (f.clear_epoch >= cleared.clear_epoch && stamp >= cleared.stamp) continue;
    const ClearResult again = mapper_->clearRegion(cleared.region, timing);
    recleared = recleared || again.voxels_cleared > 0;
  }
  if (recleared) ++frames_recleared_;
  // Frames come in arrival order and (with require_increasing_timestamps) in stamp order: a clear
  // this frame does not predate, no later frame predates either.
  while (!cleared_regions_.empty() && f.clear_epoch >= cleared_regions_.front().clear_epoch &&
         stamp >= cleared_regions_.front().stamp)
    cleared_regions_.pop_front();
}

template <typename Response>
bool FusionNodelet::clearRegion(const MapRegion& region, Response* res) {
  {
    std::lock_guard<std::mutex> lock(map_mutex_);
    const std::string invalid = region.validate();
    if (!invalid.empty()) {
      res->success = false;
      res->message = invalid + " (the map is unchanged)";
      NODELET_ERROR("stereo_fusion: clear: %s", res->message.c_str());
      return true;
    }
    ClearedRegion cleared;
    {
      std::lock_guard<std::mutex> queue_lock(queue_mutex_);
      cleared.clear_epoch = ++clear_epoch_;
    }
    cleared.stamp = ros::Time::now();
    cleared.region = region;
    if (cleared_regions_.size() >= kMaxClearedRegions) {
      // Frames from before the oldest clear could refill its region; counted on /diagnostics.
      cleared_regions_.pop_front();
      ++clears_forgotten_;
    }
    cleared_regions_.push_back(cleared);
    window_->clearRegion(region, cleared.stamp.toSec());  // a loop closure's re-fusion repeats it
    const ClearResult result = mapper_->clearRegion(region, MeshTiming::kDeferred);
    clear_log_.emplace_back(++regions_cleared_, region);
    if (clear_log_.size() > kMaxClearedRegions) clear_log_.pop_front();
    res->success = true;
    res->voxels_cleared = result.voxels_cleared;
    res->blocks_changed = result.blocks_changed;
    res->blocks_erased = result.blocks_erased;
    res->message = "cleared " + region.describe() + ": " + std::to_string(result.voxels_cleared) + " voxels, " +
                   std::to_string(result.blocks_erased) + " blocks erased, " + std::to_string(result.blocks_changed) +
                   " changed";
  }
  // The mesh follows now, whatever the publish rate: the caller expects the region gone.
  publishPending(ros::Time(0), true);
  NODELET_INFO("stereo_fusion: %s", res->message.c_str());
  return true;
}

bool FusionNodelet::clearBox(ClearBox::Request& req, ClearBox::Response& res) {
  return clearRegion(MapRegion::box({req.min.x, req.min.y, req.min.z}, {req.max.x, req.max.y, req.max.z}), &res);
}

bool FusionNodelet::clearSphere(ClearSphere::Request& req, ClearSphere::Response& res) {
  return clearRegion(MapRegion::sphere({req.center.x, req.center.y, req.center.z}, req.radius), &res);
}

bool FusionNodelet::saveMap(SaveMap::Request& req, SaveMap::Response& res) {
  const ros::WallTime start = ros::WallTime::now();
  std::vector<uint8_t> bytes;
  double locked_ms = 0.0;
  {
    // Only the copy of the blocks holds the map (at memory speed, 0.3–7 KB per block); the
    // checksums, the write and the fsync (seconds for a large map on a robot's flash) run while
    // frames are fused.
    std::lock_guard<std::mutex> lock(map_mutex_);
    const ros::WallTime locked = ros::WallTime::now();
    bytes = mapper_->encodeMap();
    res.blocks = mapper_->map().blockCount();
    locked_ms = (ros::WallTime::now() - locked).toSec() * 1e3;
  }
  std::string error;
  res.success = writeMapFileBytes(req.path, &bytes, &error);
  const double total_ms = (ros::WallTime::now() - start).toSec() * 1e3;
  res.message = res.success ? "saved " + std::to_string(res.blocks) + " blocks to " + req.path + " (map held " +
                                  std::to_string(static_cast<long>(locked_ms)) + " ms, " +
                                  std::to_string(static_cast<long>(total_ms)) + " ms in all)"
                            : error;
  if (res.success)
    NODELET_INFO("stereo_fusion: save_map: %s", res.message.c_str());
  else
    NODELET_ERROR("stereo_fusion: save_map: %s", res.message.c_str());
  return true;
}

bool FusionNodelet::loadMap(LoadMap::Request& req, LoadMap::Response& res) {
  // Read and check the file while frames are still fused into the current map; only the swap
  // and the re-meshing hold it.
  const MapperConfig& config = mapper_->config();  // fixed at start-up: safe to read unlocked
  BlockOctree loaded(config.blockSizeM());
  MapFileInfo info;
  std::string error;
  res.success = readMapFile(req.path, config, &loaded, &info, &error);
  std::lock_guard<std::mutex> lock(map_mutex_);
  if (!res.success) {
    res.blocks = mapper_->map().blockCount();
    res.message = error + " (the current map is unchanged)";
    NODELET_ERROR("stereo_fusion: load_map: %s", res.message.c_str());
    return true;
  }
  const MeshChanges changes = mapper_->adoptMap(&loaded, info);
  res.blocks = mapper_->map().blockCount();
  startMapEpochLocked();
  cleared_regions_.clear();
  dropCorrectionStateLocked();
  if (node_config_.loop_closure_max_frames > 0) {
    // The loaded map is the base a later correction re-fuses the new frames over: it holds
    // voxels, not frames, so it is not moved itself.
    std::vector<uint8_t> base = mapper_->encodeMap();
    sealMapFile(&base);
    std::string why;
    if (!window_->clear(base, &why)) NODELET_ERROR("stereo_fusion: load_map: the loop closure base: %s", why.c_str());
  }
  path_.poses.clear();
  frame_ms_.clear();
  mesh_pass_ms_.clear();
  publishFullLocked(changes.removed);
  res.message = "loaded " + std::to_string(res.blocks) + " blocks from " + req.path;
  NODELET_INFO("stereo_fusion: load_map: %s", res.message.c_str());
  return true;
}

void FusionNodelet::publishFullLocked(const std::vector<BlockKey>& removed) {
  mapper_->takeMeshChanges(publisher_);  // a full update replaces whatever was pending
  unpublished_stamps_.clear();
  std_msgs::Header header;
  header.frame_id = node_config_.world_frame;
  header.stamp = ros::Time::now();
  std::vector<BlockKey> all;
  for (const auto& [key, sub] : mapper_->mesh().submeshes()) all.push_back(key);
  std::sort(all.begin(), all.end());
  // A full update replaces whatever a subscriber held; markers: drop the gone blocks, draw all.
  MeshUpdate update = toMeshUpdate(mapper_->mesh().submeshes(), all, {}, header, mapper_config_.voxel_size_m,
                                   ++sequence_, true, node_config_.mesh_encoding, &mapper_->textures());
  update.session = session_;
  mesh_update_pub_.publish(update);
  if (node_config_.publish_markers)
    markers_pub_.publish(markers_.build(mapper_->mesh().submeshes(), all, removed, header));
}

void FusionNodelet::diagnose(diagnostic_updater::DiagnosticStatusWrapper& status) {
  const double elapsed = std::max(1e-3, (ros::WallTime::now() - started_).toSec());
  const uint64_t disparities_in = disparities_in_.load(), matched = received_.load();
  const uint64_t held_back = dropped_sync_duplicate_.load();
  const uint64_t unmatched = disparities_in > matched + held_back ? disparities_in - matched - held_back : 0;
  // A disparity whose image has not arrived yet is unmatched for a moment in normal operation:
  // only more than the synchroniser's queue can hold is surely lost.
  const bool lost_in_sync = unmatched > static_cast<uint64_t>(node_config_.sync_queue_size);
  const uint64_t dropped = dropped_queue_ + dropped_tf_ + dropped_bad_input_ + dropped_backwards_ +
                           dropped_duplicate_ + dropped_pose_jump_ + dropped_timestamp_jump_ +
                           dropped_allocation_budget_ + dropped_incoherent_ + dropped_bad_stamp_ + dropped_superseded_ + held_back +
                           (lost_in_sync ? unmatched : 0);
  std::vector<double> lat;
  // lookup, fusion, total per frame; meshing, texture per meshing pass.
  std::vector<double> stages[5];
  size_t blocks = 0, memory = 0, awaiting_mesh = 0;
  uint64_t mesh_passes = 0;
  {
    std::lock_guard<std::mutex> lock(map_mutex_);
    lat.assign(latencies_s_.begin(), latencies_s_.end());
    for (const auto& s : frame_ms_) {
      stages[0].push_back(s[0]);
      stages[1].push_back(s[1]);
      stages[4].push_back(s[2]);
    }
    for (const auto& s : mesh_pass_ms_) {
      stages[2].push_back(s[0]);
      stages[3].push_back(s[1]);
    }
    mesh_passes = mesh_passes_;
    awaiting_mesh = mapper_->blocksAwaitingMesh();
    blocks = mapper_->map().blockCount();
    memory = mapper_->memoryBytes();
  }
  auto pct = [&](double p) { return percentile(lat, p); };
  if (received_ > 0 && fused_ == 0)
    status.summary(diagnostic_msgs::DiagnosticStatus::ERROR, "no frame fused yet; see the drop counters");
  else if (dropped > 0)
    status.summary(diagnostic_msgs::DiagnosticStatus::WARN, "frames dropped; see the counters");
  else
    status.summary(diagnostic_msgs::DiagnosticStatus::OK, "fusing");
  // disparities received = frames fused + every "dropped:" counter + frames in the queue / worker.
  status.add("disparities received", disparities_in);
  // Lost before they reached the node (transport queues, the driver): not part of the sum above.
  status.add("disparities missed upstream (header.seq gaps)", disparities_missed_.load());
  status.add("frames received", matched);
  status.add("dropped: not synchronised (no matching image / camera_info yet)", unmatched);
  status.add("frames fused", fused_.load());
  status.add("input rate (Hz)", received_ / elapsed);
  status.add("dropped: queue full", dropped_queue_.load());
  status.add("dropped: tf timeout", dropped_tf_.load());
  status.add("dropped: bad input", dropped_bad_input_.load());
  status.add("dropped: timestamp backwards", dropped_backwards_.load());
  status.add("dropped: duplicate frame", dropped_duplicate_.load());
  status.add("dropped: duplicate stamp before synchronisation", held_back);
  status.add("ignored: image / camera_info repeating a stamp", ignored_duplicate_parts_.load());
  status.add("dropped: pose jump", dropped_pose_jump_.load());
  status.add("dropped: timestamp jump", dropped_timestamp_jump_.load());
  status.add("dropped: allocation budget", dropped_allocation_budget_.load());
  status.add("dropped: incoherent disparity", dropped_incoherent_.load());
  status.add("pixels rejected: speckles", pixels_rejected_speckle_.load());
  status.add("pixels rejected: near side of depth edges", pixels_rejected_edge_.load());
  status.add("dropped: bad timestamp", dropped_bad_stamp_.load());
  status.add("re-anchored (relocalisation or clock reset)", reanchored_.load());
  status.add("dropped: superseded by reset/load", dropped_superseded_.load());
  status.add("regions cleared (~clear_box, ~clear_sphere)", regions_cleared_.load());
  // Frames from before a clear whose fusion refilled the region, which was then cleared again.
  status.add("frames fused from before a clear (region cleared again)", frames_recleared_.load());
  status.add("clears forgotten (more than 256 pending)", clears_forgotten_.load());
  {
    std::lock_guard<std::mutex> lock(map_mutex_);
    status.add("loop closure: frames kept", window_->size());
    status.add("loop closure: kept frames (MB)", window_->bytes() / 1048576.0);
    // Older frames are fused into the base and no longer moved by a correction.
    status.add("loop closure: frames beyond the window (frozen)", window_->framesFrozen());
    status.add("loop closure: last correction, frames fused again", last_correction_frames_);
    status.add("loop closure: last correction (ms)", last_correction_ms_);
    status.add("loop closure: last correction, largest move (m)", last_correction_shift_m_);
    status.add("loop closure: last correction, largest turn (deg)", last_correction_deg_);
  }
  status.add("trajectories received", trajectories_received_.load());
  status.add("trajectories rejected", trajectories_rejected_.load());
  status.add("corrections applied", corrections_applied_.load());
  status.add("corrections superseded by a newer trajectory", corrections_superseded_.load());
  status.add("latency p50 (s)", pct(0.5));
  status.add("latency p99 (s)", pct(0.99));
  const char* names[5] = {"lookup", "fusion", "meshing", "texture", "total"};
  for (int k = 0; k < 5; ++k) {
    status.add(std::string(names[k]) + " p50 (ms)", percentile(stages[k], 0.5));
    status.add(std::string(names[k]) + " p99 (ms)", percentile(stages[k], 0.99));
  }
  status.add("timings", "lookup, fusion, total: per frame; meshing, texture: per meshing pass");
  status.add("meshing passes", mesh_passes);
  status.add("block changes awaiting meshing", awaiting_mesh);
  status.add("blocks", blocks);
  status.add("blocks evicted", blocks_evicted_.load());
  status.add("memory (MB)", memory / 1048576.0);
}

}  // namespace stereo_fusion

PLUGINLIB_EXPORT_CLASS(stereo_fusion::FusionNodelet, nodelet::Nodelet)
