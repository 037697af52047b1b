#include "stereo_fusion/layers/MeshLayer.h"

#include <algorithm>

#include "stereo_fusion/paging/BlockPage.h"

namespace stereo_fusion {

MeshLayer::MeshLayer(const MeshLayerConfig& config, ThreadPool* pool)
    : config_(config),
      pool_(pool),
      store_(config.meshing),
      textures_(config.texture),
      texture_consumer_(
          config.textured ? std::optional<BlockChangeLog::Consumer>(changes_.subscribe("textures"))
                          : std::nullopt) {}

void MeshLayer::onFrame(const LayerFrame& frame) {
  frames_integrated_ = frame.frames_integrated;
  if (texture_consumer_) last_frame_ = frame.frame;
}

MeshPass MeshLayer::updateMesh(const BlockOctree& map, const BlockChangeLog::Changes& changes,
                               StageScope* stage) {
  MeshPass pass;
  pass.blocks_changed = changes.updated.size() + changes.erased.size();
  if (!config_.enabled || changes.empty()) return pass;
  if (stage) stage->enter(MapperStage::kMeshing);
  pass.mesh = store_.update(map, changes.updated, pool_, changes.erased);
  record(pass.mesh);
  if (texture_consumer_) {
    if (stage) stage->enter(MapperStage::kTexture);
    const BlockChangeLog::Changes retexture = changes_.take(*texture_consumer_);
    MeshChanges submeshes;
    submeshes.changed = retexture.updated;
    submeshes.removed = retexture.erased;
    pass.texture = textures_.update(store_, submeshes, last_frame_, frames_integrated_, pool_);
  }
  return pass;
}

MeshChanges MeshLayer::rebuildMesh(const BlockOctree& map) {
  MeshChanges changes = store_.rebuild(map, pool_);
  record(changes);
  // No frame at hand: the stored patches are re-projected onto the rebuilt submeshes.
  if (texture_consumer_) {
    changes_.take(*texture_consumer_);
    textures_.reprojectAll(store_);
  }
  return changes;
}

void MeshLayer::reset() {
  MeshChanges dropped;
  for (const auto& [key, submesh] : store_.submeshes()) dropped.removed.push_back(key);
  std::sort(dropped.removed.begin(), dropped.removed.end());
  store_.clear();
  textures_.clear();
  // The consumers learn that every submesh is gone, after whatever they have not taken.
  record(dropped);
  skipTextures();
  last_frame_ = StereoFrame();
  frames_integrated_ = 0;
}

void MeshLayer::adopt(const BlockOctree& map, const MapFileInfo& info) {
  textures_.clear();
  last_frame_ = StereoFrame();
  frames_integrated_ = info.frames_integrated;
  // A rebuild over the kept store reports the old map's vanished submeshes as removed.
  adopted_ = MeshChanges();
  if (config_.enabled) {
    adopted_ = store_.rebuild(map, pool_);
    record(adopted_);
  } else {
    store_.clear();
  }
  skipTextures();
}

void MeshLayer::savePart(const BlockKey& key, ByteWriter* page) const {
  const auto mesh = store_.submeshes().find(key);
  const TexturePatch* patch = textures_.find(key);
  page->put<uint8_t>(mesh != store_.submeshes().end());
  if (mesh != store_.submeshes().end()) writeSubMesh(mesh->second, page);
  page->put<uint8_t>(patch != nullptr);
  if (patch) writeTexturePatch(*patch, page);
}

void MeshLayer::pageOut(const BlockKey& key) {
  store_.detach(key);
  textures_.detach(key);
}

void MeshLayer::resumed(const BlockOctree& /*map*/, const MapFileInfo& info) {
  last_frame_ = StereoFrame();
  frames_integrated_ = info.frames_integrated;
  adopted_ = MeshChanges();
  for (const auto& [key, submesh] : store_.submeshes()) adopted_.changed.push_back(key);
  std::sort(adopted_.changed.begin(), adopted_.changed.end());
  record(adopted_);
  skipTextures();
}

bool MeshLayer::pageIn(const BlockOctree& map, const VoxelBlock& block, ByteReader* page) {
  std::optional<SubMesh> mesh;
  if (page->get<uint8_t>()) {
    mesh.emplace();
    if (!readSubMesh(page, &*mesh) || mesh->key != block.key) return false;
  }
  std::optional<TexturePatch> patch;
  if (page->get<uint8_t>()) {
    patch.emplace();
    if (!readTexturePatch(page, &*patch)) return false;
  }
  if (!page->ok()) return false;
  store_.attach(map, block, std::move(mesh));
  if (patch) textures_.attach(block.key, std::move(*patch));
  return true;
}

bool MeshLayer::pagedParts(ByteReader* part, SubMesh* mesh, TexturePatch* patch) {
  if (part->get<uint8_t>() && !readSubMesh(part, mesh)) return false;
  if (part->get<uint8_t>() && !readTexturePatch(part, patch)) return false;
  return part->ok();
}

size_t MeshLayer::blockBytes(const BlockKey& key) const {
  size_t bytes = 0;
  const auto mesh = store_.submeshes().find(key);
  if (mesh != store_.submeshes().end()) bytes += MeshStore::submeshBytes(mesh->second);
  if (const TexturePatch* patch = textures_.find(key))
    bytes += patch->memoryBytes() + sizeof(TexturePatch);
  return bytes;
}

void MeshLayer::record(const MeshChanges& changes) {
  changes_.recordUpdated(changes.changed);
  changes_.recordErased(changes.removed);
}

void MeshLayer::skipTextures() {
  if (texture_consumer_) changes_.take(*texture_consumer_);
}

}  // namespace stereo_fusion
