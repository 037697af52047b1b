#pragma once
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <atomic>
#include <cmath>
#include <cstddef>
#include <functional>
#include <memory>
#include <mutex>
#include <vector>

#include "stereo_fusion/map/BlockKey.h"
#include "stereo_fusion/map/VoxelBlock.h"

namespace stereo_fusion {

class ThreadPool;

/// Sparse octree whose leaves are voxel blocks at a fixed depth (thesis §3.3).
///
/// A node of height h covers 2^h × 2^h × 2^h blocks starting at its integer `origin`;
/// its children split that cube into octants chosen by eq. 2.7–2.10
/// (octantIndex()). Leaves (height 0) are VoxelBlocks. When a key falls outside the root,
/// the tree grows a new root around the old one towards the key, so the map is unbounded
/// in every direction, negative coordinates included.
///
/// Concurrency: find() is lock-free and may run in parallel with findOrAllocate();
/// findOrAllocate() serialises only the allocation itself (a node or block is built
/// completely before it is published with a release store). Everything else
/// (iteration, erase, swap, clear) must not overlap with allocation or find(): the Mapper calls
/// them between frames on the integrating thread.
///
/// Every block links to its 26 neighbours (VoxelBlock::neighbours), so the per-frame neighbour
/// accesses of meshing cost a load instead of a search. Allocation links a new block both ways
/// under the allocation mutex and erase unlinks, so the links always equal
/// find(key.offset(...)). Links are plain pointers written while other threads may run find():
/// read them (neighbour(const VoxelBlock&, ...)) only when no allocation can run, i.e. after
/// the lookup stage — where fusion and meshing run.
class BlockOctree {
 public:
  /// Keys beyond ±kMaxKey are refused (2.7e8 blocks, > 20 000 km at 8 cm blocks: far beyond
  /// any real map, and far from int32 overflow of the keys themselves).
  static constexpr int32_t kMaxKey = 1 << 28;

  explicit BlockOctree(double block_size_m);
  ~BlockOctree();
  BlockOctree(const BlockOctree&) = delete;
  BlockOctree& operator=(const BlockOctree&) = delete;

  double blockSize() const { return block_size_m_; }

  /// Key of the block containing `p_world` (floor(p / block edge)).
  BlockKey keyForPoint(const Eigen::Vector3d& p_world) const;
  /// The same for a point already in block units (world coordinates / block size), for
  /// callers that scale many points by a precomputed reciprocal.
  static BlockKey keyForBlockCoordinates(const Eigen::Vector3d& p_blocks);
  /// World coordinates of the block's minimum corner.
  Eigen::Vector3d blockOrigin(const BlockKey& key) const;
  static bool keyInRange(const BlockKey& key);

  /// Octant of `key` inside a node whose centre lies between blocks centre-1 and centre:
  /// I = 4·[x ≥ cx] + 2·[y ≥ cy] + [z ≥ cz] (eq. 2.7–2.10 on block centres: the centre of
  /// block x is x + 0.5, and x + 0.5 > cx ⇔ x ≥ cx for integer x, cx).
  static int octantIndex(const BlockKey& key, const BlockKey& centre);

