// The mixed fast path: a neighbourhood with several levels (hanging points on shared faces).
// Boxes are walked as in the general path, but rejected on per-block voxel bit masks before
// any sampling where the masks prove they yield nothing; the rest go to the general meshBox().
#pragma once
#include "MesherContext.h"

namespace stereo_fusion::mesher {

/// Meshes what the owner owns in a neighbourhood that is not uniform, in the general path's
/// box order.
void meshMixedBoxes(MesherContext& ctx);

}  // namespace stereo_fusion::mesher
