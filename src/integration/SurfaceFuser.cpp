#include "stereo_fusion/integration/SurfaceFuser.h"

#include <stdexcept>

#include "stereo_fusion/integration/FusionKernels.h"

namespace stereo_fusion {

SurfaceFuser::SurfaceFuser(const FusionConfig& config, ThreadPool* pool)
    : config_(config), pool_(pool), use_avx2_(avx2Supported()) {}

void SurfaceFuser::setKernel(Kernel kernel) {
  if (kernel == Kernel::kAvx2 && !avx2Supported())
    throw std::invalid_argument("SurfaceFuser: this CPU has no AVX2");
  use_avx2_ = kernel == Kernel::kAvx2 || (kernel == Kernel::kAuto && avx2Supported());
}

FusionStats SurfaceFuser::fuse(const StereoFrame& frame, const MeasurementImage& measurements,
                               const BlockOctree& octree, const std::vector<VoxelBlock*>& blocks,
                               std::vector<VoxelBlock*>* updated) {
  return fuse(frame, measurements, octree, blocks, {}, updated, nullptr);
}

FusionStats SurfaceFuser::fuse(const StereoFrame& frame, const MeasurementImage& measurements,
                               const BlockOctree& octree, const std::vector<VoxelBlock*>& blocks,
                               const std::vector<BlockKey>& missing,
                               std::vector<VoxelBlock*>* updated,
                               std::vector<std::unique_ptr<VoxelBlock>>* created) {
  FusionStats stats;
  updated->clear();
  if (created) created->clear();
  const size_t total = blocks.size() + (created ? missing.size() : 0);
  if (total == 0) return stats;
  FusionFrame fusion_frame = makeFusionFrame(frame, config_, measurements);
  if (use_avx2_) {  // only the AVX2 kernel uses the tiles; the scalar one stays the plain reference
    tiles_.build(measurements.depths(), measurements.width(), measurements.height(),
                 fusion_frame.level1_min_depth_m, fusion_frame.level2_min_depth_m, pool_);
    fusion_frame.tiles = &tiles_;
  }
  const auto fuse_block = use_avx2_ ? fuseBlockAvx2 : fuseBlockScalar;
  per_block_updates_.assign(total, 0);
  per_block_new_bytes_.assign(total, 0);
  candidates_.resize(total - blocks.size());
  pool_->parallelFor(total, 8, [&](size_t begin, size_t end) {
    for (size_t b = begin; b < end; ++b) {
      VoxelBlock* block;
      if (b < blocks.size()) {
        block = blocks[b];
      } else {  // a missing key: a block of its own, kept only if updated
        std::unique_ptr<VoxelBlock>& candidate = candidates_[b - blocks.size()];
        if (!candidate) candidate = std::make_unique<VoxelBlock>();
        candidate->key = missing[b - blocks.size()];
        block = candidate.get();
      }
      const size_t bytes_before = block->voxelBytes();
      per_block_updates_[b] = fuse_block(fusion_frame, octree, block);
      per_block_new_bytes_[b] = block->voxelBytes() - bytes_before;
    }
  });
  for (size_t b = 0; b < total; ++b) {
    if (per_block_updates_[b] == 0) {
      stats.blocks_not_created += b >= blocks.size();
      continue;  // a candidate not updated holds no level: it is reused as it is next frame
    }
    stats.voxels_updated += per_block_updates_[b];
    stats.level_bytes_allocated += per_block_new_bytes_[b];
    ++stats.blocks_updated;
    if (b < blocks.size())
      updated->push_back(blocks[b]);
    else
      created->push_back(std::move(candidates_[b - blocks.size()]));
  }
  stats.blocks_created = created ? created->size() : 0;
  return stats;
}

}  // namespace stereo_fusion