  /// Block at `key`, or nullptr. O(log N). Counts one search.
  VoxelBlock* find(const BlockKey& key) const;
  /// Block at `key`, allocated (zero weight everywhere) if missing. nullptr only when the key
  /// is out of range. Thread-safe. `allocated` (optional) tells whether it was created now.
  VoxelBlock* findOrAllocate(const BlockKey& key, bool* allocated = nullptr);
  /// findOrAllocate() of each of keys[0, n): blocks[i] and allocated[i] (1 if created now) for
  /// keys[i]. Counts one search per key in range, as findOrAllocate() does. Thread-safe as
  /// findOrAllocate(). Fastest on sorted keys: each search starts from the deepest node of the
  /// previous key's path that holds the key, which for neighbouring keys is a few levels up rather
  /// than the root.
  void findOrAllocateBatch(const BlockKey* keys, size_t n, VoxelBlock** blocks, uint8_t* allocated);
  /// find() of each of keys[0, n) into blocks[i] (nullptr where missing), as findOrAllocateBatch()
  /// searches but allocating nothing. Counts one search per key in range.
  void findBatch(const BlockKey* keys, size_t n, VoxelBlock** blocks) const;
  /// Puts a block built outside the octree (fused into before it had a place, see SurfaceFuser)
  /// at its key, linked to its neighbours. nullptr (and the block freed) if the key is out of
  /// range or already taken. Thread-safe as findOrAllocate().
  VoxelBlock* insert(std::unique_ptr<VoxelBlock> block);
  /// Neighbour at offset (dx, dy, dz) ∈ {-1,0,1}³ (faces, edges, corners), or nullptr. A search;
  /// works for keys with no block too.
  VoxelBlock* neighbour(const BlockKey& key, int dx, int dy, int dz) const {
    return find(key.offset(dx, dy, dz));
  }
  /// The same as neighbour(block.key, dx, dy, dz) — `block` itself for (0, 0, 0) — read from the
  /// block's cached links: no search, not counted in searchCount(). `block` must belong to this
  /// octree, and no findOrAllocate() may run meanwhile (links are written without atomics).
  VoxelBlock* neighbour(const VoxelBlock& block, int dx, int dy, int dz) const;

  size_t blockCount() const { return blocks_.size(); }
  /// One more than the largest VoxelBlock::row handed out since construction or clear(): the
  /// rows a BlockColumn needs. Rows of erased blocks are handed out again.
  size_t rowCount() const { return row_count_; }
  size_t nodeCount() const { return nodes_.size(); }
  /// Height of the root above the leaves (a tree with one root holding 8 blocks has height 1).
  int height() const;
  /// Where the map's bytes are: the blocks' fixed parts (key, fields, links), their allocated
  /// voxel levels (and how many blocks hold each level), the inner nodes and bookkeeping arrays.
  /// Heap allocations are counted at their requested size (the allocator adds ~16 B to each).
  struct MemoryUse {
    size_t block_bytes = 0;
    size_t level_bytes[kNumLevels] = {};
    size_t level_blocks[kNumLevels] = {};
    size_t node_bytes = 0;
    size_t bookkeeping_bytes = 0;
    size_t voxelBytes() const {
      size_t bytes = 0;
      for (size_t b : level_bytes) bytes += b;
      return bytes;
    }
    size_t total() const { return block_bytes + node_bytes + bookkeeping_bytes + voxelBytes(); }
  };
  /// `with_levels` false leaves the level figures at 0 and walks no block (O(1)).
  MemoryUse memoryUse(bool with_levels = true) const;
  /// memoryUse().total(): bytes held by blocks, their voxels, inner nodes and bookkeeping.
  size_t memoryBytes() const { return memoryUse().total(); }
  /// memoryBytes() / blockCount(): the per-block cost including octree overhead.
  double bytesPerBlock() const;

  /// Appends to `out` the blocks whose boxes pass `may_contain` (world coordinates), descending
  /// only into nodes whose boxes pass it: a query for the blocks in a region (a camera's
  /// frustum) that costs the nodes and blocks near the region, not the whole map.
  /// `may_contain` must accept a node's box whenever it accepts a block's box inside it (a
  /// conservative "does the box reach the region" test). Order: depth-first by octant.
  /// With `pool` the subtrees are walked in parallel (`may_contain` then runs on several
  /// threads at once); the blocks come out in the same order.
  using BoxTest = std::function<bool(const Eigen::AlignedBox3d& box_world)>;
  void collectBlocks(const BoxTest& may_contain, std::vector<VoxelBlock*>* out,
                     ThreadPool* pool = nullptr) const;

  /// All blocks, in allocation order. Not safe while another thread allocates.
  const std::vector<VoxelBlock*>& blocks() const { return blocks_; }
  /// All blocks sorted by key: a deterministic order independent of thread scheduling.
  std::vector<VoxelBlock*> blocksSortedByKey() const;

  /// Total octree searches (find + findOrAllocate calls) since construction or resetCounters().
  uint64_t searchCount() const { return searches_.load(std::memory_order_relaxed); }
  void resetSearchCount() { searches_.store(0, std::memory_order_relaxed); }

  /// Removes every block and node; the block size stays.
  void clear();

