// The uniform fast path: a neighbourhood whose present blocks all share the owner's level.
// Only boxes whose support centres are observed and change sign are visited (row bit masks),
// and points are sampled by voxel index; same bits as the general path.
#pragma once
#include "MesherContext.h"

namespace stereo_fusion::mesher {

/// Meshes what the owner owns in a uniform neighbourhood (ctx.uniform), in the general path's
/// box order.
void meshUniformBoxes(MesherContext& ctx);

}  // namespace stereo_fusion::mesher
