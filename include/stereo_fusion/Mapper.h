#pragma once
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "stereo_fusion/MapperConfig.h"
#include "stereo_fusion/integration/BlockLookup.h"
#include "stereo_fusion/integration/StereoFrame.h"
#include "stereo_fusion/integration/SurfaceFuser.h"
#include "stereo_fusion/map/BlockOctree.h"
#include "stereo_fusion/mesh/MeshStore.h"
#include "stereo_fusion/mesh/TextureStore.h"
#include "stereo_fusion/util/ThreadPool.h"

namespace stereo_fusion {

/// What integrate() did with one frame.
struct IntegrationResult {
  bool accepted = false;  ///< false: the frame was rejected and the map is unchanged
  std::string error;      ///< why it was rejected
  double lookup_ms = 0.0;
  double fusion_ms = 0.0;
  LookupStats lookup;
  FusionStats fusion;
  /// Submeshes changed / removed by this frame (empty when meshing is disabled).
  MeshChanges mesh;
  /// Blocks whose voxels changed in this frame, sorted by key (the meshing stage's input).
  std::vector<BlockKey> updated_blocks;
  /// What the texture pass did (all zero unless texture = patches).
  TextureStats texture;
};

/// The ROS-free mapping pipeline: integrate(frame) = validate → lookup → fusion → meshing.
class Mapper {
 public:
  /// Throws std::invalid_argument listing every invalid parameter.
  explicit Mapper(const MapperConfig& config);

  /// Fuses one frame. A frame that fails validateFrame() is rejected with the reason and
  /// leaves the map untouched.
  IntegrationResult integrate(const StereoFrame& frame);

  const BlockOctree& map() const { return octree_; }
  /// The incrementally maintained mesh, one submesh per block.
  const MeshStore& mesh() const { return mesh_store_; }
  /// The whole mesh, submeshes welded into one (for export).
  TriangleMesh extractMesh() const { return weldSubmeshes(mesh_store_.submeshes()); }
  /// Re-meshes every block from scratch (also what a disabled incremental mesher catches up with).
  MeshChanges rebuildMesh();
  /// Texture patches of the submeshes (empty unless texture = patches).
  const TextureStore& textures() const { return texture_store_; }
  const MapperConfig& config() const { return config_; }
  /// Frames accepted so far.
  uint64_t framesIntegrated() const { return frames_integrated_; }
  /// Drops the whole map.
  void reset();

 private:
  MapperConfig config_;
  ThreadPool pool_;
  BlockOctree octree_;
  BlockLookup lookup_;
  SurfaceFuser fuser_;
  MeshStore mesh_store_;
  TextureStore texture_store_;
  uint64_t frames_integrated_ = 0;
  std::vector<VoxelBlock*> queue_;    // reused across frames
  std::vector<VoxelBlock*> updated_;  // reused across frames
};

}  // namespace stereo_fusion
