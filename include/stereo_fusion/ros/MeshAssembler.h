#pragma once
// The base-station side of ~mesh_update: keeps a copy of the robot's global mesh, repairs it
// from ~get_full_mesh after a late join or a missed update, saves it and draws it locally.

#include <diagnostic_updater/diagnostic_updater.h>
#include <nodelet/nodelet.h>
#include <ros/ros.h>
#include <stereo_fusion/GetFullMesh.h>
#include <stereo_fusion/MeshUpdate.h>
#include <stereo_fusion/SaveMesh.h>

#include <cstdint>
#include <memory>
#include <mutex>
#include <unordered_map>

#include "stereo_fusion/mesh/SubMesh.h"
#include "stereo_fusion/ros/CallbackQueueHold.h"
#include "stereo_fusion/ros/MeshMessages.h"

namespace stereo_fusion {

/// Nodelet `stereo_fusion/MeshAssembler` (standalone: `mesh_assembler_node`).
/// In: topic `mesh_update` (remap to the robot's `/stereo_fusion/mesh_update`), service client
/// `get_full_mesh` (remap to `/stereo_fusion/get_full_mesh`).
/// Out: `~mesh_markers` (the same markers as the robot's, built here so rviz on the base station
/// costs the link nothing), services `~save_mesh` (.ply: welded PLY; .obj: OBJ + MTL + atlas
/// PNGs with the robot's texture patches, as the robot's save_mesh) and `~get_full_mesh` (the
/// assembled mesh with its texture patches, the sequence of the last update applied and the
/// robot's session).
/// Updates are applied in sequence order; a first update with no base mesh, a gap in the
/// sequence numbers or a new session (the robot's nodelet restarted and counts from 1 again)
/// makes it fetch the whole mesh and continue from that sequence. A full update older than the
/// mesh held (same session) is ignored.
/// Parameters: `~publish_markers` (bool, default true), `~full_mesh_timeout_s` (double, default 5),
/// `~mesh_encoding` ("float32" | "compact", default float32: encoding of its own ~get_full_mesh;
/// float32 re-sends exactly what it holds, compact would quantise the decoded normals again).
/// Diagnostics: `/diagnostics`, task "mesh assembler", once a second: whether it is in sync, the
/// session and sequence held, blocks, and the counters of full-mesh requests, sequence gaps,
/// robot restarts and malformed updates (WARN while not in sync or once an update was lost).
class MeshAssembler : public nodelet::Nodelet {
 private:
  void onInit() override;
  void onUpdate(const MeshUpdate::ConstPtr& update);
  /// Replaces the mesh by the robot's full mesh; false (mesh kept, not synced) when the service
  /// is unavailable or the reply is malformed.
  bool fetchFullMesh();
  /// Applies `update` and draws what it changed; false for a malformed message.
  bool apply(const MeshUpdate& update);
  bool saveMesh(SaveMesh::Request& req, SaveMesh::Response& res);
  bool getFullMesh(GetFullMesh::Request& req, GetFullMesh::Response& res);
  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& status);

  CallbackQueueHold queues_;  // first: destroyed after everything registered on the queues
  std::mutex mutex_;  // the node handle is single-threaded; this guards against the timer anyway
  std::unordered_map<BlockKey, SubMesh, BlockKeyHash> mesh_;
  /// The robot's texture patches (image and UVs only), kept in step with mesh_ by applyMeshUpdate.
  std::unordered_map<BlockKey, TexturePatch, BlockKeyHash> textures_;
  MeshMarkers markers_;
  bool synced_ = false;  ///< mesh_ equals the robot's mesh at last_sequence_
  uint64_t last_sequence_ = 0;
  uint64_t session_ = 0;                            ///< MeshUpdate::session of the mesh held
  MeshEncoding encoding_ = MeshEncoding::kFloat32;  ///< of ~get_full_mesh
  float voxel_size_m_ = 0.0f;
  std_msgs::Header last_header_;
  uint64_t full_requests_ = 0, gaps_ = 0, malformed_ = 0, restarts_ = 0;
  bool publish_markers_ = true;
  double full_mesh_timeout_s_ = 5.0;

  ros::Subscriber update_sub_;
  ros::ServiceClient full_client_;
  ros::Publisher markers_pub_;
  ros::ServiceServer save_srv_, full_srv_;
  ros::WallTimer join_timer_;
  std::unique_ptr<diagnostic_updater::Updater> diagnostics_;
  ros::WallTimer diagnostics_timer_;
};

}  // namespace stereo_fusion
