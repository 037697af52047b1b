#include "stereo_fusion/mesh/MeshStore.h"

#include <algorithm>
#include <cstring>

#include "stereo_fusion/util/Timer.h"

namespace stereo_fusion {

MeshStore::MeshStore(const MeshingParams& params) : params_(params), mesher_(params) {}

std::vector<BlockKey> MeshStore::affectedOwners(const BlockOctree& map,
                                                const std::vector<BlockKey>& updated, ThreadPool* pool) {
  // The octree searches dominate: run them in parallel, one slot per (block, offset).
  std::vector<BlockKey> candidates(updated.size() * 8);
  std::vector<uint8_t> exists(candidates.size(), 0);
  auto search = [&](size_t begin, size_t end) {
    for (size_t i = begin; i < end; ++i)
      for (int d = 0; d < 8; ++d) {
        const BlockKey owner = updated[i].offset(-(d & 1), -((d >> 1) & 1), -((d >> 2) & 1));
        candidates[8 * i + d] = owner;
        exists[8 * i + d] = map.find(owner) != nullptr;
      }
  };
  if (pool != nullptr)
    pool->parallelFor(updated.size(), 64, search);
  else
    search(0, updated.size());
  std::vector<BlockKey> owners;
  owners.reserve(candidates.size());
  for (size_t i = 0; i < candidates.size(); ++i)
    if (exists[i]) owners.push_back(candidates[i]);
  std::sort(owners.begin(), owners.end());
  owners.erase(std::unique(owners.begin(), owners.end()), owners.end());
  return owners;
}

MeshChanges MeshStore::remesh(const BlockOctree& map, const std::vector<BlockKey>& owners,
                             ThreadPool* pool) {
  Timer timer;
  if (scratch_.size() < owners.size()) scratch_.resize(owners.size());
  pool->parallelFor(owners.size(), 4, [&](size_t begin, size_t end) {
    for (size_t i = begin; i < end; ++i) mesher_.mesh(map, *map.find(owners[i]), &scratch_[i]);
  });
  MeshChanges update;
  update.blocks_meshed = owners.size();
  for (size_t i = 0; i < owners.size(); ++i) {
    if (!scratch_[i].empty()) {
      std::swap(meshes_[owners[i]], scratch_[i]);
      update.changed.push_back(owners[i]);
    } else if (meshes_.erase(owners[i]) > 0) {
      update.removed.push_back(owners[i]);
    }
  }
  update.meshing_ms = timer.elapsedMs();
  return update;
}

MeshChanges MeshStore::update(const BlockOctree& map, const std::vector<BlockKey>& updated,
                             ThreadPool* pool, const std::vector<BlockKey>& erased) {
  // Each level choice reads one block's voxels: independent, so in parallel.
  pool->parallelFor(updated.size(), 16, [&](size_t begin, size_t end) {
    for (size_t i = begin; i < end; ++i)
      if (VoxelBlock* block = map.find(updated[i])) refreshMeshLevel(block, params_.level_min_coverage);
  });
  if (erased.empty()) return remesh(map, affectedOwners(map, updated, pool), pool);
  // An erased block's own submesh goes; its owners lose a seam neighbour and are re-meshed.
  std::vector<BlockKey> touched = updated;
  touched.insert(touched.end(), erased.begin(), erased.end());
  MeshChanges changes = remesh(map, affectedOwners(map, touched, pool), pool);
  for (const BlockKey& key : erased)
    if (map.find(key) == nullptr && meshes_.erase(key) > 0) changes.removed.push_back(key);
  std::sort(changes.removed.begin(), changes.removed.end());
  return changes;
}

MeshChanges MeshStore::rebuild(const BlockOctree& map, ThreadPool* pool) {
  std::vector<BlockKey> all;
  for (VoxelBlock* block : map.blocksSortedByKey()) {
    refreshMeshLevel(block, params_.level_min_coverage);
    all.push_back(block->key);
  }
  std::vector<BlockKey> stale;
  for (const auto& [key, mesh] : meshes_)
    if (map.find(key) == nullptr) stale.push_back(key);
  MeshChanges update = remesh(map, all, pool);
  for (const BlockKey& key : stale) {
    meshes_.erase(key);
    update.removed.push_back(key);
  }
  std::sort(update.removed.begin(), update.removed.end());
  return update;
}

size_t MeshStore::triangleCount() const {
  size_t n = 0;
  for (const auto& [key, mesh] : meshes_) n += mesh.triangles.size();
  return n;
}

TriangleMesh weldSubmeshes(const std::unordered_map<BlockKey, SubMesh, BlockKeyHash>& submeshes) {
  std::vector<const SubMesh*> ordered;
  for (const auto& [key, mesh] : submeshes) ordered.push_back(&mesh);
  std::sort(ordered.begin(), ordered.end(),
            [](const SubMesh* a, const SubMesh* b) { return a->key < b->key; });
  struct PositionHash {
    size_t operator()(const std::array<uint32_t, 3>& p) const {
      return (size_t{p[0]} * 73856093u) ^ (size_t{p[1]} * 19349663u) ^ (size_t{p[2]} * 83492791u);
    }
  };
  std::unordered_map<std::array<uint32_t, 3>, uint32_t, PositionHash> index_of;
  TriangleMesh mesh;
  for (const SubMesh* sub : ordered) {
    std::vector<uint32_t> remap(sub->positions.size());
    for (size_t v = 0; v < sub->positions.size(); ++v) {
      std::array<uint32_t, 3> bits;
      std::memcpy(bits.data(), sub->positions[v].data(), sizeof(bits));
      auto [it, inserted] = index_of.try_emplace(bits, static_cast<uint32_t>(mesh.positions.size()));
      if (inserted) {
        mesh.positions.push_back(sub->positions[v]);
        mesh.normals.push_back(sub->normals[v]);
        mesh.colors.push_back(sub->colors[v]);
      } else {
        mesh.normals[it->second] += sub->normals[v];
      }
      remap[v] = it->second;
    }
    for (const auto& t : sub->triangles) mesh.triangles.push_back({remap[t[0]], remap[t[1]], remap[t[2]]});
  }
  for (Eigen::Vector3f& n : mesh.normals) {
    const float len = n.norm();
    if (len > 0.0f) n /= len;
  }
  return mesh;
}

}  // namespace stereo_fusion
