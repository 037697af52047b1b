#include "stereo_fusion/planning/FleetGridMerge.h"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace stereo_fusion {

namespace {

/// Corners closer than this (in cells) to a lattice line snap to it: a footprint edge that lies
/// on the lattice must not add a column of cells whose centres are outside it (0.3 / 0.1 is
/// 2.9999999999999996 in doubles).
constexpr double kSnapCells = 1e-6;
/// A footprint coordinate beyond ±2⁵⁰ cells is a bad pose, not a map: past it, cell indices lose
/// exactness in doubles.
constexpr double kMaxLatticeIndex = 1125899906842624.0;
constexpr int64_t kMaxCellsLimit = 1000000000;

/// Cells of the operator lattice (cell i spans [i, i + 1) · resolution): columns [x0, x1),
/// rows [y0, y1).
struct LatticeRect {
  int64_t x0 = 0, y0 = 0, x1 = 0, y1 = 0;
};

int rank(int8_t v) { return v < 0 ? 0 : (v == 0 ? 1 : 2); }

constexpr int8_t kByRank[3] = {OccupancyGrid2D::kUnknown, OccupancyGrid2D::kFree,
                               OccupancyGrid2D::kOccupied};

/// Why a robot's grid or pose cannot be merged, or empty.
std::string robotProblem(const FleetGridInput& in, double max_tilt_rad) {
  if (in.grid == nullptr) return "no grid";
  const OccupancyGrid2D& g = *in.grid;
  if (!(std::isfinite(g.resolution_m) && g.resolution_m > 0.0))
    return "its grid's resolution is not a finite number of metres > 0";
  if (g.width < 0 || g.height < 0) return "its grid has a negative width or height";
  if (g.cells.size() != static_cast<size_t>(g.width) * static_cast<size_t>(g.height))
    return "its grid holds " + std::to_string(g.cells.size()) + " cells, not width x height = " +
           std::to_string(static_cast<int64_t>(g.width) * g.height);
  if (!std::isfinite(g.origin_x_m) || !std::isfinite(g.origin_y_m))
    return "its grid's origin is not finite";
  const PlanarPose& p = in.T_operator_robot;
  if (!std::isfinite(p.x_m) || !std::isfinite(p.y_m) || !std::isfinite(p.yaw_rad) ||
      !std::isfinite(p.tilt_rad))
    return "its pose in the operator frame is not finite";
  if (p.tilt_rad > max_tilt_rad) {
    std::ostringstream s;
    s << "its map frame is tilted " << p.tilt_rad << " rad against the operator frame, more than "
      << "max_tilt_rad " << max_tilt_rad << ": its grid's columns are not vertical there";
    return s.str();
  }
  return {};
}

bool hasCells(const FleetGridInput& in) { return in.grid->width > 0 && in.grid->height > 0; }

/// The lattice cells covering the robot grid's transformed footprint; nullopt beyond the
/// lattice's exact range. The input is valid and has cells.
std::optional<LatticeRect> footprint(const FleetGridInput& in, double resolution_m) {
  const OccupancyGrid2D& g = *in.grid;
  const PlanarPose& p = in.T_operator_robot;
  const double c = std::cos(p.yaw_rad), s = std::sin(p.yaw_rad);
  const double xs[2] = {g.origin_x_m, g.origin_x_m + g.width * g.resolution_m};
  const double ys[2] = {g.origin_y_m, g.origin_y_m + g.height * g.resolution_m};
  double min_x = INFINITY, min_y = INFINITY, max_x = -INFINITY, max_y = -INFINITY;
  for (double x : xs)
    for (double y : ys) {
      const double ox = (c * x - s * y + p.x_m) / resolution_m;
      const double oy = (s * x + c * y + p.y_m) / resolution_m;
      min_x = std::min(min_x, ox), max_x = std::max(max_x, ox);
      min_y = std::min(min_y, oy), max_y = std::max(max_y, oy);
    }
  for (double v : {min_x, min_y, max_x, max_y})
    if (!(std::abs(v) < kMaxLatticeIndex)) return std::nullopt;
  LatticeRect r;
  r.x0 = static_cast<int64_t>(std::floor(min_x + kSnapCells));
  r.y0 = static_cast<int64_t>(std::floor(min_y + kSnapCells));
  r.x1 = std::max(r.x0, static_cast<int64_t>(std::ceil(max_x - kSnapCells)));
  r.y1 = std::max(r.y0, static_cast<int64_t>(std::ceil(max_y - kSnapCells)));
  return r;
}

/// The lattice index of `merged`'s cell (0, 0).
int64_t latticeIndex(double origin_m, double resolution_m) {
  return std::llround(origin_m / resolution_m);
}

/// Combines the robot's samples into the cells of `window` (clipped to the robot's footprint
/// `fp`) of `merged`.
void sampleRobot(const FleetGridInput& in, const LatticeRect& fp, const GridCellWindow& window,
                 OccupancyGrid2D* merged) {
  const double res = merged->resolution_m;
  const int64_t gx0 = latticeIndex(merged->origin_x_m, res);
  const int64_t gy0 = latticeIndex(merged->origin_y_m, res);
  const int64_t x0 = std::max<int64_t>(window.x0, fp.x0 - gx0);
  const int64_t x1 = std::min<int64_t>(window.x1, fp.x1 - gx0);
  const int64_t y0 = std::max<int64_t>(window.y0, fp.y0 - gy0);
  const int64_t y1 = std::min<int64_t>(window.y1, fp.y1 - gy0);
  const OccupancyGrid2D& g = *in.grid;
  const PlanarPose& p = in.T_operator_robot;
  const double c = std::cos(p.yaw_rad), s = std::sin(p.yaw_rad);
  for (int64_t j = y0; j < y1; ++j) {
    const double dy = (static_cast<double>(gy0 + j) + 0.5) * res - p.y_m;
    for (int64_t i = x0; i < x1; ++i) {
      const double dx = (static_cast<double>(gx0 + i) + 0.5) * res - p.x_m;
      // The centre in the robot's map frame: Rᵀ(c − t).
      const double u = std::floor((c * dx + s * dy - g.origin_x_m) / g.resolution_m);
      const double v = std::floor((-s * dx + c * dy - g.origin_y_m) / g.resolution_m);
      if (!(u >= 0.0 && u < g.width && v >= 0.0 && v < g.height)) continue;
      const int r = rank(g.at(static_cast<int>(u), static_cast<int>(v)));
      int8_t& cell = merged->cells[static_cast<size_t>(j) * merged->width + i];
      if (r > rank(cell)) cell = kByRank[r];
    }
  }
}

GridCellWindow clip(GridCellWindow w, const OccupancyGrid2D& grid) {
  w.x0 = std::max(w.x0, 0), w.y0 = std::max(w.y0, 0);
  w.x1 = std::min(w.x1, grid.width), w.y1 = std::min(w.y1, grid.height);
  return w;
}

}  // namespace

