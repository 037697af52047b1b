// BlockMesher::mesh(): gathers an owner's neighbourhood and sends it down one meshing path.
// The paths live in files of their own (MesherGeneralPath, MesherUniformPath,
// MesherMixedPath) over a shared context (MesherContext) and sampler (MesherSampling).
#include "stereo_fusion/mesh/BlockMesher.h"

#include <algorithm>

#include "MesherContext.h"
#include "MesherGeneralPath.h"
#include "MesherMixedPath.h"
#include "MesherUniformPath.h"
#include "stereo_fusion/map/TruncationBand.h"

namespace stereo_fusion {

using mesher::MesherContext;

namespace {

/// Once the neighbourhood is final: whether it is uniform, and the owner's sample grid.
void prepareBoxes(MesherContext& ctx, int owner_level) {
  for (int d = 1; d < 8; ++d)
    if (ctx.nb[d] && ctx.level[d] != owner_level) ctx.uniform = false;
  ctx.buildSampleGrid();
}

}  // namespace

BlockMesher::BlockMesher(const MeshingParams& params, MesherPaths paths)
    : params_(params), paths_(paths) {}

void BlockMesher::mesh(const BlockOctree& map, const MeshStates& states, const VoxelBlock& owner,
                       SubMesh* out, const SeamFills* seam_fills) const {
  out->clear();
  out->key = owner.key;
  const int owner_level = states[owner].level;
  out->level = owner_level;
  thread_local mesher::MeshScratch scratch;
  MesherContext ctx;
  ctx.out = out;
  ctx.scratch = &scratch;
  scratch.vertex_of.clear();
  ctx.unit = params_.voxel_size_m / 2.0;
  ctx.origin[0] = int64_t{owner.key.x} * mesher::kBlockUnits;
  ctx.origin[1] = int64_t{owner.key.y} * mesher::kBlockUnits;
  ctx.origin[2] = int64_t{owner.key.z} * mesher::kBlockUnits;
  bool any_negative = false, any_positive = false;
  int coarsest_level = 0;
  for (int d = 0; d < 8; ++d) {
    ctx.nb[d] = map.neighbour(owner, d & 1, (d >> 1) & 1, (d >> 2) & 1);
    ctx.level[d] = ctx.nb[d] ? states[*ctx.nb[d]].level : 0;
    if (ctx.nb[d] != nullptr) {
      const bool prepared = seam_fills != nullptr && ctx.nb[d]->row < seam_fills->size() &&
                            !(*seam_fills)[*ctx.nb[d]].empty();
      ctx.voxels[d] = prepared ? (*seam_fills)[*ctx.nb[d]].data()
                               : meshVoxels(*ctx.nb[d], states[*ctx.nb[d]], &scratch.seam_fills[d]);
    }
    ctx.step[d] = 1 << ctx.level[d];
    if (ctx.nb[d] == nullptr) continue;
    coarsest_level = std::max(coarsest_level, ctx.level[d]);
    // Of the +neighbour d the owner reads only what lies near its faces towards the owner.
    any_negative |= (states[*ctx.nb[d]].sign_bits & meshSignBit(d, false)) != 0;
    any_positive |= (states[*ctx.nb[d]].sign_bits & meshSignBit(d, true)) != 0;
  }
  ctx.truncated_abs = static_cast<float>(
      0.99 *
      TruncationBand(params_.voxel_size_m, params_.truncation_vox).measurementM(coarsest_level));
  // The one place the paths part. Both give the same bits (test_block_mesher_fast_paths).
  switch (paths_) {
    case MesherPaths::kGeneralOnly:
      prepareBoxes(ctx, owner_level);
      mesher::meshEveryBox(ctx);
      break;
    case MesherPaths::kFast:
      // Every value the mesher uses is a convex combination of observed voxels in these
      // regions: with one sign only, no cell can change sign.
      if (!any_negative || !any_positive) return;
      // A +neighbour with nothing observed where the owner reads it adds only points that are
      // unobserved, present or not: every box with such a point — its own boxes, and any box
      // whose edges or faces it would tile with hanging points (their corners on the shared
      // line weigh it) — gives up either way. Meshing as if it were absent gives the same
      // bits, and a neighbourhood that differed only by it takes the uniform path.
      // (truncated_abs above still counts it: that is what the general path uses.)
      for (int d = 1; d < 8; ++d)
        if (ctx.nb[d] &&
            (states[*ctx.nb[d]].sign_bits & (meshSignBit(d, false) | meshSignBit(d, true))) == 0)
          ctx.nb[d] = nullptr;
      prepareBoxes(ctx, owner_level);
      if (ctx.uniform)
        mesher::meshUniformBoxes(ctx);
      else
        mesher::meshMixedBoxes(ctx);
      break;
  }
  computeVertexNormals(out);
}

}  // namespace stereo_fusion
