#include "stereo_fusion/ros/MeshPublisher.h"

#include <tf2_eigen/tf2_eigen.h>
#include <boost/make_shared.hpp>
#include <visualization_msgs/MarkerArray.h>

#include <algorithm>
#include <iterator>

#include "stereo_fusion/ros/DebugMarkers.h"

namespace stereo_fusion {

namespace {
/// What a full update sends: the map's own submeshes and patches, or with paged-out blocks a
/// copy of every one (max_map_memory_mb).
struct EveryBlock {
  Mapper::PagedMeshParts copy;
  const std::unordered_map<BlockKey, SubMesh, BlockKeyHash>* submeshes;
  const std::unordered_map<BlockKey, TexturePatch, BlockKeyHash>* patches;
  /// `keys`: only these are sent (nullptr: all).
  explicit EveryBlock(const Mapper& map, const std::vector<BlockKey>* keys = nullptr) {
    submeshes = &map.mesh().submeshes();
    patches = &map.textures().patches();
    if (map.pagedOutBlocks() == 0) return;
    if (keys == nullptr) {
      copy = map.wholeMesh();
    } else {
      copy = map.pagedMeshParts(keys);
      if (copy.submeshes.empty()) return;  // none of them paged out
      for (const BlockKey& key : *keys) {
        const auto mesh = submeshes->find(key);
        if (mesh != submeshes->end()) copy.submeshes.insert(*mesh);
        const auto patch = patches->find(key);
        if (patch != patches->end()) copy.patches.insert(*patch);
      }
    }
    submeshes = &copy.submeshes;
    patches = &copy.patches;
  }
};

/// `keys` (sorted) without those in `present` (sorted).
std::vector<BlockKey> withoutKeysOf(const std::vector<BlockKey>& keys,
                                    const std::vector<BlockKey>& present) {
  std::vector<BlockKey> out;
  std::set_difference(keys.begin(), keys.end(), present.begin(), present.end(),
                      std::back_inserter(out));
  return out;
}
}  // namespace

MeshPublisher::MeshPublisher(ros::NodeHandle& pnh, const NodeConfig& node, MappingSession* session,
                             OutputCadence* cadence, NodeStats* stats)
    : node_(node),
      session_(session),
      cadence_(cadence),
      stats_(stats),
      update_sender_("~mesh_update") {
  session_id_ = ros::WallTime::now().toNSec();
  markers_header_.frame_id = node_.world_frame;
  subscription_ = session_->subscribeToMeshChanges("mesh_update publisher");
  mesh_update_pub_ = pnh.advertise<MeshUpdate>("mesh_update", 10);
  // A new rviz gets the whole mesh, not only the blocks that change after it connects.
  markers_pub_ = pnh.advertise<visualization_msgs::MarkerArray>(
      "mesh_markers", 10, [this](const ros::SingleSubscriberPublisher&) {
        session_->read([&](const Mapper&) { markers_full_pending_ = true; });
      });
  marker_sender_ = std::make_unique<MarkerSender>(
      [publisher = markers_pub_](const visualization_msgs::MarkerArray& markers) {
        publisher.publish(markers);
      });
  if (node_.publish_path) path_pub_ = pnh.advertise<nav_msgs::Path>("camera_path", 1, true);
  path_.header.frame_id = node_.world_frame;
  if (node_.publish_frustum)
    frustum_pub_ = pnh.advertise<visualization_msgs::Marker>("frustum", 1, true);
  if (node_.publish_block_bounds)
    block_bounds_pub_ = pnh.advertise<visualization_msgs::Marker>("block_bounds", 1, true);
}

void MeshPublisher::frameFusedLocked(const StereoFrame& frame, const std_msgs::Header& header) {
  unpublished_stamps_.push_back(header.stamp);
  if (node_.publish_path) {
    geometry_msgs::PoseStamped pose;
    pose.header = header;
    pose.header.frame_id = node_.world_frame;
    pose.pose = tf2::toMsg(frame.T_world_camera);
    path_.poses.push_back(pose);
    // Bounded: keep the newest kMaxPathPoses, thinning the older half when full.
    if (path_.poses.size() > kMaxPathPoses) {
      std::vector<geometry_msgs::PoseStamped> thinned;
      for (size_t k = 0; k < path_.poses.size() / 2; k += 2) thinned.push_back(path_.poses[k]);
      thinned.insert(thinned.end(), path_.poses.begin() + path_.poses.size() / 2,
                     path_.poses.end());
      path_.poses.swap(thinned);
    }
    path_.header.stamp = header.stamp;
    if (path_pub_.getNumSubscribers() > 0) path_pub_.publish(correctedPathLocked());
  }
  if (node_.publish_frustum) {
    std_msgs::Header world_header = header;
    world_header.frame_id = node_.world_frame;
    frustum_pub_.publish(
        frustumMarker(frame.camera, frame.T_world_camera, node_.frustum_depth_m, world_header));
  }
}

void MeshPublisher::catchUpLocked(MapAccess& map) {
  if (map.map().blocksAwaitingMesh() == 0) return;
  const MeshPass pass = map.updateMesh();
  stats_->recordMeshPass(pass.mesh.meshing_ms, pass.texture.texture_ms);
  // The planning layer follows at its own rate (PlanningPublisher, planning_publish_rate_hz).
}

void MeshPublisher::publishPending(const ros::Time& stamp, bool force, bool frames_waiting) {
  session_->withMap(
      [&](MapAccess& map) { publishPendingLocked(map, stamp, force, frames_waiting); });
}

void MeshPublisher::publishPendingLocked(MapAccess& access, const ros::Time& stamp, bool force,
                                         bool frames_waiting) {
  const Mapper& map = access.map();
  {
    if (map.blocksAwaitingMesh() == 0 && access.pendingMeshChanges(subscription_) == 0)
      return publishMarkersLocked(map, force);  // the backlog may still wait for its turn
    if (!force) {
      const double now_s = ros::WallTime::now().toSec();
      // A frame waiting in the queue is fused first: this pass then carries it too, where
      // meshing now would make it wait a whole period more (and the queue behind the pass).
      if (!cadence_->meshDue(now_s, frames_waiting)) return publishMarkersLocked(map, force);
      cadence_->meshSent(now_s);
    }
    catchUpLocked(access);
    std_msgs::Header header;
    header.frame_id = node_.world_frame;
    header.stamp =
        stamp.isZero() && !unpublished_stamps_.empty() ? unpublished_stamps_.back() : stamp;
    const BlockChangeLog::Changes pending = access.takeMeshChanges(subscription_);
    const std::vector<BlockKey>& changed = pending.updated;
    const std::vector<BlockKey>& removed = pending.erased;
    const double voxel_size_m = map.config().voxel_size_m;
    // Every flush of changes gets a sequence number, sent or not: a subscriber that was not
    // connected for one sees the gap and asks ~get_full_mesh. Publish only what someone hears.
    boost::shared_ptr<MeshUpdate> update;
    if (!changed.empty() || !removed.empty()) {
      ++sequence_;
      if (mesh_update_pub_.getNumSubscribers() > 0) {
        update = boost::make_shared<MeshUpdate>(
            toMeshUpdate(map.mesh().submeshes(), changed, removed, header, voxel_size_m, sequence_,
                         false, node_.mesh_encoding, &map.textures()));
        update->session = session_id_;
      }
    }
    marker_backlog_.add(changed, removed);
    markers_header_ = header;
    publishMarkersLocked(map, force);
    // Latched and opt-in (debug): published even unheard, so a display ticked later shows it.
    if (node_.publish_block_bounds)
      block_bounds_pub_.publish(
          blockBoundsMarker(map.mesh().submeshes(), 8.0 * voxel_size_m, header));
    // Serialised on the send thread; the frames' latency runs until it is out.
    update_sender_.post([publisher = mesh_update_pub_, update,
                         stamps = std::move(unpublished_stamps_), stats = stats_] {
      if (update) publisher.publish(update);
      const ros::Time now = ros::Time::now();
      for (const ros::Time& t : stamps) stats->recordLatency((now - t).toSec());
    });
    unpublished_stamps_.clear();
  }
}

std::optional<MeshUpdate> MeshPublisher::tryFullMesh() {
  std::optional<MeshUpdate> mesh;
  session_->tryWithMap([&](MapAccess& access) {
    // Frames already fused are in the answer even if their meshing waits for the publish rate:
    // their changes go out as an update first, so the full mesh's sequence covers them.
    publishPendingLocked(access, ros::Time(0), true, false);
    const Mapper& map = access.map();
    std_msgs::Header header;
    header.frame_id = node_.world_frame;
    header.stamp = ros::Time::now();
    // The sequence of the last published update: apply updates with a larger sequence on top.
    const EveryBlock every(map);
    mesh = toMeshUpdate(*every.submeshes, map.submeshKeys(), {}, header, map.config().voxel_size_m,
                        sequence_, true, node_.mesh_encoding, every.patches);
    mesh->session = session_id_;
  });
  return mesh;
}

void MeshPublisher::onMapReplaced(const MapReplaced& replaced) {
  MapAccess& access = replaced.map;  // a correction swapped in a new map: subscription_ follows
  const Mapper& map = access.map();
  correction_ = replaced.correction;
  switch (replaced.change) {
    case MapChange::kReset: {
      path_.poses.clear();
      stats_->clearTimings();
      access.takeMeshChanges(subscription_);  // the empty full update below says it all
      unpublished_stamps_.clear();
      std_msgs::Header header;
      header.frame_id = node_.world_frame;
      header.stamp = ros::Time::now();
      marker_backlog_.clear();
      markers_header_.stamp = ros::Time();
      marker_sender_->sendClear(header);
      MeshUpdate empty = toMeshUpdate(map.mesh().submeshes(), {}, {}, header,
                                      map.config().voxel_size_m, ++sequence_, true);
      empty.session = session_id_;
      sendUpdate(std::move(empty));
      return;
    }
    case MapChange::kLoaded:
      path_.poses.clear();
      stats_->clearTimings();
      publishFullLocked(access, replaced.removed);
      return;
    case MapChange::kCorrected:
      // One full update: cheaper to build than a diff of every submesh, and a correction moves
      // most.
      publishFullLocked(access, replaced.removed);
      if (node_.publish_path) path_pub_.publish(correctedPathLocked());
      return;
    case MapChange::kRecovered: publishFullLocked(access, replaced.removed); return;
  }
}

void MeshPublisher::publishMarkersLocked(const Mapper& map, bool force) {
  if (!node_.publish_markers || markers_pub_.getNumSubscribers() == 0) {
    marker_backlog_.clear();  // a subscriber that connects later gets every block
    return;
  }
  if (marker_backlog_.empty() && !markers_full_pending_) return;
  if (!force && !markers_full_pending_) {
    const double now_s = ros::WallTime::now().toSec();
    if (!cadence_->markersDue(now_s)) return;
    // The previous arrays not out yet: the backlog goes on merging (what must go, queues).
    if (!marker_sender_->idle()) return;
    cadence_->markersSent(now_s);
  }
  std::vector<BlockKey> changed, removed;
  marker_backlog_.take(&changed, &removed);
  if (markers_full_pending_) {
    changed = map.submeshKeys();
    removed = withoutKeysOf(removed, changed);  // removed, then meshed again since
  }
  markers_full_pending_ = false;
  std_msgs::Header header = markers_header_;
  if (header.stamp.isZero()) header.stamp = ros::Time::now();  // no frame fused since a reset
  // A backlog key paged out since its change was taken is read back with the rest.
  const EveryBlock every(map, &changed);
  marker_sender_->send(*every.submeshes, changed, removed, header);
}

void MeshPublisher::publishFullLocked(MapAccess& access, const std::vector<BlockKey>& removed) {
  access.takeMeshChanges(subscription_);  // a full update replaces whatever was pending
  const Mapper& map = access.map();
  unpublished_stamps_.clear();
  std_msgs::Header header;
  header.frame_id = node_.world_frame;
  header.stamp = ros::Time::now();
  const std::vector<BlockKey> all = map.submeshKeys();
  const EveryBlock every(map);
  // A full update replaces whatever a subscriber held; markers: drop the gone blocks, draw all.
  MeshUpdate update = toMeshUpdate(*every.submeshes, all, {}, header, map.config().voxel_size_m,
                                   ++sequence_, true, node_.mesh_encoding, every.patches);
  update.session = session_id_;
  sendUpdate(std::move(update));
  // The full set supersedes the backlog, but not its removals: blocks gone from the mesh
  // before the replacement are in neither `all` nor `removed`, and rviz still draws them.
  std::vector<BlockKey> backlog_changed, gone;
  marker_backlog_.take(&backlog_changed, &gone);
  gone.insert(gone.end(), removed.begin(), removed.end());
  std::sort(gone.begin(), gone.end());
  gone.erase(std::unique(gone.begin(), gone.end()), gone.end());
  markers_header_ = header;
  if (node_.publish_markers) {
    marker_sender_->send(*every.submeshes, all, withoutKeysOf(gone, all), header);
    markers_full_pending_ = false;
  }
}

void MeshPublisher::sendUpdate(MeshUpdate&& update) {
  auto message = boost::make_shared<MeshUpdate>(std::move(update));
  update_sender_.post([publisher = mesh_update_pub_, message] { publisher.publish(message); });
}

nav_msgs::Path MeshPublisher::correctedPathLocked() const {
  if (correction_.empty()) return path_;
  nav_msgs::Path corrected = path_;
  for (geometry_msgs::PoseStamped& p : corrected.poses) {
    Eigen::Isometry3d T;
    tf2::fromMsg(p.pose, T);
    p.pose = tf2::toMsg(correction_.corrected(p.header.stamp.toSec(), T));
  }
  return corrected;
}

}  // namespace stereo_fusion
