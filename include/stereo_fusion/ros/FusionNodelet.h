#pragma once
// The ROS face of stereo_fusion: synchronised DisparityImage + Image + CameraInfo in, pose from
// tf2, fusion and incremental meshing off the subscriber thread, MeshUpdate + rviz markers out.

#include <diagnostic_updater/diagnostic_updater.h>
#include <message_filters/subscriber.h>
#include <message_filters/sync_policies/approximate_time.h>
#include <message_filters/sync_policies/exact_time.h>
#include <message_filters/synchronizer.h>
#include <nav_msgs/Path.h>
#include <nodelet/nodelet.h>
#include <ros/ros.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <std_srvs/Empty.h>
#include <stereo_fusion/ClearBox.h>
#include <stereo_fusion/ClearSphere.h>
#include <stereo_fusion/GetFullMesh.h>
#include <stereo_fusion/LoadMap.h>
#include <stereo_fusion/SaveMap.h>
#include <stereo_fusion/SaveMesh.h>
#include <stereo_msgs/DisparityImage.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>

#include <array>
#include <atomic>
#include <condition_variable>
#include <deque>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <thread>

#include "stereo_fusion/Mapper.h"
#include "stereo_fusion/ros/MeshMessages.h"
#include "stereo_fusion/ros/RosParameters.h"
#include "stereo_fusion/ros/RecentStamps.h"
#include "stereo_fusion/ros/SequenceGaps.h"
#include "stereo_fusion/trajectory/CorrectionWindow.h"

namespace stereo_fusion {

/// Nodelet `stereo_fusion/FusionNodelet`. Topics: `disparity`, `image`, `camera_info`,
/// `trajectory` (a SLAM's corrected poses, nav_msgs/Path: the map follows) in;
/// `~mesh_update`, `~mesh_markers`, `~camera_path`, `~frustum`, `~block_bounds` out. Services:
/// `~save_mesh`, `~reset`, `~get_full_mesh`, `~save_map`, `~load_map`, `~clear_box`,
/// `~clear_sphere`. Every dropped frame is
/// counted by reason (queue full, tf timeout, bad input, timestamp backwards, duplicate, pose
/// jump) and reported on /diagnostics together with rates, latency, map size and blocks
/// evicted by the memory bound.
class FusionNodelet : public nodelet::Nodelet {
 public:
  ~FusionNodelet() override;

 private:
  using DisparityMsg = stereo_msgs::DisparityImage;
  using ImageMsg = sensor_msgs::Image;
  using InfoMsg = sensor_msgs::CameraInfo;
  using ExactPolicy = message_filters::sync_policies::ExactTime<DisparityMsg, ImageMsg, InfoMsg>;
  using ApproxPolicy = message_filters::sync_policies::ApproximateTime<DisparityMsg, ImageMsg, InfoMsg>;

  struct QueuedFrame {
    DisparityMsg::ConstPtr disparity;
    ImageMsg::ConstPtr image;
    InfoMsg::ConstPtr info;
    uint64_t map_epoch = 0;  ///< map_epoch_ when the frame arrived
    uint64_t clear_epoch = 0;  ///< clear_epoch_ when the frame arrived
  };
  /// A region an operator cleared, kept while frames from before the clear may still arrive.
  struct ClearedRegion {
    uint64_t clear_epoch = 0;  ///< clear_epoch_ after the clear: frames that arrived earlier have less
    ros::Time stamp;           ///< ROS time of the clear: frames stamped earlier are from before it
    MapRegion region;
  };

