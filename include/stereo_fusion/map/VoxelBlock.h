#pragma once
#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>

#include "stereo_fusion/map/BlockKey.h"
#include "stereo_fusion/map/ResolutionLevel.h"
#include "stereo_fusion/map/Voxel.h"

namespace stereo_fusion {

struct VoxelBlock;

/// Pointers from a block to the blocks touching it by a face, an edge or a corner, kept by the
/// BlockOctree that owns the block so that reaching a neighbour costs one load instead of a tree
/// search (read them through BlockOctree::neighbour(const VoxelBlock&, ...)).
///
/// All 26 offsets are kept, not only the 7 towards + the mesher reads and the 7 towards − the
/// re-meshing reads: 96 more bytes per block (1.3 % of a block) buy an accessor with the same
/// domain as BlockOctree::neighbour(key, ...), and linking stays symmetric (slot s of a block
/// pairs with slot kCount − 1 − s of the neighbour), so erase can unlink without searching.
///
/// A copy starts unlinked and assignment keeps the target's links: links describe where a block
/// sits in its octree, not its contents, and a copy (a test's snapshot) sits in no octree.
class NeighbourLinks {
 public:
  /// Offsets in {-1,0,1}³ other than (0,0,0).
  static constexpr int kCount = 26;

  NeighbourLinks() = default;
  NeighbourLinks(const NeighbourLinks&) {}
  NeighbourLinks& operator=(const NeighbourLinks&) { return *this; }

  /// Slot of offset (dx, dy, dz) ∈ {-1,0,1}³ \ {(0,0,0)}: x fastest, the centre skipped.
  static constexpr int slot(int dx, int dy, int dz) {
    const int cube_index = (dx + 1) + 3 * (dy + 1) + 9 * (dz + 1);
    return cube_index < 13 ? cube_index : cube_index - 1;
  }
  /// Slot of the opposite offset: where the neighbour in `slot` keeps its link back.
  static constexpr int opposite(int slot) { return kCount - 1 - slot; }

  VoxelBlock* at(int slot) const { return blocks_[slot]; }

 private:
  friend class BlockOctree;  // the only writer: links must mirror the tree
  std::array<VoxelBlock*, kCount> blocks_{};
};

static_assert(NeighbourLinks::slot(-1, -1, -1) == 0 && NeighbourLinks::slot(1, 1, 1) == 25 &&
                  NeighbourLinks::slot(1, 0, 0) == 13 && NeighbourLinks::slot(-1, 0, 0) == 12,
              "slots number {-1,0,1}³ x fastest without the centre");
static_assert(NeighbourLinks::opposite(NeighbourLinks::slot(1, -1, 0)) ==
                      NeighbourLinks::slot(-1, 1, 0) &&
                  NeighbourLinks::opposite(NeighbourLinks::slot(0, 0, 1)) ==
                      NeighbourLinks::slot(0, 0, -1),
              "opposite() negates the offset");

/// A leaf of the BlockOctree: one cube of the world holding the same volume at three
/// resolutions, 8³ + 4³ + 2³ = 584 voxels addressed by one flat index (thesis eq. 3.4–3.5).
///
/// Levels are stored only once used: a level's voxels are allocated when a measurement first
/// updates one of them (level consistency below makes that "a measurement at this level or a
/// finer one"). A far wall seen only at 2³ holds 8 voxels (96 B), not 584 (7 KB). A level that
/// is not allocated reads as all unobserved (weight 0), exactly like an allocated one that no
/// measurement reached, so readers need not tell the two apart; writers go through the
/// writable*() accessors, which allocate.
///
/// Level consistency rule: a measurement whose depth selects level L (eq. 3.2) is fused
/// into level L *and every coarser level* of the block, and, with
/// update_allocated_finer_level, into level L − 1 where the block already holds it (at a
/// quarter weight, measurementUpdatesLevel()). So the coarsest level holds every
/// measurement that reached the block, and a finer level holds the measurements close enough
/// to deserve it plus, once it exists, those one level coarser. All levels therefore sample the
/// same fused surface; the mesher picks the finest level with enough observation and can read any
/// coarser level of a neighbour to close a seam.
struct VoxelBlock {
  static constexpr int kVoxelCount = 584;

