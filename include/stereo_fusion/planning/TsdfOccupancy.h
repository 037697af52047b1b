#pragma once
#include <vector>

#include "stereo_fusion/map/VoxelBlock.h"
#include "stereo_fusion/planning/PlanningBlock.h"

namespace stereo_fusion {

/// What the TSDF says of one planning cell.
struct TsdfCellState {
  CellIndex cell;
  bool observed = false;  ///< some voxel overlapping the cell is observed (weight > 0)
  bool occupied =
      false;  ///< the finest level observed there has a voxel with sdf ≥ 0 over the cell
};

/// The planning cells a TSDF block covers, and their state read from its voxels. A planning cell
/// is `cells_per_voxel` (1, 2, 4 or 8) finest voxels wide, so a TSDF block (8 voxels) covers
/// (8 / cells_per_voxel)³ whole cells and every cell lies in exactly one TSDF block.
///
/// Per cell, the finest level with an observed voxel overlapping the cell decides (finer levels
/// hold the nearer, more precise views; a coarser level of the same block holds every
/// measurement too, see VoxelBlock): occupied if one of those voxels has sdf ≥ 0 — the cell
/// holds the surface or the band just behind it —, otherwise free (all lie in front of a surface).
/// `block` may be null (an erased block): every cell reads unobserved.
void tsdfCellStates(const BlockKey& tsdf_key, const VoxelBlock* block, int voxels_per_cell,
                    std::vector<TsdfCellState>* out);

}  // namespace stereo_fusion
