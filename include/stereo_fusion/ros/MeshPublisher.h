#pragma once
// The node's outputs of the map: ~mesh_update (MeshUpdate), ~mesh_markers (rviz), ~camera_path,
// ~frustum and ~block_bounds; the mesh is brought up to date at mesh_publish_rate_hz.
#include <nav_msgs/Path.h>
#include <ros/ros.h>
#include <stereo_fusion/MeshUpdate.h>

#include <memory>
#include <optional>
#include <vector>

#include "stereo_fusion/ros/MarkerBacklog.h"
#include "stereo_fusion/ros/MarkerSender.h"
#include "stereo_fusion/ros/MeshMessages.h"
#include "stereo_fusion/ros/NodeStats.h"
#include "stereo_fusion/ros/RosParameters.h"
#include "stereo_fusion/ros/SendThread.h"
#include "stereo_fusion/session/MappingSession.h"
#include "stereo_fusion/session/OutputCadence.h"

namespace stereo_fusion {

/// Every member is touched only with the session's map lock held (inside read(), withMap() or
/// the session's MapReplaced listener). Its place in the mesh's change log is the session's
/// MeshSubscription: it follows the map across a correction's swap. When to mesh and send is
/// the OutputCadence's. The markers are built and sent on a thread of their own (MarkerSender).
class MeshPublisher {
 public:
  MeshPublisher(ros::NodeHandle& private_nh, const NodeConfig& node, MappingSession* session,
                OutputCadence* cadence, NodeStats* stats);

  /// A frame was fused (path, frustum, latency): call with the map lock held.
  void frameFusedLocked(const StereoFrame& frame, const std_msgs::Header& header);
  /// Brings the mesh up to date and sends what changed, at most at
  /// mesh_publish_rate_hz unless `force`; while `frames_waiting` (to be fused), a pass due waits
  /// for them, up to a period. `stamp` 0: the newest fused frame's.
  void publishPending(const ros::Time& stamp, bool force, bool frames_waiting = false);
  /// Meshes what fusion changed since the last pass (map lock held; save_mesh).
  void catchUpLocked(MapAccess& map);
  /// The whole mesh as one full MeshUpdate whose sequence the published updates continue;
  /// nullopt if the map stayed busy (MappingSession::tryWithMap()).
  std::optional<MeshUpdate> tryFullMesh();
  /// The session's listener: the map was replaced wholesale; sends it whole.
  void onMapReplaced(const MapReplaced& replaced);

 private:
  void publishPendingLocked(MapAccess& map, const ros::Time& stamp, bool force,
                            bool frames_waiting);
  void publishFullLocked(MapAccess& map, const std::vector<BlockKey>& removed);
  /// Hands the marker backlog (or every block, for a new subscriber) to the sender at
  /// markers_publish_rate_hz, once it is idle, unless `force`.
  void publishMarkersLocked(const Mapper& map, bool force);
  nav_msgs::Path correctedPathLocked() const;
  /// Publishes `update` on the send thread, after the updates handed over before it.
  void sendUpdate(MeshUpdate&& update);

  const NodeConfig& node_;
  MappingSession* session_;
  OutputCadence* cadence_;  // meshing, ~mesh_update and markers (map lock)
  NodeStats* stats_;
  ros::Publisher mesh_update_pub_, markers_pub_, path_pub_, frustum_pub_, block_bounds_pub_;
  /// Its place in the map's log of mesh changes: what it has not sent yet.
  MeshSubscription subscription_{};
  std::unique_ptr<MarkerSender> marker_sender_;
  bool markers_full_pending_ = false;
  MarkerBacklog marker_backlog_;     // the mesh's changes ~mesh_markers has not sent yet
  std_msgs::Header markers_header_;  // of the newest mesh flush: the markers' stamp
  uint64_t sequence_ = 0;
  /// MeshUpdate::session of this run (wall clock at start, ns): tells subscribers that a
  /// restarted nodelet's sequence numbers begin again.
  uint64_t session_id_ = 0;
  static constexpr size_t kMaxPathPoses = 4000;  // ~/camera_path length bound
  nav_msgs::Path path_;
  PoseCorrection correction_;  // the latest applied, for the path
  std::vector<ros::Time> unpublished_stamps_;
  /// ~mesh_update's messages are serialised (1.9 ms per 10 Hz update at 1 cm) and sent here, in
  /// order. Last: stopped before the members above go.
  SendThread update_sender_;
};

}  // namespace stereo_fusion
