#include "stereo_fusion/io/TextureAtlas.h"

#include <algorithm>
#include <numeric>
#include <opencv2/core.hpp>
#include <stdexcept>

namespace stereo_fusion {

AtlasLayout packAtlas(const std::vector<cv::Size>& sizes, int atlas_edge_px, int gutter_px) {
  AtlasLayout layout;
  layout.placements.resize(sizes.size());
  std::vector<size_t> order(sizes.size());
  std::iota(order.begin(), order.end(), 0);
  // Tallest first keeps the shelves tight; ties by width, then index, for a deterministic layout.
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) {
    if (sizes[a].height != sizes[b].height) return sizes[a].height > sizes[b].height;
    return sizes[a].width > sizes[b].width;
  });
  int atlas = -1, shelf_y = 0, shelf_h = 0, cursor_x = 0, used_h = 0;
  auto open_atlas = [&] {
    if (atlas >= 0) layout.atlas_sizes.back().height = used_h;
    ++atlas;
    layout.atlas_sizes.emplace_back(atlas_edge_px, atlas_edge_px);
    shelf_y = shelf_h = cursor_x = used_h = 0;
  };
  open_atlas();
  for (size_t i : order) {
    const int w = sizes[i].width + 2 * gutter_px, h = sizes[i].height + 2 * gutter_px;
    if (w > atlas_edge_px || h > atlas_edge_px)
      throw std::invalid_argument("packAtlas: a patch is larger than the atlas");
    if (cursor_x + w > atlas_edge_px) {  // next shelf
      shelf_y += shelf_h;
      shelf_h = cursor_x = 0;
    }
    if (shelf_y + h > atlas_edge_px) open_atlas();
    layout.placements[i] = {atlas, cv::Rect(cursor_x + gutter_px, shelf_y + gutter_px,
                                            sizes[i].width, sizes[i].height)};
    cursor_x += w;
    shelf_h = std::max(shelf_h, h);
    used_h = std::max(used_h, shelf_y + shelf_h);
  }
  layout.atlas_sizes.back().height = std::max(used_h, 1);
  return layout;
}

std::vector<cv::Mat> renderAtlases(const AtlasLayout& layout, const std::vector<cv::Mat>& patches,
                                   int gutter_px) {
  std::vector<cv::Mat> atlases;
  for (const cv::Size& s : layout.atlas_sizes)
    atlases.emplace_back(s, CV_8UC3, cv::Scalar(0, 0, 0));
  for (size_t i = 0; i < patches.size(); ++i) {
    const AtlasPlacement& p = layout.placements[i];
    cv::Mat framed;
    cv::copyMakeBorder(patches[i], framed, gutter_px, gutter_px, gutter_px, gutter_px,
                       cv::BORDER_REPLICATE);
    framed.copyTo(atlases[p.atlas](
        cv::Rect(p.rect.x - gutter_px, p.rect.y - gutter_px, framed.cols, framed.rows)));
  }
  return atlases;
}

}  // namespace stereo_fusion
