#include "evaluator/OccupancyScore.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include <Eigen/Geometry>  // cross()

namespace stereo_fusion::eval {

namespace {

/// Calls `f(point, wall)` for points on a grid of at most `step_m` over every triangle that
/// reaches into [min_z_m, max_z_m], keeping those in it; `wall`: the triangle's |n_z| is below
/// `wall_max_abs_normal_z`.
template <typename F>
void forEachSurfacePointInBand(const TriangleMesh& mesh, const OccupancyScoreOptions& o, F f) {
  const size_t n_positions = mesh.positions.size();
  for (const auto& t : mesh.triangles) {
    if (t[0] >= n_positions || t[1] >= n_positions || t[2] >= n_positions) continue;
    const Eigen::Vector3d a = mesh.positions[t[0]].cast<double>(),
                          b = mesh.positions[t[1]].cast<double>(),
                          c = mesh.positions[t[2]].cast<double>();
    if (std::max({a.z(), b.z(), c.z()}) < o.min_z_m || std::min({a.z(), b.z(), c.z()}) > o.max_z_m)
      continue;
    const Eigen::Vector3d normal = (b - a).cross(c - a);
    const double length = normal.norm();
    const bool wall = length > 0.0 && std::abs(normal.z()) < o.wall_max_abs_normal_z * length;
    const double longest = std::max({(b - a).norm(), (c - a).norm(), (c - b).norm()});
    const int n = std::max(1, static_cast<int>(std::ceil(longest / o.sample_step_m)));
    for (int i = 0; i <= n; ++i)
      for (int j = 0; i + j <= n; ++j) {
        const Eigen::Vector3d p = a + (b - a) * (double(i) / n) + (c - a) * (double(j) / n);
        if (p.z() >= o.min_z_m && p.z() <= o.max_z_m) f(p, wall);
      }
  }
}

}  // namespace

namespace {
/// Whether the vertical through (x, y) lies inside a solid at some height of the band (sampled
/// every 2 cm).
bool columnInsideSolid(const SolidTruth& solid, double x, double y,
                       const OccupancyScoreOptions& o) {
  for (double z = o.min_z_m; z <= o.max_z_m + 1e-9; z += 0.02)
    if (solid.signedDistance({x, y, z}) < 0.0) return true;
  return false;
}
}  // namespace

OccupancyScore scoreOccupancy(const OccupancyMap& map, const TriangleMesh& truth,
                              const OccupancyScoreOptions& options, const SolidTruth* solid) {
  OccupancyScore score;
  score.options = options;
  if (map.width <= 0 || map.height <= 0 || !(map.resolution_m > 0.0)) return score;
  const double res = map.resolution_m, reach = options.reach_m + 1e-9;
  // Pixels k apart along an axis leave a gap of (k − 1) cells between their squares.
  const int k_max = static_cast<int>(std::floor(reach / res)) + 1;
  std::vector<std::pair<int, int>> neighbours;
  for (int dy = -k_max; dy <= k_max; ++dy)
    for (int dx = -k_max; dx <= k_max; ++dx)
      if (res * std::hypot(std::max(0, std::abs(dx) - 1), std::max(0, std::abs(dy) - 1)) <= reach)
        neighbours.emplace_back(dx, dy);
  // The obstacle raster reaches k_max pixels past the map: a wall just outside its edge still
  // has the edge's pixels within reach.
  const int m = k_max, raster_w = map.width + 2 * m, raster_h = map.height + 2 * m;
  std::vector<uint8_t> obstacle(static_cast<size_t>(raster_w) * raster_h, 0);
  std::vector<uint8_t> on_surface(map.cells.size(), 0);
  forEachSurfacePointInBand(truth, options, [&](const Eigen::Vector3d& p, bool wall) {
    const double u = (p.x() - map.origin_x_m) / res, v = (p.y() - map.origin_y_m) / res;
    if (wall) {
      const int rx = static_cast<int>(std::floor(u)) + m, ry = static_cast<int>(std::floor(v)) + m;
      if (rx >= 0 && ry >= 0 && rx < raster_w && ry < raster_h)
        obstacle[static_cast<size_t>(ry) * raster_w + rx] = 1;
    }
    const int x0 = std::max(0, static_cast<int>(std::floor(u - reach / res)) - 1),
              x1 = std::min(map.width - 1, static_cast<int>(std::floor(u + reach / res))),
              y0 = std::max(0, static_cast<int>(std::floor(v - reach / res)) - 1),
              y1 = std::min(map.height - 1, static_cast<int>(std::floor(v + reach / res)));
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) {
        // Horizontal distance from the point to the pixel's square.
        const double gx = std::max({0.0, x - u, u - (x + 1)}),
                     gy = std::max({0.0, y - v, v - (y + 1)});
        if (res * std::hypot(gx, gy) <= reach)
          on_surface[static_cast<size_t>(y) * map.width + x] = 1;
      }
  });
  for (size_t i = 0; i < map.cells.size(); ++i)
    if (map.cells[i] == OccupancyMap::kOccupied) {
      ++score.occupied_pixels;
      const int x = static_cast<int>(i % map.width), y = static_cast<int>(i / map.width);
      const bool right =
          on_surface[i] || (solid && columnInsideSolid(*solid, map.origin_x_m + (x + 0.5) * res,
                                                       map.origin_y_m + (y + 0.5) * res, options));
      score.occupied_on_surface += right;
      if (!right) score.false_pixels.emplace_back(x, y);
    }
  for (int ry = 0; ry < raster_h; ++ry)
    for (int rx = 0; rx < raster_w; ++rx) {
      if (!obstacle[static_cast<size_t>(ry) * raster_w + rx]) continue;
      bool known = false, occupied = false;
      for (const auto& [dx, dy] : neighbours) {
        const int x = rx - m + dx, y = ry - m + dy;
        if (x < 0 || y < 0 || x >= map.width || y >= map.height) continue;
        const int8_t cell = map.at(x, y);
        known |= cell != OccupancyMap::kUnknown;
        occupied |= cell == OccupancyMap::kOccupied;
      }
      if (!known) {
        ++score.obstacle_pixels_unknown;
        continue;
      }
      ++score.obstacle_pixels_known;
      score.obstacle_pixels_found += occupied;
    }
  return score;
}

double OccupancyScore::precision() const {
  return occupied_pixels == 0 ? 0.0 : double(occupied_on_surface) / occupied_pixels;
}

double OccupancyScore::wallRecall() const {
  return obstacle_pixels_known == 0 ? 0.0 : double(obstacle_pixels_found) / obstacle_pixels_known;
}

std::string OccupancyScore::describe(const std::string& name, const std::string& band_from) const {
  char text[512];
  std::snprintf(text, sizeof(text),
                "  %s (z %.2f-%.2f m from %s, within %.0f cm): precision %.1f %% (%zu/%zu), wall "
                "recall %.1f %% (%zu/%zu; %zu wall pixels unseen)\n",
                name.c_str(), options.min_z_m, options.max_z_m, band_from.c_str(),
                100.0 * options.reach_m, 100.0 * precision(), occupied_on_surface, occupied_pixels,
                100.0 * wallRecall(), obstacle_pixels_found, obstacle_pixels_known,
                obstacle_pixels_unknown);
  return text;
}

}  // namespace stereo_fusion::eval
