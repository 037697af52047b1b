#pragma once
// One robot's ~mesh_update stream followed on the base station: a copy of that robot's global
// mesh, kept in the robot's own frame, repaired from its ~get_full_mesh after a late join or a
// missed update, saved and drawn locally. The MeshAssembler nodelet holds one per robot.

#include <diagnostic_updater/diagnostic_updater.h>
#include <ros/ros.h>
#include <stereo_fusion/GetFullMesh.h>
#include <stereo_fusion/MeshUpdate.h>
#include <stereo_fusion/SaveMesh.h>

#include <cstdint>
#include <mutex>
#include <string>
#include <unordered_map>

#include "stereo_fusion/mesh/SubMesh.h"
#include "stereo_fusion/mesh/TexturePatch.h"
#include "stereo_fusion/ros/MeshMessages.h"

namespace stereo_fusion {

/// How one robot's stream is followed (the MeshAssembler's parameters of the same names).
struct RobotMeshAssemblyConfig {
  bool publish_markers = true;
  double full_mesh_timeout_s = 5.0;                ///< (0, 600]
  MeshEncoding encoding = MeshEncoding::kFloat32;  ///< of its own ~get_full_mesh
};

/// In (on `inputs`): topic `mesh_update`, service client `get_full_mesh`. Out (on `outputs`):
/// `mesh_markers` (in the robot's frame, as the update's header says), services `save_mesh` and
/// `get_full_mesh`. Updates are applied in sequence order; a first update with no base mesh, a
/// gap in the sequence numbers or a new session (the robot's nodelet restarted and counts from 1
/// again) makes it fetch the whole mesh and continue from that sequence. A full update older
/// than the mesh held (same session) is ignored.
class RobotMeshAssembly {
 public:
  using Mesh = std::unordered_map<BlockKey, SubMesh, BlockKeyHash>;

  /// `label` names the robot in logs ("" for the single-robot assembler). Callbacks run on
  /// `inputs`' and `outputs`' callback queues; the object must outlive them (the nodelet holds
  /// it until it is destroyed).
  RobotMeshAssembly(const std::string& label, ros::NodeHandle inputs, ros::NodeHandle outputs,
                    const RobotMeshAssemblyConfig& config);

  /// The mesh held and the frame it is in (the robot's world frame, from its updates; empty
  /// before the first), copied under the lock.
  void snapshot(Mesh* mesh, std::string* frame_id) const;
  /// Blocks held.
  size_t blocks() const;
  /// The status of this robot's stream (a diagnostic_updater task).
  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& status);

 private:
  void onUpdate(const MeshUpdate::ConstPtr& update);
  /// Replaces the mesh by the robot's full mesh; false (mesh kept, not synced) when the service
  /// is unavailable or the reply is malformed.
  bool fetchFullMesh();
  /// Applies `update` and draws what it changed; false for a malformed message.
  bool apply(const MeshUpdate& update);
  bool saveMesh(SaveMesh::Request& req, SaveMesh::Response& res);
  bool getFullMesh(GetFullMesh::Request& req, GetFullMesh::Response& res);

  std::string log_name_;  ///< "mesh_assembler" or "mesh_assembler[robot1]"
  RobotMeshAssemblyConfig config_;
  mutable std::mutex mutex_;  // the queue is single-threaded; this guards against the timer anyway
  Mesh mesh_;
  /// The robot's texture patches (image and UVs only), kept in step with mesh_ by applyMeshUpdate.
  std::unordered_map<BlockKey, TexturePatch, BlockKeyHash> textures_;
  MeshMarkers markers_;
  bool synced_ = false;  ///< mesh_ equals the robot's mesh at last_sequence_
  uint64_t last_sequence_ = 0;
  uint64_t session_ = 0;  ///< MeshUpdate::session of the mesh held
  float voxel_size_m_ = 0.0f;
  std_msgs::Header last_header_;
  uint64_t full_requests_ = 0, gaps_ = 0, malformed_ = 0, restarts_ = 0;

  ros::Subscriber update_sub_;
  ros::ServiceClient full_client_;
  ros::Publisher markers_pub_;
  ros::ServiceServer save_srv_, full_srv_;
  ros::WallTimer join_timer_;
};

}  // namespace stereo_fusion
