#pragma once
#include <array>
#include <cstdint>

#include "stereo_fusion/map/BlockKey.h"
#include "stereo_fusion/map/ResolutionLevel.h"
#include "stereo_fusion/map/Voxel.h"

namespace stereo_fusion {

/// A leaf of the BlockOctree: one cube of the world holding the same volume at three
/// resolutions, 8³ + 4³ + 2³ = 584 voxels in one flat array (thesis eq. 3.4–3.5).
///
/// Level consistency rule: a measurement whose depth selects level L (eq. 3.2) is fused
/// into level L *and every coarser level* of the block. So the coarsest level holds every
/// measurement that reached the block, and a finer level holds exactly the measurements
/// close enough to deserve it. All levels therefore sample the same fused surface; the
/// mesher picks the finest level with enough observation and can read any coarser level of
/// a neighbour to close a seam.
struct VoxelBlock {
  static constexpr int kVoxelCount = 584;

  /// Flat index I_B(i, j, k) = i + j·B + k·B² + O (eq. 3.4–3.5); (0,0,0) is the voxel at the
  /// block's minimum corner (the thesis' "left-top-front" in the camera-aligned view).
  static constexpr int index(int level, int i, int j, int k) {
    const int side = levelSide(level);
    return i + j * side + k * side * side + levelOffset(level);
  }

  Voxel& at(int level, int i, int j, int k) { return voxels[index(level, i, j, k)]; }
  const Voxel& at(int level, int i, int j, int k) const { return voxels[index(level, i, j, k)]; }

  std::array<Voxel, kVoxelCount> voxels{};
  BlockKey key;
  /// Level the mesher samples this block at (see chooseMeshLevel()); refreshed after fusion.
  int8_t mesh_level = kNumLevels - 1;
  /// Whether the observed voxels of mesh_level include negative / non-negative distances:
  /// an owner whose whole neighbourhood has one sign cannot contain a surface.
  bool mesh_has_negative = false;
  bool mesh_has_positive = false;
  // (The 8-byte fields last: the small ones above fill the padding after `key`.)
  /// Frame counter of the last fusion that changed this block (0 = never).
  uint64_t last_update_frame = 0;
  /// Stamp of the last lookup pass that queued this block (BlockLookup de-duplicates its
  /// queue with it instead of sorting every region's finds).
  uint64_t lookup_stamp = 0;
};

static_assert(VoxelBlock::index(0, 7, 7, 7) == 511, "8³ level ends at 511");
static_assert(VoxelBlock::index(1, 0, 0, 0) == 512 && VoxelBlock::index(1, 3, 3, 3) == 575,
              "4³ level occupies 512..575");
static_assert(VoxelBlock::index(2, 0, 0, 0) == 576 && VoxelBlock::index(2, 1, 1, 1) == 583,
              "2³ level occupies 576..583");
static_assert(sizeof(VoxelBlock) <= 584 * 12 + 32, "VoxelBlock must stay ~7 KiB");

}  // namespace stereo_fusion
