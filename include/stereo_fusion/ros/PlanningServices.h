#pragma once
// The planning layer's services: ~get_distance (points → distances, gradients, states) and
// ~get_esdf_box (a dense grid of distances in a box). Both bring the planning layer up to date
// with the map first (what changed since the planning publisher's last update) and sample it
// under the map lock, taken per kPointsPerLock points (≈ 3 ms each), so fusion waits at most that
// long for a request; each time they wait at most max_request_wait_s for the lock (then "busy").
#include <ros/ros.h>
#include <stereo_fusion/GetDistance.h>
#include <stereo_fusion/GetEsdfBox.h>

#include <atomic>
#include <vector>

#include "stereo_fusion/ros/RosParameters.h"
#include "stereo_fusion/session/MappingSession.h"

namespace stereo_fusion {

class PlanningServices {
 public:
  PlanningServices(ros::NodeHandle& service_nh, const NodeConfig& node, MappingSession* session);

  /// Points sampled per hold of the map lock (≈ 0.1 µs each).
  static constexpr size_t kPointsPerLock = 25000;

  uint64_t requests() const { return requests_.load(); }
  uint64_t refused() const { return refused_.load(); }

 private:
  bool getDistance(GetDistance::Request& req, GetDistance::Response& res);
  bool getEsdfBox(GetEsdfBox::Request& req, GetEsdfBox::Response& res);
  /// Samples `points` under the map lock; false with `why` when there is no planning layer or
  /// the map stayed busy.
  bool sample(const std::vector<Eigen::Vector3d>& points, std::vector<EsdfSample>* samples,
              double* cell_m, std::string* why);
  template <typename Response>
  bool refuse(const char* service, const std::string& why, Response* res);

  const NodeConfig& node_;
  MappingSession* session_;
  std::atomic<uint64_t> requests_{0}, refused_{0};
  std::vector<ros::ServiceServer> servers_;
};

}  // namespace stereo_fusion