std::vector<std::string> validateFleetGridMergeConfig(const FleetGridMergeConfig& config) {
  std::vector<std::string> errors;
  if (!(std::isfinite(config.resolution_m) && config.resolution_m > 0.0))
    errors.push_back("fleet grid resolution_m must be a finite number of metres > 0");
  if (config.max_cells <= 0 || config.max_cells > kMaxCellsLimit)
    errors.push_back("fleet grid max_cells must be in [1, " + std::to_string(kMaxCellsLimit) + "]");
  if (!(config.max_tilt_rad >= 0.0 && config.max_tilt_rad < M_PI / 2))
    errors.push_back("fleet grid max_tilt_rad must be in [0, pi/2) radians");
  return errors;
}

PlanarPose planarPose(const Eigen::Isometry3d& T_operator_robot) {
  const Eigen::Matrix3d R = T_operator_robot.linear();
  PlanarPose p;
  p.x_m = T_operator_robot.translation().x();
  p.y_m = T_operator_robot.translation().y();
  p.yaw_rad = std::atan2(R(1, 0) - R(0, 1), R(0, 0) + R(1, 1));
  p.tilt_rad = std::acos(std::clamp(R(2, 2), -1.0, 1.0));
  return p;
}

FleetGridMerge::FleetGridMerge(const FleetGridMergeConfig& config) : config_(config) {}

