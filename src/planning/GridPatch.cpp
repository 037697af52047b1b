#include "stereo_fusion/planning/GridPatch.h"

#include <algorithm>
#include <climits>

namespace stereo_fusion {

bool applyGridPatch(const GridPatch& patch, OccupancyGrid2D* grid, std::string* error) {
  if (patch.x < 0 || patch.y < 0 || patch.width < 0 || patch.height < 0) {
    *error = "the patch's rectangle has a negative corner or size";
    return false;
  }
  if (static_cast<int64_t>(patch.x) + patch.width > grid->width ||
      static_cast<int64_t>(patch.y) + patch.height > grid->height) {
    *error = "the patch (" + std::to_string(patch.x) + ", " + std::to_string(patch.y) + ") + " +
             std::to_string(patch.width) + " x " + std::to_string(patch.height) +
             " reaches outside the grid of " + std::to_string(grid->width) + " x " +
             std::to_string(grid->height) + " cells";
    return false;
  }
  if (patch.cells.size() != static_cast<size_t>(patch.width) * static_cast<size_t>(patch.height)) {
    *error = "the patch holds " + std::to_string(patch.cells.size()) +
             " cells, not width x height = " +
             std::to_string(static_cast<int64_t>(patch.width) * patch.height);
    return false;
  }
  for (int r = 0; r < patch.height; ++r)
    std::copy_n(patch.cells.begin() + static_cast<size_t>(r) * patch.width, patch.width,
                grid->cells.begin() + static_cast<size_t>(patch.y + r) * grid->width + patch.x);
  return true;
}

std::optional<GridPatch> gridChange(const OccupancyGrid2D& before, const OccupancyGrid2D& after) {
  if (before.resolution_m != after.resolution_m || before.origin_x_m != after.origin_x_m ||
      before.origin_y_m != after.origin_y_m || before.width != after.width ||
      before.height != after.height || before.cells.size() != after.cells.size())
    return std::nullopt;
  int x0 = INT_MAX, y0 = INT_MAX, x1 = -1, y1 = -1;
  for (int y = 0; y < after.height; ++y)
    for (int x = 0; x < after.width; ++x)
      if (before.at(x, y) != after.at(x, y)) {
        x0 = std::min(x0, x), x1 = std::max(x1, x);
        y0 = std::min(y0, y), y1 = std::max(y1, y);
      }
  GridPatch patch;
  if (x1 < 0) return patch;  // nothing changed
  patch.x = x0, patch.y = y0, patch.width = x1 - x0 + 1, patch.height = y1 - y0 + 1;
  patch.cells.reserve(static_cast<size_t>(patch.width) * patch.height);
  for (int y = y0; y <= y1; ++y)
    for (int x = x0; x <= x1; ++x) patch.cells.push_back(after.at(x, y));
  return patch;
}

}  // namespace stereo_fusion