  void onInit() override;
  /// False if a message of `stamp` on that topic already waits in the synchroniser.
  bool passToSync(RecentStamps* stamps, const ros::Time& stamp) {
    std::lock_guard<std::mutex> lock(stamps_mutex_);
    return stamps->pass(stamp.toNSec());
  }
  /// Hands one message to whichever synchroniser runs (it calls onFrame when a set is complete).
  template <int I, typename M>
  void addToSync(const M& msg) {
    if (exact_sync_) exact_sync_->template add<I>(msg);
    if (approx_sync_) approx_sync_->template add<I>(msg);
  }
  void onFrame(const DisparityMsg::ConstPtr& d, const ImageMsg::ConstPtr& i, const InfoMsg::ConstPtr& c);
  void workerLoop();
  void processFrame(const QueuedFrame& frame);
  void publishPending(const ros::Time& stamp, bool force);
  /// Counts one meshing pass and its timings (caller holds map_mutex_).
  void recordMeshPassLocked(double meshing_ms, double texture_ms);
  /// Meshes the blocks fused since the last meshing pass, if any, and counts the pass (caller
  /// holds map_mutex_).
  void catchUpMeshLocked();
  bool saveMesh(SaveMesh::Request& req, SaveMesh::Response& res);
  bool getFullMesh(GetFullMesh::Request& req, GetFullMesh::Response& res);
  bool reset(std_srvs::Empty::Request& req, std_srvs::Empty::Response& res);
  bool saveMap(SaveMap::Request& req, SaveMap::Response& res);
  /// Starts a new map epoch: drops (and counts) the queued frames. Caller holds map_mutex_.
  void startMapEpochLocked();
  bool loadMap(LoadMap::Request& req, LoadMap::Response& res);
  bool clearBox(ClearBox::Request& req, ClearBox::Response& res);
  bool clearSphere(ClearSphere::Request& req, ClearSphere::Response& res);
  /// Clears `region` for ~clear_box / ~clear_sphere and publishes the mesh's changes.
  template <typename Response>
  bool clearRegion(const MapRegion& region, Response* res);
  /// After fusing frame `f` (stamped `stamp`): clears again the regions cleared after it arrived
  /// or after it was taken, so that a frame from before a clear does not refill the region,
  /// and forgets the clears no later frame can predate. Caller holds map_mutex_.
  void reapplyClearsLocked(const QueuedFrame& f, const ros::Time& stamp, MeshTiming timing);
  /// Publishes the whole mesh as a `full` update and redraws the markers (after reset / load).
  /// Caller holds map_mutex_.
  void publishFullLocked(const std::vector<BlockKey>& removed);
  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& status);

  // Loop closures (FusionNodeletLoopClosure.cpp).
  /// A trajectory message: its poses as camera poses, queued for the correction thread.
  void onTrajectory(const nav_msgs::Path::ConstPtr& path);
  /// The correction thread: re-fuses the kept frames at the corrected poses while fusion goes
  /// on, catches up with the frames fused meanwhile, then swaps the maps.
  void correctionLoop();
  /// Swaps in `rebuilt` (caller holds map_mutex_) and publishes it as a full update.
  void adoptCorrectedMapLocked(std::unique_ptr<Mapper> rebuilt, const PoseCorrection& correction);
  /// The fused frames' path with the current correction applied (caller holds map_mutex_).
  nav_msgs::Path correctedPathLocked() const;
  /// Stops a running correction and forgets the kept frames (reset, load_map). Caller holds map_mutex_.
  void dropCorrectionStateLocked();

  NodeConfig node_config_;
  MapperConfig mapper_config_;

  std::mutex map_mutex_;  // guards everything below it up to the queue
  std::unique_ptr<Mapper> mapper_;
  /// The publisher's place in the mapper's log of mesh changes: what it has not sent yet.
  BlockChangeLog::Consumer publisher_ = 0;
  MeshMarkers markers_;
  bool markers_full_pending_ = false;
  uint64_t sequence_ = 0;
  /// MeshUpdate::session of this run (wall clock at onInit, ns): tells subscribers that a
  /// restarted nodelet's sequence numbers begin again.
  uint64_t session_ = 0;
  ros::WallTime last_publish_;
  std::deque<double> latencies_s_;  // frame stamp → publish, the last 1000 frames
  std::deque<std::array<double, 3>> frame_ms_;     // lookup, fusion, total per frame: the last 1000 frames
  std::deque<std::array<double, 2>> mesh_pass_ms_;  // meshing, texture per meshing pass: the last 1000 passes
  uint64_t mesh_passes_ = 0;
  static constexpr size_t kMaxPathPoses = 4000;  // ~/camera_path length bound
  nav_msgs::Path path_;
  std::vector<ros::Time> unpublished_stamps_;

  std::mutex queue_mutex_;
  std::condition_variable queue_cv_;
  std::deque<QueuedFrame> queue_;
  bool stopping_ = false;
  std::thread worker_;

  std::unique_ptr<tf2_ros::Buffer> tf_buffer_;
  std::unique_ptr<tf2_ros::TransformListener> tf_listener_;
  message_filters::Subscriber<DisparityMsg> disparity_sub_;
  message_filters::Subscriber<ImageMsg> image_sub_;
  message_filters::Subscriber<InfoMsg> info_sub_;
  std::unique_ptr<message_filters::Synchronizer<ExactPolicy>> exact_sync_;
  std::unique_ptr<message_filters::Synchronizer<ApproxPolicy>> approx_sync_;
  ros::Publisher mesh_update_pub_, markers_pub_, path_pub_, frustum_pub_, block_bounds_pub_;
  ros::ServiceServer save_srv_, full_srv_, reset_srv_, save_map_srv_, load_map_srv_, clear_box_srv_, clear_sphere_srv_;
  std::unique_ptr<diagnostic_updater::Updater> diagnostics_;
  ros::WallTimer diagnostics_timer_;

