// The per-block mesh level and sign bits (declared in BlockMesher.h). They run on the fusion
// workers for every updated block, apart from the mesher itself.

#include <algorithm>

#include "stereo_fusion/mesh/BlockMesher.h"

namespace stereo_fusion {

int chooseMeshLevel(const VoxelBlock& block, double level_min_coverage) {
  // Observed surface area of each level, in finest-voxel units: a level's band is
  // truncation_vox of its own voxels thick, so area ≈ observed volume / thickness ∝ n · s².
  // Areas, not voxel shares: a coarse centre can miss the band that finer centres near the
  // block's faces catch, so no level is assumed to contain another.
  double area[kNumLevels];
  double largest = 0.0;
  for (int level = 0; level < kNumLevels; ++level) {
    int observed = 0;
    for (int n = 0; n < levelVoxelCount(level); ++n)
      observed += block.voxels[levelOffset(level) + n].weight > 0.0f;
    const double scale = levelScale(level);
    area[level] = observed * scale * scale;
    largest = std::max(largest, area[level]);
  }
  for (int level = 0; level < kNumLevels; ++level)
    if (largest > 0.0 && area[level] >= level_min_coverage * largest) return level;
  return kNumLevels - 1;
}

void refreshMeshSigns(VoxelBlock* block) {
  const int level = block->mesh_level;
  const int side = levelSide(level), step = levelScale(level);
  // The owners below reach at most 4 half-voxel units into this block (the coarsest level's
  // first centre), where blockField() weighs up to the next centre beyond: every voxel they
  // can read has its centre below 8 units, i.e. within 4 finest voxels of the face.
  auto near_low_face = [step](int i) { return step * (2 * i + 1) < 8 ? 1 : 0; };
  uint16_t seen[8] = {};  // by the axes a voxel is near the low face on: its signs (region-0 bits)
  for (int k = 0; k < side; ++k)
    for (int j = 0; j < side; ++j)
      for (int i = 0; i < side; ++i) {
        const Voxel& v = block->at(level, i, j, k);
        if (!(v.weight > 0.0f)) continue;
        // A value in [−1e-30, 0) counts as both signs: the mesher's weighted sums can round it
        // to −0, which compares as non-negative.
        const uint16_t sign = v.sdf_m >= 0.0f ? meshSignBit(0, true)
                              : v.sdf_m < -1e-30f ? meshSignBit(0, false)
                                                  : static_cast<uint16_t>(meshSignBit(0, false) | meshSignBit(0, true));
        seen[near_low_face(i) | 2 * near_low_face(j) | 4 * near_low_face(k)] |= sign;
      }
  // Region r holds the voxels near the low face on every axis of r.
  uint16_t bits = 0;
  for (int region = 0; region < 8; ++region)
    for (int near = 0; near < 8; ++near)
      if ((region & near) == region) bits |= static_cast<uint16_t>(seen[near] << (2 * region));
  block->mesh_sign_bits = bits;
}

void refreshMeshLevel(VoxelBlock* block, double level_min_coverage) {
  block->mesh_level = static_cast<int8_t>(chooseMeshLevel(*block, level_min_coverage));
  refreshMeshSigns(block);
}

}  // namespace stereo_fusion
