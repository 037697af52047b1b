#pragma once
#include <limits>
#include <vector>

#include "stereo_fusion/map/VoxelBlock.h"
#include "stereo_fusion/planning/PlanningBlock.h"

namespace stereo_fusion {

/// What the TSDF says of one planning cell.
struct TsdfCellState {
  CellIndex cell;
  bool observed = false;  ///< some voxel overlapping the cell is evidence (weight ≥ the minimum)
  bool occupied =
      false;  ///< the finest level with evidence there has an evidence voxel with sdf ≥ 0
  /// The TSDF's signed distance at the cell's centre (m, > 0 behind the surface), interpolated
  /// from the evidence voxels of that level around it; NaN where none lies around the centre.
  /// Where all 8 voxels around the centre are evidence it is divided by the interpolated
  /// gradient's length when that exceeds 1: the TSDF's distances are projective (along the
  /// rays, 1 / cos θ of the Euclidean distance on a surface seen at θ), the ESDF's Euclidean.
  float centre_sdf_m = std::numeric_limits<float>::quiet_NaN();
};

/// The planning cells a TSDF block covers, and their state read from its voxels. A planning cell
/// is `params.voxels_per_cell` (1, 2, 4 or 8) finest voxels wide, so a TSDF block (8 voxels) covers
/// (8 / voxels_per_cell)³ whole cells and every cell lies in exactly one TSDF block.
///
/// Evidence: a voxel counts only once its weight reaches `params.min_weight`:
/// about the number of views that agree on it, less what carving took. One view of one
/// mismatch is no obstacle, and a surface that later views see through loses weight (carving's
/// decay) and sdf until it is free or no evidence again.
///
/// Per cell, the finest level with an evidence voxel overlapping the cell decides (finer levels
/// hold the nearer, more precise views; a coarser level of the same block holds every
/// measurement too, see VoxelBlock): occupied if one of those voxels has sdf ≥ 0 — the cell
/// holds the surface or the band just behind it —, otherwise free (all lie in front of a surface).
/// `block` may be null (an erased block): every cell reads unobserved.
struct TsdfCellParams {
  int voxels_per_cell = 4;  ///< 1, 2, 4 or 8 finest voxels per cell edge
  float voxel_m = 0.02f;    ///< the finest voxel's edge
  float min_weight = 2.0f;  ///< occupancy_min_weight
};
void tsdfCellStates(const BlockKey& tsdf_key, const VoxelBlock* block, const TsdfCellParams& params,
                    std::vector<TsdfCellState>* out);

}  // namespace stereo_fusion