FleetGridMergeResult FleetGridMerge::merge(const std::vector<FleetGridInput>& robots) const {
  FleetGridMergeResult result;
  result.grid.resolution_m = config_.resolution_m;
  bool any = false;
  LatticeRect bounds;
  for (size_t k = 0; k < robots.size(); ++k) {
    const std::string problem = robotProblem(robots[k], config_.max_tilt_rad);
    if (!problem.empty()) {
      result.robots_refused.push_back({k, problem});
      continue;
    }
    if (!hasCells(robots[k])) {
      ++result.robots_empty;
      continue;
    }
    const std::optional<LatticeRect> fp = footprint(robots[k], config_.resolution_m);
    if (!fp) {
      result.robots_refused.push_back(
          {k, "its grid lies beyond 2^50 cells of the operator origin"});
      continue;
    }
    ++result.robots_merged;
    if (!any) {
      bounds = *fp;
      any = true;
    } else {
      bounds.x0 = std::min(bounds.x0, fp->x0), bounds.y0 = std::min(bounds.y0, fp->y0);
      bounds.x1 = std::max(bounds.x1, fp->x1), bounds.y1 = std::max(bounds.y1, fp->y1);
    }
  }
  if (!any) return result;
  const int64_t width = bounds.x1 - bounds.x0, height = bounds.y1 - bounds.y0;
  // In doubles: two spans of up to 2⁵¹ cells overflow an int64 product.
  const double cells = static_cast<double>(width) * static_cast<double>(height);
  if (cells > static_cast<double>(config_.max_cells)) {
    std::ostringstream s;
    s << "the merged grid would be " << width << " x " << height << " cells (" << cells
      << "), more than max_cells " << config_.max_cells << ": the robots' grids span x ["
      << bounds.x0 * config_.resolution_m << ", " << bounds.x1 * config_.resolution_m << "] m, y ["
      << bounds.y0 * config_.resolution_m << ", " << bounds.y1 * config_.resolution_m
      << "] m of the operator frame (a robot placed far away by its alignment?)";
    result.error = s.str();
    result.robots_merged = 0;
    return result;
  }
  OccupancyGrid2D& g = result.grid;
  g.origin_x_m = static_cast<double>(bounds.x0) * config_.resolution_m;
  g.origin_y_m = static_cast<double>(bounds.y0) * config_.resolution_m;
  g.width = static_cast<int>(width);
  g.height = static_cast<int>(height);
  g.known_width = width;
  g.known_height = height;
  g.cells.assign(static_cast<size_t>(width) * static_cast<size_t>(height),
                 OccupancyGrid2D::kUnknown);
  remergeWindow(robots, {0, 0, g.width, g.height}, &g);
  return result;
}

void FleetGridMerge::remergeWindow(const std::vector<FleetGridInput>& robots,
                                   const GridCellWindow& window, OccupancyGrid2D* merged) const {
  const GridCellWindow w = clip(window, *merged);
  if (w.empty()) return;
  for (int y = w.y0; y < w.y1; ++y)
    std::fill_n(merged->cells.begin() + static_cast<ptrdiff_t>(y) * merged->width + w.x0,
                w.x1 - w.x0, OccupancyGrid2D::kUnknown);
  for (const FleetGridInput& robot : robots) {
    if (!robotProblem(robot, config_.max_tilt_rad).empty() || !hasCells(robot)) continue;
    const std::optional<LatticeRect> fp = footprint(robot, merged->resolution_m);
    if (fp) sampleRobot(robot, *fp, w, merged);
  }
}

std::optional<GridCellWindow> FleetGridMerge::changedWindow(const FleetGridInput& before,
                                                            const FleetGridInput& after,
                                                            const OccupancyGrid2D& merged) const {
  const double res = merged.resolution_m;
  const int64_t gx0 = latticeIndex(merged.origin_x_m, res);
  const int64_t gy0 = latticeIndex(merged.origin_y_m, res);
  const auto local = [&](const LatticeRect& r) {  // clipped to merged, so the casts hold
    GridCellWindow w;
    w.x0 = static_cast<int>(std::clamp<int64_t>(r.x0 - gx0, 0, merged.width));
    w.x1 = static_cast<int>(std::clamp<int64_t>(r.x1 - gx0, 0, merged.width));
    w.y0 = static_cast<int>(std::clamp<int64_t>(r.y0 - gy0, 0, merged.height));
    w.y1 = static_cast<int>(std::clamp<int64_t>(r.y1 - gy0, 0, merged.height));
    return w;
  };
  GridCellWindow window;
  if (!robotProblem(after, config_.max_tilt_rad).empty()) return std::nullopt;
  if (hasCells(after)) {
    const std::optional<LatticeRect> fp = footprint(after, res);
    if (!fp || fp->x0 < gx0 || fp->y0 < gy0 || fp->x1 > gx0 + merged.width ||
        fp->y1 > gy0 + merged.height)
      return std::nullopt;
    window = local(*fp);
  }
  if (robotProblem(before, config_.max_tilt_rad).empty() && hasCells(before)) {
    if (const std::optional<LatticeRect> fp = footprint(before, res)) {
      const GridCellWindow b = local(*fp);
      if (window.empty()) {
        window = b;
      } else if (!b.empty()) {
        window.x0 = std::min(window.x0, b.x0), window.y0 = std::min(window.y0, b.y0);
        window.x1 = std::max(window.x1, b.x1), window.y1 = std::max(window.y1, b.y1);
      }
    }
  }
  return window;
}

}  // namespace stereo_fusion
