#include "stereo_fusion/planning/OccupancyGrid2D.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace stereo_fusion {

namespace {
/// Cells [lo, hi] of one axis of a window of at most `side` cells around `centre`, inside the
/// known [lo, hi]: all of it if it is no wider, else slid inwards where the centre lies near an
/// edge or beyond it.
void windowAxis(int64_t side, int64_t centre, int64_t* lo, int64_t* hi) {
  if (*hi - *lo + 1 <= side) return;
  const int64_t first = std::clamp(centre - side / 2, *lo, *hi - side + 1);
  *lo = first;
  *hi = first + side - 1;
}
}  // namespace

OccupancyGrid2D projectOccupancy(const PlanningMap& planning, double min_z_m, double max_z_m,
                                 const GridWindow& window) {
  OccupancyGrid2D grid;
  const PlanningGrid& g = planning.grid();
  grid.resolution_m = g.cell_m;
  struct Column {
    int32_t x, y;
    CellState state;
  };
  std::vector<Column> columns;
  int64_t x0 = std::numeric_limits<int64_t>::max(), y0 = x0,
          x1 = std::numeric_limits<int64_t>::min(), y1 = x1;
  planning.forEachKnownCell([&](const CellIndex& c, CellState state, double) {
    const double z = g.centre(c).z();
    if (z < min_z_m || z > max_z_m) return;
    columns.push_back({c.x, c.y, state});
    x0 = std::min<int64_t>(x0, c.x), x1 = std::max<int64_t>(x1, c.x);
    y0 = std::min<int64_t>(y0, c.y), y1 = std::max<int64_t>(y1, c.y);
  });
  if (columns.empty()) return grid;
  grid.known_width = x1 - x0 + 1;
  grid.known_height = y1 - y0 + 1;
  // Cells counted in int64: a wide map's extent overflows int32 products long before memory.
  if (window.max_cells > 0 && grid.known_width * grid.known_height > window.max_cells) {
    const auto side = std::max<int64_t>(
        1, static_cast<int64_t>(std::floor(std::sqrt(static_cast<double>(window.max_cells)))));
    const double limit = static_cast<double>(kPlanningCellLimit);
    const auto centreCell = [&](double v_m) {  // a non-finite centre: the origin's cell
      const double cell = std::floor(v_m / g.cell_m);
      return std::isfinite(cell) ? static_cast<int64_t>(std::clamp(cell, -limit, limit)) : 0;
    };
    windowAxis(side, centreCell(window.centre_m.x()), &x0, &x1);
    windowAxis(side, centreCell(window.centre_m.y()), &y0, &y1);
    grid.windowed = true;
  }
  grid.width = static_cast<int>(x1 - x0 + 1);
  grid.height = static_cast<int>(y1 - y0 + 1);
  grid.origin_x_m = static_cast<double>(x0) * g.cell_m;
  grid.origin_y_m = static_cast<double>(y0) * g.cell_m;
  grid.cells.assign(static_cast<size_t>(grid.width) * grid.height, OccupancyGrid2D::kUnknown);
  for (const Column& c : columns) {
    if (c.x < x0 || c.x > x1 || c.y < y0 || c.y > y1) continue;
    int8_t& cell = grid.cells[static_cast<size_t>(c.y - y0) * grid.width + (c.x - x0)];
    if (c.state == CellState::kOccupied)
      cell = OccupancyGrid2D::kOccupied;
    else if (cell == OccupancyGrid2D::kUnknown)
      cell = OccupancyGrid2D::kFree;
  }
  return grid;
}

}  // namespace stereo_fusion
