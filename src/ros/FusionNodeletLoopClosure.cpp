// FusionNodelet's loop closures: a SLAM's corrected trajectory in, the kept frames fused again
// at their corrected poses on a thread of their own while fusion goes on, then the maps swapped.
#include <tf2_eigen/tf2_eigen.h>

#include <algorithm>
#include <set>

#include "stereo_fusion/ros/FusionNodelet.h"
#include "stereo_fusion/util/Timer.h"

namespace stereo_fusion {

namespace {
// A trajectory that moves no kept frame by more than this is taken as it is, without re-fusion.
constexpr double kMinCorrectionM = 0.002;
constexpr double kMinCorrectionDeg = 0.05;
}  // namespace

void FusionNodelet::onTrajectory(const nav_msgs::Path::ConstPtr& path) {
  ++trajectories_received_;
  auto reject = [&](const std::string& why) {
    ++trajectories_rejected_;
    NODELET_ERROR_THROTTLE(5.0, "stereo_fusion: trajectory ignored (%llu so far): %s",
                           static_cast<unsigned long long>(trajectories_rejected_.load()), why.c_str());
  };
  if (!path->header.frame_id.empty() && path->header.frame_id != node_config_.world_frame)
    return reject("it is in frame '" + path->header.frame_id + "', the map in '" + node_config_.world_frame + "'");
  std::string camera_frame;
  PendingTrajectory pending;
  {
    std::lock_guard<std::mutex> lock(map_mutex_);
    camera_frame = camera_frame_;
    pending.fused_until_s = window_->size() > 0 ? window_->frames().back().timestamp_s : 0.0;
  }
  if (window_->maxFrames() == 0) return reject("loop_closure_max_frames is 0: no frame is kept to correct");
  if (camera_frame.empty()) return reject("no frame has been fused yet");
  // T_world_camera = T_world_trajectory · T_trajectory_camera (the identity for the camera's own poses).
  Eigen::Isometry3d T_trajectory_camera = Eigen::Isometry3d::Identity();
  if (!node_config_.trajectory_frame.empty() && node_config_.trajectory_frame != camera_frame) {
    try {
      T_trajectory_camera = tf2::transformToEigen(
          tf_buffer_->lookupTransform(node_config_.trajectory_frame, camera_frame, ros::Time(0)));
    } catch (const tf2::TransformException& e) {
      return reject(std::string("no transform ") + node_config_.trajectory_frame + " <- " + camera_frame + ": " + e.what());
    }
  }
  for (const geometry_msgs::PoseStamped& p : path->poses) {
    Eigen::Isometry3d T_world_trajectory;
    tf2::fromMsg(p.pose, T_world_trajectory);
    if (!T_world_trajectory.matrix().allFinite()) return reject("a pose is not finite");
    pending.poses.push_back({p.header.stamp.toSec(), T_world_trajectory * T_trajectory_camera});
  }
  if (pending.poses.empty()) return reject("it holds no pose");
  sortByStamp(&pending.poses);
  {
    std::lock_guard<std::mutex> lock(correction_mutex_);
    pending_trajectory_ = std::move(pending);  // a newer trajectory supersedes one not yet applied
  }
  correction_cv_.notify_one();
}

void FusionNodelet::correctionLoop() {
  while (true) {
    PendingTrajectory trajectory;
    {
      std::unique_lock<std::mutex> lock(correction_mutex_);
      correction_cv_.wait(lock, [this] { return correction_stopping_ || pending_trajectory_.has_value(); });
      if (correction_stopping_) return;
      trajectory = std::move(*pending_trajectory_);
      pending_trajectory_.reset();
    }
    Timer timer;
    // The snapshot: the kept frames (their images are shared, not copied), the base and the clears.
    std::vector<StereoFrame> frames;
    std::vector<uint8_t> base;
    std::vector<TimedRegion> clears;
    PoseCorrection correction;
    uint64_t snapshot_added = 0, snapshot_clears = 0;
    const uint64_t generation = correction_generation_.load();
    {
      std::lock_guard<std::mutex> lock(map_mutex_);
      const std::vector<StampedPose> originals = window_->originalPoses();
      correction = PoseCorrection(originals, trajectory.poses, trajectory.fused_until_s);
      frames.assign(window_->frames().begin(), window_->frames().end());
      double shift_m = 0.0, turn_deg = 0.0;
      correctionMagnitude(originals, correction, &shift_m, &turn_deg);
      if (correction.empty() || (shift_m < kMinCorrectionM && turn_deg < kMinCorrectionDeg)) {
        // Nothing kept moves (or no pose matched a kept frame): frames leaving the window still
        // take this correction.
        window_->setCorrection(correction);
        correction_ = correction;
        continue;
      }
      last_correction_shift_m_ = shift_m;
      last_correction_deg_ = turn_deg;
      base = window_->baseBytes();
      clears = window_->clears();
      snapshot_added = window_frames_added_;
      snapshot_clears = regions_cleared_.load();
    }
    NODELET_INFO("stereo_fusion: trajectory of %zu poses moves the kept frames by up to %.3f m / %.2f deg: "
                 "fusing %zu frames again",
                 trajectory.poses.size(), last_correction_shift_m_, last_correction_deg_, frames.size());
    auto cancelled = [&] {
      std::lock_guard<std::mutex> lock(correction_mutex_);
      return correction_stopping_ || pending_trajectory_.has_value() || correction_generation_.load() != generation;
    };
    std::string error;
    std::unique_ptr<Mapper> rebuilt = refuseWindow(mapper_config_, base, frames, correction, cancelled, nullptr, &error, clears);
    if (!rebuilt) {
      if (error == "cancelled") ++corrections_superseded_;
      else NODELET_ERROR("stereo_fusion: the correction failed, the map is unchanged: %s", error.c_str());
      continue;
    }
    // Catch up with the frames fused meanwhile, a batch at a time outside the lock; the swap
    // happens under the lock once none is left, so no frame is missed.
    size_t refused = frames.size();
    bool dropped = false;
    while (true) {
      std::vector<StereoFrame> newer;
      {
        std::lock_guard<std::mutex> lock(map_mutex_);
        if (correction_generation_.load() != generation) {
          dropped = true;  // a reset or load_map replaced the map meanwhile
          break;
        }
        const uint64_t missing = window_frames_added_ - snapshot_added;
        if (missing == 0) {
          // Regions cleared while the frames were fused again.
          for (const auto& [number, region] : clear_log_)
            if (number > snapshot_clears) rebuilt->clearRegion(region, MeshTiming::kDeferred);
          rebuilt->updateMesh();
          last_correction_frames_ = refused;
          adoptCorrectedMapLocked(std::move(rebuilt), correction);
          last_correction_ms_ = timer.elapsedMs();
          break;
        }
        const size_t take = static_cast<size_t>(std::min<uint64_t>(missing, window_->size()));
        newer.assign(window_->frames().end() - take, window_->frames().end());
        snapshot_added = window_frames_added_;
      }
      for (const StereoFrame& original : newer) rebuilt->integrate(correction.corrected(original), MeshTiming::kDeferred);
      refused += newer.size();
    }
    if (dropped) continue;
    ++corrections_applied_;
    NODELET_INFO("stereo_fusion: correction applied: %zu frames fused again in %.0f ms", refused, last_correction_ms_);
  }
}

void FusionNodelet::adoptCorrectedMapLocked(std::unique_ptr<Mapper> rebuilt, const PoseCorrection& correction) {
  std::set<BlockKey> kept;
  for (const auto& [key, sub] : rebuilt->mesh().submeshes()) kept.insert(key);
  std::vector<BlockKey> removed;
  for (const auto& [key, sub] : mapper_->mesh().submeshes())
    if (!kept.count(key)) removed.push_back(key);
  std::sort(removed.begin(), removed.end());
  publisher_ = rebuilt->subscribeToMeshChanges("mesh_update publisher");
  mapper_ = std::move(rebuilt);
  window_->setCorrection(correction);
  correction_ = correction;
  // One full update: cheaper to build than a diff of every submesh, and a correction moves most.
  publishFullLocked(removed);
  if (node_config_.publish_path) path_pub_.publish(correctedPathLocked());
}

nav_msgs::Path FusionNodelet::correctedPathLocked() const {
  if (correction_.empty()) return path_;
  nav_msgs::Path corrected = path_;
  for (geometry_msgs::PoseStamped& p : corrected.poses) {
    Eigen::Isometry3d T;
    tf2::fromMsg(p.pose, T);
    p.pose = tf2::toMsg(correction_.corrected(p.header.stamp.toSec(), T));
  }
  return corrected;
}

void FusionNodelet::dropCorrectionStateLocked() {
  ++correction_generation_;
  window_->clear();
  correction_ = PoseCorrection();
  {
    std::lock_guard<std::mutex> lock(correction_mutex_);
    pending_trajectory_.reset();
  }
}

}  // namespace stereo_fusion