  VoxelBlock() = default;
  /// A deep copy of the key and voxels (a test's snapshot); index and links stay the target's own.
  VoxelBlock(const VoxelBlock& other);
  VoxelBlock& operator=(const VoxelBlock& other);

  /// Flat index I_B(i, j, k) = i + j·B + k·B² + O (eq. 3.4–3.5); (0,0,0) is the voxel at the
  /// block's minimum corner (the thesis' "left-top-front" in the camera-aligned view).
  static constexpr int index(int level, int i, int j, int k) {
    const int side = levelSide(level);
    return i + j * side + k * side * side + levelOffset(level);
  }
  /// Index of voxel (i, j, k) within the voxels of one level of `side`³ (index() without the
  /// level's offset).
  static constexpr int indexInLevel(int side, int i, int j, int k) {
    return i + side * (j + side * k);
  }
  /// The level a flat index lies in.
  static constexpr int levelOfIndex(int flat_index) {
    return flat_index < levelOffset(1) ? 0 : (flat_index < levelOffset(2) ? 1 : 2);
  }

  /// The voxels of `level` (levelVoxelCount(level) of them, eq. 3.4 order): its storage, or a
  /// shared all-unobserved level when it is not allocated.
  const Voxel* level(int level) const {
    return levels_[level] ? levels_[level].get() : unobservedLevel();
  }
  /// The level's storage, or nullptr when it is not allocated.
  Voxel* levelIfAllocated(int level) { return levels_[level].get(); }
  bool hasLevel(int level) const { return levels_[level] != nullptr; }
  /// The level's storage, allocated (all unobserved) first if missing.
  Voxel* writableLevel(int level);
  /// Allocates `level` as a copy of `voxels` (levelVoxelCount(level) of them); it must be missing.
  void adoptLevel(int level, const Voxel* voxels);
  /// Frees `level`: it reads as never observed.
  void releaseLevel(int level) { levels_[level].reset(); }
  /// Frees every level: the block reads as never observed.
  void clearLevels();
  /// Bytes of allocated voxel storage.
  size_t voxelBytes() const;

  const Voxel& at(int level, int i, int j, int k) const { return voxel(index(level, i, j, k)); }
  Voxel& writableAt(int level, int i, int j, int k) { return writableVoxel(index(level, i, j, k)); }
  const Voxel& voxel(int flat_index) const {
    const int l = levelOfIndex(flat_index);
    return level(l)[flat_index - levelOffset(l)];
  }
  Voxel& writableVoxel(int flat_index) {
    const int l = levelOfIndex(flat_index);
    return writableLevel(l)[flat_index - levelOffset(l)];
  }

  BlockKey key;
  /// The block's row in every stage's BlockColumn: a dense number handed out by its octree on
  /// insertion and reused after the block is erased (what stages keep per
  /// block lives there, not here). kNoRow while the block is in no octree.
  static constexpr uint32_t kNoRow = 0xFFFFFFFFu;
  uint32_t row = kNoRow;

 private:
  /// levelVoxelCount(0) unobserved voxels: what a missing level of any size reads as.
  static const Voxel* unobservedLevel();
  std::array<std::unique_ptr<Voxel[]>, kNumLevels> levels_;

 public:
  /// The 26 neighbours, maintained by the owning BlockOctree.
  NeighbourLinks neighbours;
};

static_assert(VoxelBlock::index(0, 7, 7, 7) == 511, "8³ level ends at 511");
static_assert(VoxelBlock::index(1, 0, 0, 0) == 512 && VoxelBlock::index(1, 3, 3, 3) == 575,
              "4³ level occupies 512..575");
static_assert(VoxelBlock::index(2, 0, 0, 0) == 576 && VoxelBlock::index(2, 1, 1, 1) == 583,
              "2³ level occupies 576..583");
static_assert(VoxelBlock::levelOfIndex(511) == 0 && VoxelBlock::levelOfIndex(512) == 1 &&
                  VoxelBlock::levelOfIndex(575) == 1 && VoxelBlock::levelOfIndex(576) == 2,
              "levelOfIndex() inverts the level offsets");
// Without its voxels a block is its key and index, three level pointers and the 26 neighbour
// links (248 B on 64-bit): a block seen only at 2³ costs ~350 B with its 96 B of voxels.
static_assert(sizeof(VoxelBlock) <= 256, "a block's fixed part must stay small");

}  // namespace stereo_fusion
