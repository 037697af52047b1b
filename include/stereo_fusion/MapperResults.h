#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "stereo_fusion/integration/FramePipeline.h"
#include "stereo_fusion/layers/MeshLayer.h"
#include "stereo_fusion/planning/FreeSpaceRecorder.h"

namespace stereo_fusion {

/// When Mapper::integrate() brings the mesh up to date.
enum class MeshTiming {
  kNow,       ///< right after the frame (updateMesh()): the mesh always matches the map
  kDeferred,  ///< later, by the caller's updateMesh(): the frame's changes wait in the change log
};

/// What Mapper::integrate() did with one frame: the pipeline's stages (FrameStageStats), then
/// the map host's and the layers' work.
struct IntegrationResult : FrameStageStats {
  /// The layers' per-frame hooks (the planning layer records the space the frame saw empty),
  /// included in nothing else.
  double free_space_ms = 0.0;
  FreeSpaceStats free_space;
  /// Paging (max_map_memory_mb): bringing back the blocks the frame reaches before it, and
  /// paging out what exceeds the cap after it; included in nothing else.
  double paging_ms = 0.0;
  double page_in_ms = 0.0;  ///< the part of paging_ms before the frame
  uint64_t blocks_paged_in = 0;
  uint64_t blocks_paged_out = 0;
  /// With a cap: the map's memory once the frame fused and meshed, before the page-out after it.
  size_t map_memory_bytes = 0;
  /// A layer (the planning layer) was updated after this frame because its changes had piled
  /// up (kMaxPendingLayerChanges), taking planning_catch_up_ms.
  bool planning_catch_up = false;
  double planning_catch_up_ms = 0.0;
  /// Blocks whose voxels changed in this frame and were kept, sorted by key.
  std::vector<BlockKey> updated_blocks;
  /// Blocks evicted after this frame by the memory bound (max_blocks,
  /// max_distance_from_camera_m), sorted by key.
  std::vector<BlockKey> evicted_blocks;
  /// With MeshTiming::kNow (and meshing enabled): what the meshing pass after this frame
  /// changed (the submeshes of evicted blocks among the removed) and its texture pass.
  /// Empty with MeshTiming::kDeferred.
  MeshChanges mesh;
  TextureStats texture;
};

/// What Mapper::clearRegion() did.
struct ClearResult {
  bool accepted =
      false;  ///< false: the region was invalid (`error` says why) and the map is unchanged
  std::string error;
  uint64_t blocks_visited = 0;  ///< blocks of the map the region reaches
  uint64_t blocks_changed = 0;  ///< blocks that lost observed voxels and keep some
  uint64_t blocks_erased = 0;   ///< blocks left without an observed voxel, erased
  uint64_t voxels_cleared = 0;  ///< observed voxels made unobserved, all levels
  double clear_ms = 0.0;
  /// As IntegrationResult::mesh and ::texture: with MeshTiming::kNow, what the meshing pass
  /// changed.
  MeshChanges mesh;
  TextureStats texture;
};

}  // namespace stereo_fusion
