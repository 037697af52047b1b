#include "stereo_fusion/ros/PlanningServices.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace stereo_fusion {

namespace {
float distanceOf(const EsdfSample& s) {
  if (s.state == CellState::kUnknown) return std::numeric_limits<float>::quiet_NaN();
  return static_cast<float>(s.interpolated ? s.interpolated_m : s.distance_m);
}
bool finite(const geometry_msgs::Point& p) {
  return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z);
}
}  // namespace

PlanningServices::PlanningServices(ros::NodeHandle& nh, const NodeConfig& node,
                                   MappingSession* session)
    : node_(node), session_(session) {
  servers_.push_back(nh.advertiseService("get_distance", &PlanningServices::getDistance, this));
  servers_.push_back(nh.advertiseService("get_esdf_box", &PlanningServices::getEsdfBox, this));
}

template <typename Response>
bool PlanningServices::refuse(const char* service, const std::string& why, Response* res) {
  ++refused_;
  res->success = false;
  res->message = why;
  ROS_WARN_THROTTLE(5.0, "stereo_fusion: %s: %s", service, why.c_str());
  return true;
}

bool PlanningServices::sample(const std::vector<Eigen::Vector3d>& points,
                              std::vector<EsdfSample>* samples, double* cell_m, std::string* why) {
  samples->resize(points.size());
  std::vector<Eigen::Vector3d> chunk;
  std::vector<EsdfSample> chunk_samples;
  // The map lock is taken per chunk of kPointsPerLock points (≈ 3 ms of sampling), so a large
  // request lets the frames that wait for the map in between instead of holding them back for
  // its whole length; every point is answered from the map as it was at some moment of the call.
  for (size_t begin = 0; begin == 0 || begin < points.size(); begin += kPointsPerLock) {
    const size_t end = std::min(points.size(), begin + kPointsPerLock);
    chunk.assign(points.begin() + begin, points.begin() + end);
    bool enabled = true;
    const bool got = session_->tryWithMap([&](MapAccess& map) {
      const PlanningMap* planning = map.map().planning();
      if (!planning) {
        enabled = false;
        return;
      }
      *cell_m = planning->grid().cell_m;
      // The answer is the map as it is now: the TSDF changes since the last planning update
      // (at most 1 / planning_publish_rate_hz old, or one chunk) reach the distances first.
      map.updatePlanning();
      planning->sampleBatch(chunk, &chunk_samples);
    });
    if (!got) {
      *why = session_->busyMessage();
      return false;
    }
    if (!enabled) {
      *why = "the planning layer is off (planning_enabled: false)";
      return false;
    }
    std::copy(chunk_samples.begin(), chunk_samples.end(), samples->begin() + begin);
  }
  return true;
}

bool PlanningServices::getDistance(GetDistance::Request& req, GetDistance::Response& res) {
  ++requests_;
  if (req.points.size() > static_cast<size_t>(node_.planning_max_query_points))
    return refuse("get_distance",
                  std::to_string(req.points.size()) +
                      " points, more than planning_max_query_points (" +
                      std::to_string(node_.planning_max_query_points) + ")",
                  &res);
  std::vector<Eigen::Vector3d> points;
  points.reserve(req.points.size());
  for (size_t k = 0; k < req.points.size(); ++k) {
    const geometry_msgs::Point& p = req.points[k];
    if (!finite(p))
      return refuse("get_distance", "point " + std::to_string(k) + " is not finite", &res);
    points.emplace_back(p.x, p.y, p.z);
  }
  std::vector<EsdfSample> samples;
  double cell_m = 0.0;
  std::string why;
  if (!sample(points, &samples, &cell_m, &why)) return refuse("get_distance", why, &res);
  res.distances.resize(samples.size());
  res.gradients.resize(samples.size());
  res.states.resize(samples.size());
  for (size_t k = 0; k < samples.size(); ++k) {
    res.distances[k] = distanceOf(samples[k]);
    res.gradients[k].x = samples[k].gradient.x();
    res.gradients[k].y = samples[k].gradient.y();
    res.gradients[k].z = samples[k].gradient.z();
    res.states[k] = static_cast<uint8_t>(samples[k].state);
  }
  res.success = true;
  res.message = std::to_string(samples.size()) + " points";
  return true;
}

bool PlanningServices::getEsdfBox(GetEsdfBox::Request& req, GetEsdfBox::Response& res) {
  ++requests_;
  if (!finite(req.min) || !finite(req.max))
    return refuse("get_esdf_box", "a corner is not finite", &res);
  if (req.min.x > req.max.x || req.min.y > req.max.y || req.min.z > req.max.z)
    return refuse("get_esdf_box", "min is not below max on every axis", &res);
  if (!std::isfinite(req.resolution_m) || req.resolution_m < 0.0)
    return refuse("get_esdf_box", "resolution_m must be ≥ 0 (0 = the ESDF's cell)", &res);
  double cell_m = 0.0;
  std::string why;
  std::vector<EsdfSample> none;
  if (req.resolution_m == 0.0 && !sample({}, &none, &cell_m, &why))
    return refuse("get_esdf_box", why, &res);
  const double step = req.resolution_m > 0.0 ? req.resolution_m : cell_m;
  const Eigen::Vector3d lo(req.min.x, req.min.y, req.min.z), hi(req.max.x, req.max.y, req.max.z);
  double size[3];
  for (int a = 0; a < 3; ++a) size[a] = std::floor((hi[a] - lo[a]) / step + 1e-9) + 1.0;
  // In doubles first: a tiny resolution over a large box must not overflow before the check.
  const double cells = size[0] * size[1] * size[2];
  if (!(cells <= node_.planning_max_box_cells))
    return refuse("get_esdf_box",
                  "the grid would hold " + std::to_string(cells) +
                      " samples, more than planning_max_box_cells (" +
                      std::to_string(node_.planning_max_box_cells) +
                      "): a coarser resolution_m or a smaller box",
                  &res);
  res.size_x = static_cast<uint32_t>(size[0]);
  res.size_y = static_cast<uint32_t>(size[1]);
  res.size_z = static_cast<uint32_t>(size[2]);
  std::vector<Eigen::Vector3d> points;
  points.reserve(static_cast<size_t>(cells));
  for (uint32_t z = 0; z < res.size_z; ++z)
    for (uint32_t y = 0; y < res.size_y; ++y)
      for (uint32_t x = 0; x < res.size_x; ++x)
        points.push_back(lo + step * Eigen::Vector3d(x, y, z));
  std::vector<EsdfSample> samples;
  if (!sample(points, &samples, &cell_m, &why)) return refuse("get_esdf_box", why, &res);
  res.origin = req.min;
  res.resolution_m = step;
  res.distances.resize(samples.size());
  res.states.resize(samples.size());
  for (size_t k = 0; k < samples.size(); ++k) {
    res.distances[k] = distanceOf(samples[k]);
    res.states[k] = static_cast<uint8_t>(samples[k].state);
  }
  res.success = true;
  res.message = std::to_string(res.size_x) + " × " + std::to_string(res.size_y) + " × " +
                std::to_string(res.size_z) + " samples every " + std::to_string(step) + " m";
  return true;
}

}  // namespace stereo_fusion
