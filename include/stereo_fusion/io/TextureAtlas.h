#pragma once
// Packs texture patches into a few large images (atlases) for export.

#include <opencv2/core/mat.hpp>
#include <vector>

namespace stereo_fusion {

/// Where one patch went: atlas image `atlas`, its texels at [x, x + width) × [y, y + height).
struct AtlasPlacement {
  int atlas = 0;
  cv::Rect rect;
};

/// Shelf packing: patches sorted by decreasing height fill rows left to right; a row that is
/// full opens the next one, an atlas that is full opens the next atlas. Every patch gets
/// `gutter_px` free texels on each side (filled with its replicated border when rendered, so
/// bilinear and mip-mapped sampling near a patch edge never reads a neighbour). Placements of
/// different patches, gutters included, are disjoint. Patches larger than the atlas (gutter
/// included) are not allowed (the texture cap keeps them far smaller).
struct AtlasLayout {
  std::vector<AtlasPlacement> placements;  ///< one per input size, in input order
  std::vector<cv::Size> atlas_sizes;  ///< width = atlas_edge_px; height trimmed to the used rows
};

/// Lays out `sizes` in atlases of at most atlas_edge_px × atlas_edge_px.
AtlasLayout packAtlas(const std::vector<cv::Size>& sizes, int atlas_edge_px, int gutter_px);

/// Renders the atlas images (CV_8UC3, RGB) of `layout` from `patches` (RGB, in the order of
/// the sizes given to packAtlas); gutters hold the patch's replicated border.
std::vector<cv::Mat> renderAtlases(const AtlasLayout& layout, const std::vector<cv::Mat>& patches,
                                   int gutter_px);

}  // namespace stereo_fusion
