#pragma once
// Shared by the tests that compare a base station's assembled mesh with the robot's: a mesh
// fetched through a GetFullMesh service, decoded, and a saved file's bytes.

#include <ros/ros.h>
#include <stereo_fusion/GetFullMesh.h>

#include <fstream>
#include <iterator>
#include <string>
#include <unordered_map>

#include "RosTestSupport.h"
#include "stereo_fusion/ros/MeshMessages.h"

namespace stereo_fusion::test {

using SubmeshMap = std::unordered_map<BlockKey, SubMesh, BlockKeyHash>;

/// The mesh `service` returns, decoded into `mesh`; its sequence in `sequence`, the message in
/// `raw`. False when the call or the decoding fails.
inline bool fetchFullMesh(const std::string& service, SubmeshMap* mesh, uint64_t* sequence,
                          MeshUpdate* raw = nullptr) {
  GetFullMesh srv;
  if (!ros::service::call(service, srv)) return false;
  mesh->clear();
  *sequence = srv.response.mesh.sequence;
  if (raw) *raw = srv.response.mesh;
  return applyMeshUpdate(srv.response.mesh, mesh);
}

/// Fetches the robot's (/stereo_fusion) and the base station's (/mesh_assembler) full meshes
/// until the base station has reached the robot's sequence (true) or `timeout_s` has passed
/// (false; the last fetched meshes and sequences are left for the failure message).
inline bool waitForAssemblerToCatchUp(SubmeshMap* robot, uint64_t* robot_sequence,
                                      SubmeshMap* assembled, uint64_t* assembled_sequence,
                                      double timeout_s) {
  return waitFor(
      [&] {
        return fetchFullMesh("/stereo_fusion/get_full_mesh", robot, robot_sequence) &&
               fetchFullMesh("/mesh_assembler/get_full_mesh", assembled, assembled_sequence) &&
               *assembled_sequence == *robot_sequence;
      },
      timeout_s);
}

/// The bytes of the file at `path` (empty if it cannot be read).
inline std::string readFileBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

}  // namespace stereo_fusion::test
