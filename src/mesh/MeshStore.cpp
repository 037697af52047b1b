#include "stereo_fusion/mesh/MeshStore.h"

#include <algorithm>
#include <cstring>
#include <utility>

#include "stereo_fusion/util/Timer.h"

namespace stereo_fusion {

MeshStore::MeshStore(const MeshingParams& params) : params_(params), mesher_(params) {}

namespace {
/// Offset from a block to the d-th owner whose seams reach it: −(0|1) per axis, d = 0 the block.
constexpr int ownerOffset(int d, int axis) { return -((d >> axis) & 1); }

/// Splits `keys`, given the block found at each (or nullptr), into the blocks that exist and the
/// keys that have none.
void splitByPresence(const std::vector<BlockKey>& keys, const std::vector<const VoxelBlock*>& found,
                     std::vector<const VoxelBlock*>* present, std::vector<BlockKey>* absent) {
  for (size_t i = 0; i < keys.size(); ++i) {
    if (found[i] != nullptr)
      present->push_back(found[i]);
    else
      absent->push_back(keys[i]);
  }
}

/// Frees the face fills of `blocks` (nullptr entries skipped): they live for one pass only.
void freeFills(const std::vector<const VoxelBlock*>& blocks, SeamFills* fills) {
  for (const VoxelBlock* block : blocks)
    if (block != nullptr) std::vector<Voxel>().swap((*fills)[*block]);
}
}  // namespace

void MeshStore::PassClaims::begin(const BlockOctree& map) {
  if (++pass_ == 0) {  // wrapped: older stamps could read as this pass
    stamps_.clear();
    pass_ = 1;
  }
  stamps_.fit(map);
}

std::vector<MeshStore::Owner> MeshStore::ownersOf(const BlockOctree& map,
                                                  const std::vector<const VoxelBlock*>& present,
                                                  const std::vector<BlockKey>& absent,
                                                  PassClaims* claims, ThreadPool* pool) {
  // Up to 8 candidates per updated block but ~1.4 distinct owners each: each owner is claimed
  // once, by whichever of its updated blocks comes first; then only the distinct ones are sorted.
  claims->begin(map);
  std::vector<Owner> candidates(8 * present.size(), Owner{BlockKey{}, nullptr});
  auto claim = [&](size_t begin, size_t end) {
    for (size_t i = begin; i < end; ++i)
      for (int d = 0; d < 8; ++d) {
        const int dx = ownerOffset(d, 0), dy = ownerOffset(d, 1), dz = ownerOffset(d, 2);
        const VoxelBlock* owner = map.neighbour(*present[i], dx, dy, dz);
        // The key by arithmetic: owner->key would touch one more block's memory per owner.
        if (owner != nullptr && claims->claim(*owner))
          candidates[8 * i + d] = {present[i]->key.offset(dx, dy, dz), owner};
      }
  };
  parallelForOrHere(pool, present.size(), 64, claim);
  std::vector<Owner> owners;
  owners.reserve(2 * present.size() + absent.size());
  for (const Owner& owner : candidates)
    if (owner.block != nullptr) owners.push_back(owner);
  for (const BlockKey& key : absent)
    for (int d = 1; d < 8; ++d) {
      const BlockKey owner_key =
          key.offset(ownerOffset(d, 0), ownerOffset(d, 1), ownerOffset(d, 2));
      const VoxelBlock* owner = map.find(owner_key);
      if (owner != nullptr && claims->claim(*owner)) owners.push_back({owner_key, owner});
    }
  std::sort(owners.begin(), owners.end(),
            [](const Owner& a, const Owner& b) { return a.key < b.key; });
  return owners;
}

std::vector<BlockKey> MeshStore::affectedOwners(const BlockOctree& map,
                                                const std::vector<BlockKey>& updated,
                                                ThreadPool* pool) {
  std::vector<const VoxelBlock*> found(updated.size());
  auto search = [&](size_t begin, size_t end) {
    for (size_t i = begin; i < end; ++i) found[i] = map.find(updated[i]);
  };
  parallelForOrHere(pool, updated.size(), 64, search);
  std::vector<const VoxelBlock*> present;
  std::vector<BlockKey> absent;
  splitByPresence(updated, found, &present, &absent);
  std::vector<BlockKey> keys;
  PassClaims claims;
  for (const Owner& owner : ownersOf(map, present, absent, &claims, pool))
    keys.push_back(owner.key);
  return keys;
}

MeshChanges MeshStore::remesh(const BlockOctree& map, const std::vector<Owner>& owners,
                              ThreadPool* pool) {
  Timer timer;
  // Each owner's new submesh, empty where it has no triangles; the replaced ones are freed
  // with it at the end of the pass.
  std::vector<SubMesh> remeshed(owners.size());
  // The face-filled copies the owners read, each built once for the pass instead of once per
  // owner reading it (up to 8), by the thread that claims it first, and freed after it: they
  // are not kept between passes.
  seam_fills_.fit(map);
  fill_claims_.begin(map);
  std::vector<const VoxelBlock*> filled(8 * owners.size(), nullptr);
  pool->parallelFor(owners.size(), 16, [&](size_t begin, size_t end) {
    for (size_t i = begin; i < end; ++i)
      for (int d = 0; d < 8; ++d) {
        const VoxelBlock* block =
            map.neighbour(*owners[i].block, d & 1, (d >> 1) & 1, (d >> 2) & 1);
        if (block == nullptr || !states_[*block].seam_filled || !fill_claims_.claim(*block))
          continue;
        if (seam_fills_[*block].empty())  // not left by this pass's level refresh
          fillFacesFromCoarserLevels(*block, states_[*block].level, &seam_fills_[*block]);
        filled[8 * i + d] = block;
      }
  });
  pool->parallelFor(owners.size(), 4, [&](size_t begin, size_t end) {
    // Meshed into a per-thread buffer that keeps its capacity, then copied at its exact size:
    // kept submeshes grown by push_back would hold up to twice their bytes.
    thread_local SubMesh work;
    for (size_t i = begin; i < end; ++i) {
      mesher_.mesh(map, states_, *owners[i].block, &work, &seam_fills_);
      if (!work.empty()) remeshed[i] = SubMesh(work);
    }
  });
  freeFills(filled, &seam_fills_);
  // The submeshes kept so far are replaced in place, in parallel (no entry is added or erased
  // meanwhile); the table itself changes only below, for owners that gain or lose their
  // submesh. The replaced ones are freed with `remeshed`, on this thread: freeing them on the
  // pool's threads made the pass slower (malloc's arenas contend).
  enum : uint8_t { kWasKept = 1, kMeshed = 2 };
  std::vector<uint8_t> outcome(owners.size(), 0);
  std::vector<int64_t> bytes_delta(owners.size(), 0);
  pool->parallelFor(owners.size(), 64, [&](size_t begin, size_t end) {
    for (size_t i = begin; i < end; ++i) {
      outcome[i] = remeshed[i].empty() ? 0 : kMeshed;
      const int64_t meshed_bytes = remeshed[i].empty() ? 0 : submeshBytes(remeshed[i]);
      bytes_delta[i] = meshed_bytes;
      const auto it = meshes_.find(owners[i].key);
      if (it == meshes_.end()) continue;
      outcome[i] |= kWasKept;
      bytes_delta[i] -= static_cast<int64_t>(submeshBytes(it->second));
      if (outcome[i] & kMeshed) std::swap(it->second, remeshed[i]);
    }
  });
  MeshChanges update;
  update.blocks_meshed = owners.size();
  for (size_t i = 0; i < owners.size(); ++i) {
    const BlockKey& key = owners[i].key;
    submesh_bytes_ += bytes_delta[i];
    if (outcome[i] & kMeshed) {
      if (!(outcome[i] & kWasKept)) meshes_.emplace(key, std::move(remeshed[i]));
      update.changed.push_back(key);
    } else if (outcome[i] & kWasKept) {
      meshes_.erase(key);
      update.removed.push_back(key);
    }
  }
  update.meshing_ms = timer.elapsedMs();
  return update;
}

MeshChanges MeshStore::update(const BlockOctree& map, const std::vector<BlockKey>& updated,
                              ThreadPool* pool, const std::vector<BlockKey>& erased) {
  const Timer timer;  // the whole pass: the levels, the owners' search, meshing, the table
  // The one search per updated block: owners and neighbours are then reached through links.
  std::vector<const VoxelBlock*> found(updated.size());
  states_.fit(map);
  seam_fills_.fit(map);
  // The fills the refresh leaves are freed when the pass ends, thrown out of or not: one left
  // over would be read by a later pass as its block's (remesh() frees those its owners read).
  struct FreeFills {
    SeamFills& fills;
    const std::vector<const VoxelBlock*>& blocks;
    ~FreeFills() { freeFills(blocks, &fills); }
  } free_fills{seam_fills_, found};
  // Each level choice reads one block's voxels: independent, so in parallel. Its face fill
  // stays for the owners (remesh() builds only the neighbours' that are missing).
  pool->parallelFor(updated.size(), 16, [&](size_t begin, size_t end) {
    for (size_t i = begin; i < end; ++i)
      if (const VoxelBlock* block = map.find(updated[i])) {
        found[i] = block;
        refreshMeshLevel(*block, params_, &states_[*block], &seam_fills_[*block]);
      }
  });
  std::vector<const VoxelBlock*> present;
  std::vector<BlockKey> absent;
  present.reserve(updated.size());
  splitByPresence(updated, found, &present, &absent);
  MeshChanges changes = remeshAround(map, std::move(present), std::move(absent), pool, erased);
  changes.meshing_ms = timer.elapsedMs();
  return changes;
}

MeshChanges MeshStore::remeshAround(const BlockOctree& map, std::vector<const VoxelBlock*> present,
                                    std::vector<BlockKey> absent, ThreadPool* pool,
                                    const std::vector<BlockKey>& erased) {
  // An erased block's own submesh goes; its owners lose a seam neighbour and are re-meshed.
  std::vector<const VoxelBlock*> erased_found(erased.size());
  for (size_t i = 0; i < erased.size(); ++i) erased_found[i] = map.find(erased[i]);
  std::vector<BlockKey> erased_absent;
  splitByPresence(erased, erased_found, &present, &erased_absent);
  absent.insert(absent.end(), erased_absent.begin(), erased_absent.end());
  MeshChanges changes = remesh(map, ownersOf(map, present, absent, &owner_claims_, pool), pool);
  if (erased.empty()) return changes;
  for (const BlockKey& key : erased_absent)
    if (detach(key)) changes.removed.push_back(key);
  std::sort(changes.removed.begin(), changes.removed.end());
  return changes;
}

MeshChanges MeshStore::rebuild(const BlockOctree& map, ThreadPool* pool) {
  std::vector<Owner> all;
  const std::vector<VoxelBlock*> blocks = map.blocksSortedByKey();
  states_.fit(map);
  pool->parallelFor(blocks.size(), 16, [&](size_t begin, size_t end) {
    for (size_t i = begin; i < end; ++i)
      refreshMeshLevel(*blocks[i], params_, &states_[*blocks[i]]);
  });
  for (const VoxelBlock* block : blocks) all.push_back({block->key, block});
  std::vector<BlockKey> stale;
  for (const auto& [key, mesh] : meshes_)
    if (map.find(key) == nullptr) stale.push_back(key);
  MeshChanges update = remesh(map, all, pool);
  for (const BlockKey& key : stale) {
    detach(key);
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

size_t MeshStore::submeshBytes(const SubMesh& mesh) {
  return sizeof(std::pair<const BlockKey, SubMesh>) + 2 * sizeof(void*) +  // table entry
         mesh.positions.capacity() * sizeof(mesh.positions[0]) +
         mesh.normals.capacity() * sizeof(mesh.normals[0]) +
         mesh.colors.capacity() * sizeof(mesh.colors[0]) +
         mesh.triangles.capacity() * sizeof(mesh.triangles[0]);
}

size_t MeshStore::memoryBytes() const {
  return static_cast<size_t>(submesh_bytes_) + meshes_.bucket_count() * sizeof(void*);
}

std::optional<SubMesh> MeshStore::detach(const BlockKey& key) {
  const auto it = meshes_.find(key);
  if (it == meshes_.end()) return std::nullopt;
  submesh_bytes_ -= static_cast<int64_t>(submeshBytes(it->second));
  std::optional<SubMesh> mesh(std::move(it->second));
  meshes_.erase(it);
  return mesh;
}

void MeshStore::attach(const BlockOctree& map, const VoxelBlock& block,
                       std::optional<SubMesh> mesh) {
  states_.fit(map);
  refreshMeshLevel(block, params_, &states_[block]);
  if (!mesh) return;
  submesh_bytes_ += static_cast<int64_t>(submeshBytes(*mesh));
  meshes_[block.key] = std::move(*mesh);
}

TriangleMesh weldSubmeshes(const std::unordered_map<BlockKey, SubMesh, BlockKeyHash>& submeshes) {
  std::vector<const SubMesh*> ordered;
  for (const auto& [key, mesh] : submeshes) ordered.push_back(&mesh);
  return weldSubmeshes(std::move(ordered));
}

TriangleMesh weldSubmeshes(std::vector<const SubMesh*> ordered) {
  std::sort(ordered.begin(), ordered.end(),
            [](const SubMesh* a, const SubMesh* b) { return a->key < b->key; });
  // Every vertex of every submesh in that order, by its position's bits: sorted, equal bits
  // lie together with the first seen first, which keeps the vertex's place and colour. A
  // sorted array instead of a hash table: a third of the bytes at the end of a large run.
  struct Entry {
    std::array<uint32_t, 3> bits;
    uint32_t seq;  // the vertex's place among all submeshes' vertices
    bool operator<(const Entry& o) const { return bits != o.bits ? bits < o.bits : seq < o.seq; }
  };
  size_t vertex_total = 0, triangle_total = 0;
  for (const SubMesh* sub : ordered) {
    vertex_total += sub->positions.size();
    triangle_total += sub->triangles.size();
  }
  std::vector<Entry> entries;
  entries.reserve(vertex_total);
  for (const SubMesh* sub : ordered)
    for (const Eigen::Vector3f& p : sub->positions) {
      Entry e{};
      std::memcpy(e.bits.data(), p.data(), sizeof(e.bits));
      e.seq = static_cast<uint32_t>(entries.size());
      entries.push_back(e);
    }
  std::sort(entries.begin(), entries.end());
  // first_of[seq]: the seq of the first vertex with the same bits; the welded vertices are the
  // first ones, numbered in their order.
  std::vector<uint32_t> first_of(vertex_total);
  for (size_t i = 0; i < entries.size(); ++i)
    first_of[entries[i].seq] = i > 0 && entries[i].bits == entries[i - 1].bits
                                   ? first_of[entries[i - 1].seq]
                                   : entries[i].seq;
  std::vector<Entry>().swap(entries);
  size_t welded = 0;
  for (size_t seq = 0; seq < vertex_total; ++seq) welded += first_of[seq] == seq;
  TriangleMesh mesh;
  mesh.positions.reserve(welded);
  mesh.normals.reserve(welded);
  mesh.colors.reserve(welded);
  mesh.triangles.reserve(triangle_total);
  // index_of[seq]: the welded index, for first vertices; duplicates read their first's.
  std::vector<uint32_t>& index_of = first_of;
  size_t seq = 0;
  for (const SubMesh* sub : ordered) {
    const size_t base = seq;
    for (size_t v = 0; v < sub->positions.size(); ++v, ++seq) {
      if (first_of[seq] == seq) {
        index_of[seq] = static_cast<uint32_t>(mesh.positions.size());
        mesh.positions.push_back(sub->positions[v]);
        mesh.normals.push_back(sub->normals[v]);
        mesh.colors.push_back(sub->colors[v]);
      } else {
        index_of[seq] = index_of[first_of[seq]];  // first_of[seq] < seq: already an index
        mesh.normals[index_of[seq]] += sub->normals[v];
      }
    }
    for (const auto& t : sub->triangles)
      mesh.triangles.push_back(
          {index_of[base + t[0]], index_of[base + t[1]], index_of[base + t[2]]});
  }
  for (Eigen::Vector3f& n : mesh.normals) {
    const float len = n.norm();
    if (len > 0.0f) n /= len;
  }
  return mesh;
}

}  // namespace stereo_fusion
