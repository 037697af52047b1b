#include "stereo_fusion/planning/OccupancyGrid2D.h"

#include <algorithm>
#include <limits>

namespace stereo_fusion {

OccupancyGrid2D projectOccupancy(const PlanningMap& planning, double min_z_m, double max_z_m) {
  OccupancyGrid2D grid;
  const PlanningGrid& g = planning.grid();
  grid.resolution_m = g.cell_m;
  struct Column {
    int32_t x, y;
    CellState state;
  };
  std::vector<Column> columns;
  int32_t x0 = std::numeric_limits<int32_t>::max(), y0 = x0,
          x1 = std::numeric_limits<int32_t>::min(), y1 = x1;
  planning.forEachKnownCell([&](const CellIndex& c, CellState state, double) {
    const double z = g.centre(c).z();
    if (z < min_z_m || z > max_z_m) return;
    columns.push_back({c.x, c.y, state});
    x0 = std::min(x0, c.x), x1 = std::max(x1, c.x), y0 = std::min(y0, c.y), y1 = std::max(y1, c.y);
  });
  if (columns.empty()) return grid;
  grid.width = x1 - x0 + 1;
  grid.height = y1 - y0 + 1;
  grid.origin_x_m = x0 * g.cell_m;
  grid.origin_y_m = y0 * g.cell_m;
  grid.cells.assign(static_cast<size_t>(grid.width) * grid.height, OccupancyGrid2D::kUnknown);
  for (const Column& c : columns) {
    int8_t& cell = grid.cells[static_cast<size_t>(c.y - y0) * grid.width + (c.x - x0)];
    if (c.state == CellState::kOccupied)
      cell = OccupancyGrid2D::kOccupied;
    else if (cell == OccupancyGrid2D::kUnknown)
      cell = OccupancyGrid2D::kFree;
  }
  return grid;
}

}  // namespace stereo_fusion
