// The planning layer's readers: distances, states and samples (safe from any thread while the
// layer is written; the writers are PlanningMap.cpp's).
#include "stereo_fusion/planning/PlanningMap.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <mutex>

namespace stereo_fusion {

namespace {
constexpr double kMinObstacleDepthM = 1e-3;
}  // namespace

double PlanningMap::signedDistance(const BlockKey& key, const PlanningBlock& block,
                                   int cell) const {
  const uint16_t d2 = block.dist2[cell];
  const bool occupied = PlanningBlock::test(block.occupied, cell);
  if (d2 == PlanningBlock::kNoSite)
    return occupied ? -config_.max_distance_m : config_.max_distance_m;
  // The site's surface lies centre_sdf behind its centre (in front where negative): a free cell
  // reads its distance to that surface, an occupied cell its depth behind it.
  const auto& offset = block.site[cell];
  const CellIndex site = cellOf(key, cell).offset(offset[0], offset[1], offset[2]);
  const BlockKey site_key = planningBlockOf(site);
  const PlanningBlock* site_block = &block;
  if (!(site_key == key)) {
    const auto it = blocks_.find(site_key);
    site_block = it == blocks_.end() ? nullptr : it->second.get();
  }
  const double site_sdf_m =
      site_block ? site_block->centreSdfM(cellInBlock(site), grid_.cell_m) : 0.0;
  const double centres_m = std::sqrt(double(d2)) * grid_.cell_m;
  // An occupied cell reads at least kMinObstacleDepthM deep: its sign must say occupied.
  const double distance = std::clamp(occupied ? centres_m + site_sdf_m : centres_m - site_sdf_m,
                                     occupied ? kMinObstacleDepthM : 0.0, config_.max_distance_m);
  return occupied ? -distance : distance;
}

CellState PlanningMap::state(const Eigen::Vector3d& p_world) const {
  CellIndex cell;
  if (!grid_.cellFor(p_world, &cell)) return CellState::kUnknown;
  std::shared_lock lock(mutex_);
  const auto it = blocks_.find(planningBlockOf(cell));
  return it == blocks_.end() ? CellState::kUnknown : it->second->state(cellInBlock(cell));
}

double PlanningMap::centreSdfM(const CellIndex& cell) const {
  std::shared_lock lock(mutex_);
  const auto it = blocks_.find(planningBlockOf(cell));
  return it == blocks_.end() ? 0.0 : it->second->centreSdfM(cellInBlock(cell), grid_.cell_m);
}

EsdfSample PlanningMap::sampleLocked(const Eigen::Vector3d& p_world) const {
  EsdfSample s;
  s.distance_m = s.interpolated_m = std::numeric_limits<double>::quiet_NaN();
  CellIndex cell;
  if (!grid_.cellFor(p_world, &cell)) return s;
  const auto it = blocks_.find(planningBlockOf(cell));
  if (it == blocks_.end()) return s;
  const int index = cellInBlock(cell);
  s.state = it->second->state(index);
  if (s.state == CellState::kUnknown) return s;
  s.distance_m = s.interpolated_m = signedDistance(it->first, *it->second, index);
  // Trilinear over the 8 cell centres around the point, all of them known.
  const Eigen::Vector3d q = p_world / grid_.cell_m - Eigen::Vector3d::Constant(0.5);
  const Eigen::Vector3d base = q.array().floor();
  const Eigen::Vector3d t = q - base;
  double corner[2][2][2];
  const PlanningBlock* cached = nullptr;
  BlockKey cached_key;
  for (int k = 0; k < 2; ++k)
    for (int j = 0; j < 2; ++j)
      for (int i = 0; i < 2; ++i) {
        const CellIndex c{static_cast<int32_t>(base.x()) + i, static_cast<int32_t>(base.y()) + j,
                          static_cast<int32_t>(base.z()) + k};
        const BlockKey key = planningBlockOf(c);
        if (!cached || !(key == cached_key)) {
          const auto found = blocks_.find(key);
          if (found == blocks_.end()) return s;
          cached = found->second.get();
          cached_key = key;
        }
        if (cached->state(cellInBlock(c)) == CellState::kUnknown) return s;
        corner[k][j][i] = signedDistance(cached_key, *cached, cellInBlock(c));
      }
  double value = 0.0;
  Eigen::Vector3d gradient = Eigen::Vector3d::Zero();
  for (int k = 0; k < 2; ++k)
    for (int j = 0; j < 2; ++j)
      for (int i = 0; i < 2; ++i) {
        const double wx = i ? t.x() : 1 - t.x(), wy = j ? t.y() : 1 - t.y(),
                     wz = k ? t.z() : 1 - t.z();
        const double v = corner[k][j][i];
        value += wx * wy * wz * v;
        gradient.x() += (i ? 1 : -1) * wy * wz * v;
        gradient.y() += (j ? 1 : -1) * wx * wz * v;
        gradient.z() += (k ? 1 : -1) * wx * wy * v;
      }
  s.interpolated_m = value;
  s.gradient = gradient / grid_.cell_m;
  s.interpolated = true;
  return s;
}

EsdfSample PlanningMap::sample(const Eigen::Vector3d& p_world) const {
  std::shared_lock lock(mutex_);
  return sampleLocked(p_world);
}

void PlanningMap::sampleBatch(const std::vector<Eigen::Vector3d>& points,
                              std::vector<EsdfSample>* out) const {
  out->resize(points.size());
  std::shared_lock lock(mutex_);
  // Not on the pool: a reader may run while the integrating thread uses it.
  for (size_t i = 0; i < points.size(); ++i) (*out)[i] = sampleLocked(points[i]);
}

void PlanningMap::forEachKnownCell(
    const std::function<void(const CellIndex&, CellState, double)>& fn) const {
  std::shared_lock lock(mutex_);
  std::vector<BlockKey> keys;
  keys.reserve(blocks_.size());
  for (const auto& [key, block] : blocks_) keys.push_back(key);
  std::sort(keys.begin(), keys.end());
  for (const BlockKey& key : keys) {
    const PlanningBlock& block = *blocks_.at(key);
    for (int cell = 0; cell < PlanningBlock::kCells; ++cell) {
      const CellState state = block.state(cell);
      if (state != CellState::kUnknown)
        fn(cellOf(key, cell), state, signedDistance(key, block, cell));
    }
  }
}

}  // namespace stereo_fusion
