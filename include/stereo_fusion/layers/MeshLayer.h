#pragma once
#include <string>

#include "stereo_fusion/MapperStage.h"
#include "stereo_fusion/layers/MapLayer.h"
#include "stereo_fusion/mesh/MeshStore.h"
#include "stereo_fusion/mesh/TextureStore.h"
#include "stereo_fusion/util/ThreadPool.h"

namespace stereo_fusion {

/// What the mesh layer reads (from the parameter table: StageConfigs).
struct MeshLayerConfig {
  bool enabled = true;    ///< mesh_enabled: false keeps no mesh (rebuildMesh() still makes one)
  bool textured = false;  ///< texture = patches
  MeshingParams meshing;
  TextureParams texture;
};

/// What one meshing pass did.
struct MeshPass {
  /// Submeshes changed / removed by this pass.
  MeshChanges mesh;
  /// What the texture pass did (all zero unless texture = patches).
  TextureStats texture;
  /// Blocks fusion or eviction changed since the previous pass: what this pass meshed around.
  size_t blocks_changed = 0;
};

/// The mesh (one submesh per block, MeshStore) and its texture patches (TextureStore), kept
/// up to date from the map's changes, and the log of the submeshes it changed for its own
/// consumers (the texture pass, publishers).
class MeshLayer final : public MapLayer {
 public:
  MeshLayer(const MeshLayerConfig& config, ThreadPool* pool);

  const char* name() const override { return "mesher"; }
  /// Keeps the frame (its images are shared) for a later texture pass.
  void onFrame(const LayerFrame& frame) override;
  void update(const BlockOctree& map, const BlockChangeLog::Changes& changes) override {
    updateMesh(map, changes, nullptr);
  }
  /// Meshes around `changes` (nothing when disabled) and, textured, textures the changed
  /// submeshes from the latest frame; reports its stages into `stage` when given.
  MeshPass updateMesh(const BlockOctree& map, const BlockChangeLog::Changes& changes,
                      StageScope* stage);
  void rebuild(const BlockOctree& map) override { rebuildMesh(map); }
  /// Re-meshes every block; the stored patches are re-projected onto the new submeshes.
  MeshChanges rebuildMesh(const BlockOctree& map);
  void reset() override;
  /// The loaded map's mesh (the file holds no patches: it starts with vertex colours).
  void adopt(const BlockOctree& map, const MapFileInfo& info) override;
  /// The block's submesh and texture patch go with its page; its mesher state is refreshed
  /// from its voxels when it comes back.
  void savePart(const BlockKey& key, ByteWriter* page) const override;
  void pageOut(const BlockKey& key) override;
  /// The resumed map's mesh is the saved one (pageIn() brought each submesh and patch back):
  /// nothing is re-meshed; consumers hear of every submesh as changed.
  void resumed(const BlockOctree& map, const MapFileInfo& info) override;
  bool pageIn(const BlockOctree& map, const VoxelBlock& block, ByteReader* page) override;
  /// The submesh and patch a page's mesh part holds (left empty where it has none); false when
  /// it is unreadable.
  static bool pagedParts(ByteReader* part, SubMesh* mesh, TexturePatch* patch);
  /// Bytes the layer holds for `key` (its submesh and patch): what paging it out frees.
  size_t blockBytes(const BlockKey& key) const;
  /// Bytes of the submeshes and patches.
  size_t memoryBytes() const {
    return store_.memoryBytes() + (texture_consumer_ ? textures_.memoryBytes() : 0);
  }
  /// The caller meshes at its own cadence (Mapper::blocksAwaitingMesh()).
  bool catchesUpItself() const override { return false; }

  /// What the last adopt() changed: every submesh of the new map, and the old ones gone.
  const MeshChanges& adopted() const { return adopted_; }
  const MeshStore& store() const { return store_; }
  const TextureStore& textures() const { return textures_; }

  /// The submeshes' change log (passes, rebuilds, loads and resets) for outside consumers.
  BlockChangeLog::Consumer subscribe(const std::string& name) { return changes_.subscribe(name); }
  BlockChangeLog::Changes take(BlockChangeLog::Consumer consumer) {
    return changes_.take(consumer);
  }
  size_t pending(BlockChangeLog::Consumer consumer) const { return changes_.pending(consumer); }
  /// The submeshes some consumer has not taken the change of yet (they must stay readable).
  void appendPendingMeshChanges(std::vector<BlockKey>* out) const { changes_.appendPending(out); }

 private:
  void record(const MeshChanges& changes);
  /// The texture pass has nothing to texture from (no frame): its changes are dropped.
  void skipTextures();

  const MeshLayerConfig config_;
  ThreadPool* pool_;
  MeshStore store_;
  TextureStore textures_;
  BlockChangeLog changes_;
  std::optional<BlockChangeLog::Consumer> texture_consumer_;  // textured only
  StereoFrame last_frame_;  // the latest fused frame: what a texture pass projects
  uint64_t frames_integrated_ = 0;
  MeshChanges adopted_;
};

}  // namespace stereo_fusion
