#pragma once
#include <optional>
#include <unordered_map>
#include <vector>

#include "stereo_fusion/map/BlockColumn.h"
#include "stereo_fusion/map/BlockOctree.h"
#include "stereo_fusion/mesh/BlockMesher.h"
#include "stereo_fusion/mesh/SubMesh.h"
#include "stereo_fusion/util/ThreadPool.h"

namespace stereo_fusion {

/// What one meshing pass changed: enough for a subscriber to keep an exact copy.
struct MeshChanges {
  std::vector<BlockKey> changed;  ///< blocks whose submesh was (re)built and is non-empty, sorted
  std::vector<BlockKey> removed;  ///< blocks whose submesh disappeared, sorted
  size_t blocks_meshed = 0;       ///< owners re-meshed in this pass
  /// The whole pass (update(): mesh levels, owners, meshing and the submesh table).
  double meshing_ms = 0.0;
};

/// The global mesh as one submesh per block, kept up to date incrementally (thesis §3.6).
class MeshStore {
 public:
  explicit MeshStore(const MeshingParams& params);

  /// After fusion changed `updated` blocks: refresh their mesh levels, then re-mesh them and
  /// every block whose owned seams reach them — the −x/−y/−z neighbours and diagonals, i.e.
  /// owners K − (0|1, 0|1, 0|1) — in parallel over blocks. `erased` lists blocks just removed
  /// from the map (eviction): their submeshes are dropped (reported in `removed`) and the
  /// owners whose seams reached them are re-meshed, so the result equals a rebuild.
  /// Owners and seam neighbours are reached through the blocks' neighbour links (one search per
  /// updated block), so no allocation may run on `map` meanwhile (BlockOctree::neighbour).
  MeshChanges update(const BlockOctree& map, const std::vector<BlockKey>& updated, ThreadPool* pool,
                     const std::vector<BlockKey>& erased = {});
  /// Meshes every block from scratch (the reference for the incremental result).
  MeshChanges rebuild(const BlockOctree& map, ThreadPool* pool);

  const std::unordered_map<BlockKey, SubMesh, BlockKeyHash>& submeshes() const { return meshes_; }
  /// The mesher's per-block state (level and sign bits), current for every block meshed.
  const MeshStates& states() const { return states_; }
  size_t triangleCount() const;
  /// Bytes the submeshes hold (their arrays and the key table's entries).
  size_t memoryBytes() const;
  void clear() {
    meshes_.clear();
    submesh_bytes_ = 0;
    states_.clear();
    seam_fills_.clear();
  }

  /// Paging: takes the submesh of `key` out of the store (nullopt when it has none), as if the
  /// block had never been meshed; nothing is reported (the mesh did not change).
  std::optional<SubMesh> detach(const BlockKey& key);
  /// Paging: `block`, back in `map`, gets its mesher state again (refreshed from its voxels, as
  /// it was when it left) and its submesh `mesh` (nullopt: it had none).
  void attach(const BlockOctree& map, const VoxelBlock& block, std::optional<SubMesh> mesh);
  /// The bytes memoryBytes() counts for one kept submesh (its arrays and its table entry).
  static size_t submeshBytes(const SubMesh& mesh);

  /// The owners a change of `updated` must re-mesh (existing blocks only), sorted by key.
  /// The searches for `updated` run on `pool` when given; their owners are then reached through
  /// the neighbour links (keys with no block, such as erased ones, through searches).
  static std::vector<BlockKey> affectedOwners(const BlockOctree& map,
                                              const std::vector<BlockKey>& updated,
                                              ThreadPool* pool = nullptr);

 private:
  /// A block to re-mesh with its key beside it, so that sorting reads no block memory.
  struct Owner {
    BlockKey key;
    const VoxelBlock* block;
  };
  /// Per row, the last pass that claimed the block: each block is taken once per pass by
  /// whichever thread claims it first (an atomic exchange), whatever the order.
  class PassClaims {
   public:
    /// A new pass over `map`'s rows: nothing claimed yet.
    void begin(const BlockOctree& map);
    /// True for the first claim of `block` in this pass (thread-safe).
    bool claim(const VoxelBlock& block) {
      return __atomic_exchange_n(&stamps_[block], pass_, __ATOMIC_RELAXED) != pass_;
    }

   private:
    BlockColumn<uint32_t> stamps_;
    uint32_t pass_ = 0;
  };
  /// Owners of the seams of `present` blocks (through their links, on `pool` when given) and of
  /// `absent` keys (through searches), sorted by key without duplicates.
  static std::vector<Owner> ownersOf(const BlockOctree& map,
                                     const std::vector<const VoxelBlock*>& present,
                                     const std::vector<BlockKey>& absent, PassClaims* claims,
                                     ThreadPool* pool);
  MeshChanges remesh(const BlockOctree& map, const std::vector<Owner>& owners, ThreadPool* pool);
  /// The part of update() after the mesh levels are refreshed: `present` updated blocks and
  /// `absent` updated keys with no block, plus `erased`.
  MeshChanges remeshAround(const BlockOctree& map, std::vector<const VoxelBlock*> present,
                           std::vector<BlockKey> absent, ThreadPool* pool,
                           const std::vector<BlockKey>& erased);

  MeshingParams params_;
  BlockMesher mesher_;
  MeshStates
      states_;  // the mesher's per-block cache, refreshed for every block before it is meshed
  SeamFills seam_fills_;  // during a pass: the face-filled copies its owners read, then freed
  std::unordered_map<BlockKey, SubMesh, BlockKeyHash> meshes_;
  int64_t submesh_bytes_ = 0;  // submeshBytes() of every kept submesh: memoryBytes() in O(1)
  PassClaims owner_claims_;    // ownersOf()'s de-duplication, reused pass after pass
  PassClaims fill_claims_;     // remesh(): each seam-filled neighbour filled once per pass
};

/// All submeshes as one mesh, vertices shared between submeshes welded (they are computed
/// bit-identically on both sides of a seam); welded normals are averaged. Deterministic:
/// blocks are taken in key order.
TriangleMesh weldSubmeshes(const std::unordered_map<BlockKey, SubMesh, BlockKeyHash>& submeshes);
/// The same over submeshes held elsewhere (a paged map's: some in memory, some read back).
TriangleMesh weldSubmeshes(std::vector<const SubMesh*> submeshes);

}  // namespace stereo_fusion
