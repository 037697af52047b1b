#pragma once
// The truncation band Φ of the signed distance field (thesis eq. 3.15): the one definition that
// the lookup (which blocks a measurement reaches), fusion (which voxels it updates, and its
// skip tests), the mesher (which sign changes are band edges, not surfaces) and the texture
// pass share, so that a fast path's "no update possible" proof and the update agree.

#include <algorithm>

#include "stereo_fusion/map/ResolutionLevel.h"

namespace stereo_fusion {

class TruncationBand {
 public:
  /// Minimum half-width of the band a measurement leaves in a coarser level, in that level's
  /// voxels: a coarse level fed by near measurements still needs values on both sides of the
  /// surface at its own spacing. (A band of truncation_vox coarse voxels would be thicker than
  /// small objects and let views disagree about their far side.)
  static constexpr float kMinVoxelsOfUpdatedLevel = 2.0f;

  TruncationBand(double voxel_size_m, double truncation_vox)
      : voxel_size_m_(voxel_size_m), truncation_vox_(truncation_vox) {}

  /// Φ of a measurement whose depth selects `measurement_level` (eq. 3.2): truncation_vox
  /// voxels of that level. The lookup queues the blocks within Φ of the measured surface along
  /// the ray; the mesher and the textures read a block's Φ at its mesh level from here.
  template <typename T = double>
  T measurementM(int measurement_level) const {
    return static_cast<T>(truncation_vox_) * static_cast<T>(levelScale(measurement_level)) *
           static_cast<T>(voxel_size_m_);
  }

  /// Φ that a measurement of `measurement_level` applies to the voxels of `voxel_level`:
  /// measurementM(), but never less than kMinVoxelsOfUpdatedLevel voxels of `voxel_level`.
  /// (T = float: the fusion kernels' values, rounded in this order.)
  template <typename T = double>
  T updateM(int measurement_level, int voxel_level) const {
    const T level_voxel_m = static_cast<T>(voxel_size_m_) * static_cast<T>(levelScale(voxel_level));
    return std::max(measurementM<T>(measurement_level),
                    static_cast<T>(kMinVoxelsOfUpdatedLevel) * level_voxel_m);
  }

  /// The widest band of any measurement on any level: how far from a surface any voxel can be
  /// updated (the block-level skip tests' bound).
  template <typename T = double>
  T maxM() const {
    return std::max(static_cast<T>(truncation_vox_), static_cast<T>(kMinVoxelsOfUpdatedLevel)) *
           static_cast<T>(levelScale(kNumLevels - 1)) * static_cast<T>(voxel_size_m_);
  }

  double voxelSizeM() const { return voxel_size_m_; }
  double truncationVox() const { return truncation_vox_; }

 private:
  double voxel_size_m_;
  double truncation_vox_;
};

}  // namespace stereo_fusion
