#pragma once
#include <optional>
// Texture patches of the submeshes (thesis §3.6 method B), kept beside MeshStore and updated
// after each meshing pass from the frame that was just fused.

#include <unordered_map>
#include <vector>

#include "stereo_fusion/integration/StereoFrame.h"
#include "stereo_fusion/mesh/MeshStore.h"
#include "stereo_fusion/mesh/TexturePatch.h"
#include "stereo_fusion/util/ThreadPool.h"

namespace stereo_fusion {

/// The knobs of texturing (from MapperConfig).
struct TextureParams {
  /// A frame may texture a block only if every vertex projects at least this many pixels
  /// inside the image (thesis: 24 px: stereo is least reliable at the border).
  int border_px = 24;
  /// Cap on a patch's width and height; larger crops are downscaled to fit.
  int max_patch_px = 64;
  /// Occlusion test tolerance: a vertex is hidden when the measured surface is more than
  /// Φ = truncation_vox · s · voxel_size_m (s = 1, 2, 4 by the block's mesh level) in front of
  /// it — the fused surface can lie up to Φ from any one measurement.
  double voxel_size_m = 0.02;
  double truncation_vox = 4.0;
};

/// What one texture pass did.
struct TextureStats {
  size_t retextured = 0;   ///< blocks given a new patch from the current frame
  size_t reprojected = 0;  ///< blocks that kept their patch with UVs re-projected into it
  size_t untextured = 0;   ///< re-meshed blocks left without a patch (vertex colour fallback)
  size_t occluded = 0;  ///< blocks the current frame could not texture because a vertex was hidden
  double texture_ms = 0.0;
};

/// Texture patches keyed by block.
///
/// Choosing the view. For a re-meshed block, a frame is a *candidate* when every vertex of the
/// submesh projects in front of the camera, at least border_px inside the image, and is not
/// occluded (no valid disparity in its 3×3 pixel neighbourhood measures a surface more than Φ
/// in front of the vertex). Its score is the texel density the patch would store:
///
///   score = Σ_front-facing triangles projected area [px²] / Σ_all triangles area [m²] · k²
///
/// where k = min(1, max_patch_px / crop edge) is the downscaling the memory cap imposes.
/// Projected area per surface area ∝ f²·cos θ / z², so the score prefers closer and more
/// frontal views, and it does not depend on how large the submesh is. The current frame
/// replaces the stored patch when it is a candidate and its score beats the stored patch's
/// (re-scored with the new vertices through the stored camera) by more than 10 % — the margin
/// keeps patches from flickering between near-equal views and spares republishing them.
/// Otherwise the stored patch is kept if the new vertices still project inside it; else the
/// block falls back to vertex colour (it has no patch).
class TextureStore {
 public:
  explicit TextureStore(const TextureParams& params) : params_(params) {}

  /// After a meshing pass: updates the patches of `changes.changed` from `frame` (the frame
  /// just fused, `frame_index` its 1-based number) and drops those of `changes.removed`.
  /// A frame without a colour image only re-projects stored patches. Parallel over blocks.
  TextureStats update(const MeshStore& meshes, const MeshChanges& changes, const StereoFrame& frame,
                      uint64_t frame_index, ThreadPool* pool);
  /// Re-projects every stored patch onto the current submeshes (after MeshStore::rebuild) and
  /// drops patches of blocks that no longer have a submesh or no longer fit their patch.
  void reprojectAll(const MeshStore& meshes);

  const std::unordered_map<BlockKey, TexturePatch, BlockKeyHash>& patches() const {
    return patches_;
  }
  /// The patch of `key`, or nullptr (vertex colour).
  const TexturePatch* find(const BlockKey& key) const;
  /// Bytes held by all patches.
  size_t memoryBytes() const;
  void clear() { patches_.clear(); }
  /// Paging: takes the patch of `key` out (nullopt: it has none); attach() puts one back.
  std::optional<TexturePatch> detach(const BlockKey& key);
  void attach(const BlockKey& key, TexturePatch patch) { patches_[key] = std::move(patch); }

 private:
  TextureParams params_;
  std::unordered_map<BlockKey, TexturePatch, BlockKeyHash> patches_;
};

/// Projects a world point through the patch's source camera into the patch's UV convention.
/// False when the point is behind that camera.
bool projectIntoPatch(const TexturePatch& patch, const Eigen::Vector3f& p_world,
                      Eigen::Vector2f* uv);

}  // namespace stereo_fusion