  /// Removes the blocks at `keys` (missing keys are ignored) and every inner node left without
  /// children, so a map that keeps moving does not keep the nodes of space it has forgotten.
  /// Pointers to the erased blocks become invalid. Returns how many blocks were removed.
  /// Not thread-safe: nothing may search or allocate meanwhile.
  size_t erase(const std::vector<BlockKey>& keys);

  /// Exchanges the contents (blocks, nodes, block size) with `other`; counters stay. Used to
  /// install a map loaded into a fresh octree in one step. Not thread-safe.
  void swap(BlockOctree& other);

 private:
  struct Node;
  Node* newNode(const std::array<int64_t, 3>& origin, int height);
  void growToContain(const BlockKey& key);  // caller holds alloc_mutex_
  /// The block at the in-range `key`, allocated if still missing: the locked half of
  /// findOrAllocate(), after its search found nothing. Not counted in searchCount().
  VoxelBlock* allocate(const BlockKey& key, std::unique_ptr<VoxelBlock> fresh, bool* allocated);
  /// findOrAllocateBatch() (`allocated` non-null) or findBatch() (null).
  void searchBatch(const BlockKey* keys, size_t n, VoxelBlock** blocks, uint8_t* allocated);
  /// The block at `key` in the subtree of `node`, which must contain the key. Not counted in
  /// searchCount(): link() uses it, and the octree's own searches are not the callers' work.
  static VoxelBlock* findBelow(const Node* node, const BlockKey& key);
  /// Links a block being allocated with its existing neighbours, both ways (caller holds
  /// alloc_mutex_).
  void link(VoxelBlock* block);
  /// Clears the links of `block`'s neighbours back to it, before it is freed.
  static void unlink(VoxelBlock* block);
  static bool contains(const Node* node, const BlockKey& key);
  /// The world box of `side`³ blocks from block coordinates `origin`.
  Eigen::AlignedBox3d boxOf(const std::array<int64_t, 3>& origin, int64_t side) const;
  /// collectBlocks() below `start`, depth-first by octant, on the calling thread.
  void collectBelow(const Node* start, const BoxTest& may_contain,
                    std::vector<VoxelBlock*>* out) const;

  double block_size_m_;
  std::atomic<Node*> root_{nullptr};
  // Own cache line: every find() bumps it, and it must not evict the root pointer.
  alignas(64) mutable std::atomic<uint64_t> searches_{0};
  alignas(64) char pad_[1] = {};
  std::mutex alloc_mutex_;
  std::vector<std::unique_ptr<Node>> nodes_;
  std::vector<VoxelBlock*> blocks_;
  std::vector<std::unique_ptr<VoxelBlock>> block_storage_;
  std::vector<uint32_t> free_rows_;  // of erased blocks, handed out before new ones
  uint32_t row_count_ = 0;
};

// Inline: the lookup calls these twice per pixel.
inline BlockKey BlockOctree::keyForBlockCoordinates(const Eigen::Vector3d& p_blocks) {
  const double lim = static_cast<double>(kMaxKey) + 1.0;
  auto toKey = [lim](double v) {
    const double k = std::floor(v);
    // Out-of-range (or NaN) coordinates map beyond kMaxKey so keyInRange() refuses them.
    if (!(std::abs(k) < lim)) return static_cast<int32_t>(kMaxKey) + 1;
    return static_cast<int32_t>(k);
  };
  return {toKey(p_blocks.x()), toKey(p_blocks.y()), toKey(p_blocks.z())};
}

inline VoxelBlock* BlockOctree::neighbour(const VoxelBlock& block, int dx, int dy, int dz) const {
  // The octree owns its blocks mutably, so a const octree hands out VoxelBlock* as find() does.
  if (dx == 0 && dy == 0 && dz == 0) return const_cast<VoxelBlock*>(&block);
  return block.neighbours.at(NeighbourLinks::slot(dx, dy, dz));
}

inline bool BlockOctree::keyInRange(const BlockKey& key) {
  auto ok = [](int32_t v) { return v >= -kMaxKey && v <= kMaxKey; };
  return ok(key.x) && ok(key.y) && ok(key.z);
}

}  // namespace stereo_fusion
