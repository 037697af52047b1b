#include "evaluator/BatchDistance.h"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace stereo_fusion::eval {
namespace {

constexpr size_t kQueriesPerChunk = 1024;

/// Spreads the low 21 bits of `v` to every third bit.
uint64_t spreadBits(uint64_t v) {
  v &= 0x1FFFFF;
  v = (v | v << 32) & 0x1F00000000FFFFull;
  v = (v | v << 16) & 0x1F0000FF0000FFull;
  v = (v | v << 8) & 0x100F00F00F00F00Full;
  v = (v | v << 4) & 0x10C30C30C30C30C3ull;
  v = (v | v << 2) & 0x1249249249249249ull;
  return v;
}

}  // namespace

std::vector<uint32_t> mortonOrder(const std::vector<Eigen::Vector3d>& points_m) {
  Eigen::Vector3d low = Eigen::Vector3d::Constant(INFINITY);
  Eigen::Vector3d high = Eigen::Vector3d::Constant(-INFINITY);
  for (const Eigen::Vector3d& p : points_m) {
    if (!p.allFinite()) continue;
    low = low.cwiseMin(p);
    high = high.cwiseMax(p);
  }
  const double extent = std::max((high - low).maxCoeff(), 1e-12);
  const double scale = static_cast<double>((1 << 21) - 1) / extent;
  std::vector<std::pair<uint64_t, uint32_t>> keyed(points_m.size());
  for (size_t i = 0; i < points_m.size(); ++i) {
    uint64_t code = 0;  // non-finite points sort first; their order does not matter
    if (points_m[i].allFinite()) {
      const Eigen::Vector3d q = (points_m[i] - low) * scale;
      code = spreadBits(static_cast<uint64_t>(q.x())) |
             spreadBits(static_cast<uint64_t>(q.y())) << 1 |
             spreadBits(static_cast<uint64_t>(q.z())) << 2;
    }
    keyed[i] = {code, static_cast<uint32_t>(i)};
  }
  std::sort(keyed.begin(), keyed.end());
  std::vector<uint32_t> order(keyed.size());
  for (size_t i = 0; i < keyed.size(); ++i) order[i] = keyed[i].second;
  return order;
}

std::vector<double> distancesToSurface(const TriangleBvh& surface,
                                       const std::vector<Eigen::Vector3d>& points_m,
                                       ThreadPool* pool) {
  std::vector<double> distances(points_m.size(), INFINITY);
  if (surface.empty() || points_m.empty()) return distances;
  const std::vector<uint32_t> order = mortonOrder(points_m);
  pool->parallelFor(order.size(), kQueriesPerChunk, [&](size_t begin, size_t end) {
    for (size_t k = begin; k < end; ++k) {
      distances[order[k]] = surface.distance(points_m[order[k]]);
    }
  });
  return distances;
}

}  // namespace stereo_fusion::eval
