// The general path: boxes meshed from cached samples, with hanging points where levels meet
// (BlockMesher.h, "Different levels"). It is the reference the fast paths must match bit for
// bit (MesherPaths::kGeneralOnly), and the mixed path hands it the boxes it cannot reject.
#pragma once
#include "MesherContext.h"

namespace stereo_fusion::mesher {

/// Meshes every box the owner owns, in the order of BoxIntervals (core boxes are pre-tested
/// on the owner's voxel signs only, which decides them exactly).
void meshEveryBox(MesherContext& ctx);

/// Meshes the box [lo, hi]: the case table for a plain box, polygons with hanging points
/// otherwise. Needs ctx.buildLinePoints() for a neighbourhood that is not uniform.
void meshBox(MesherContext& ctx, const int lo[3], const int hi[3]);

/// True if the box has only its 8 corners: nothing on its edges or faces (always in a uniform
/// neighbourhood; otherwise only a box on a block face between levels can carry more).
bool boxIsPlain(const MesherContext& ctx, const int lo[3], const int hi[3]);

}  // namespace stereo_fusion::mesher