  std::atomic<uint64_t> received_{0}, fused_{0}, dropped_queue_{0}, dropped_tf_{0}, dropped_bad_input_{0};
  /// Disparity messages that reached the node; those the synchroniser never matched with an
  /// image and a CameraInfo (or that still wait for them) are disparities_in_ − received_.
  std::atomic<uint64_t> disparities_in_{0};
  std::atomic<uint64_t> disparities_missed_{0};  // gaps in the disparities' header.seq
  SequenceGaps disparity_seq_;
  /// Stamps each topic passed to the synchroniser, not matched yet: the first message of a stamp wins.
  std::mutex stamps_mutex_;
  RecentStamps disparity_stamps_{1}, image_stamps_{1}, info_stamps_{1};
  std::atomic<uint64_t> dropped_sync_duplicate_{0};   // disparities repeating a stamp, held back
  std::atomic<uint64_t> ignored_duplicate_parts_{0};  // images / camera_infos repeating a stamp
  std::atomic<uint64_t> dropped_backwards_{0}, dropped_duplicate_{0}, dropped_pose_jump_{0};
  std::atomic<uint64_t> dropped_timestamp_jump_{0};
  std::atomic<uint64_t> dropped_incoherent_{0};  // disparities agreeing with no neighbour: a broken matcher?
  std::atomic<uint64_t> pixels_rejected_speckle_{0}, pixels_rejected_edge_{0};  // OutlierRejection, fused frames
  std::atomic<uint64_t> dropped_allocation_budget_{0};  // bands reaching more than max_new_blocks_per_frame new blocks
  std::atomic<uint64_t> dropped_bad_stamp_{0};  // stamped 0, or too far ahead of the clock
  std::atomic<uint64_t> reanchored_{0};  // frames the gate accepted as a relocalisation / clock reset
  std::atomic<uint64_t> dropped_superseded_{0};  // arrived before a reset / load_map: not fused into the new map
  /// Bumped (under both queue_mutex_ and map_mutex_) by reset and load_map: a frame that arrived
  /// earlier belongs to the map those replaced.
  std::atomic<uint64_t> map_epoch_{0};
  /// Bumped (under both queue_mutex_ and map_mutex_) by ~clear_box / ~clear_sphere.
  std::atomic<uint64_t> clear_epoch_{0};
  static constexpr size_t kMaxClearedRegions = 256;
  std::deque<ClearedRegion> cleared_regions_;  // guarded by map_mutex_, oldest first
  std::atomic<uint64_t> regions_cleared_{0}, frames_recleared_{0}, clears_forgotten_{0};
  /// The last kMaxClearedRegions clears, numbered by regions_cleared_ after each (guarded by
  /// map_mutex_): what a loop closure's re-fusion that started earlier must clear again.
  std::deque<std::pair<uint64_t, MapRegion>> clear_log_;
  /// A trajectory waiting for the correction thread (the newest supersedes an older one).
  struct PendingTrajectory {
    std::vector<StampedPose> poses;  ///< camera poses in world_frame, by stamp
    double fused_until_s = 0.0;      ///< the newest fused frame's stamp when it arrived
  };
  std::mutex correction_mutex_;
  std::condition_variable correction_cv_;
  std::optional<PendingTrajectory> pending_trajectory_;  // guarded by correction_mutex_
  bool correction_stopping_ = false;                     // guarded by correction_mutex_
  std::thread correction_thread_;
  /// Bumped under map_mutex_ by reset and load_map: a correction started before is dropped.
  std::atomic<uint64_t> correction_generation_{0};
  ros::Subscriber trajectory_sub_;
  std::unique_ptr<CorrectionWindow> window_;  // guarded by map_mutex_
  uint64_t window_frames_added_ = 0;          // guarded by map_mutex_: frames window_ received
  PoseCorrection correction_;                 // guarded by map_mutex_: the latest applied
  std::string camera_frame_;                  // guarded by map_mutex_: the disparity's frame_id
  std::atomic<uint64_t> trajectories_received_{0}, trajectories_rejected_{0}, corrections_applied_{0};
  std::atomic<uint64_t> corrections_superseded_{0};
  double last_correction_ms_ = 0.0;           // guarded by map_mutex_
  size_t last_correction_frames_ = 0;         // guarded by map_mutex_
  double last_correction_shift_m_ = 0.0, last_correction_deg_ = 0.0;  // guarded by map_mutex_
  std::atomic<uint64_t> blocks_evicted_{0};  // by the memory bound, since start (reset and load included)
  ros::WallTime started_;
};

}  // namespace stereo_fusion
