#pragma once
#include <limits>
// What the node measured about its own work, for /diagnostics: stage timings, latencies and
// per-frame pixel counts, the last 1000 of each.
#include <array>
#include <atomic>
#include <cstdint>
#include <deque>
#include <mutex>
#include <vector>

namespace stereo_fusion {

class NodeStats {
 public:
  static constexpr size_t kWindow = 1000;

  /// One fused frame: lookup, fusion (with carving), total (with a meshing pass after it).
  void recordFrame(double lookup_ms, double fusion_ms, double total_ms) {
    std::lock_guard<std::mutex> lock(mutex_);
    push(&frame_ms_, {lookup_ms, fusion_ms, total_ms});
  }
  void recordMeshPass(double meshing_ms, double texture_ms) {
    std::lock_guard<std::mutex> lock(mutex_);
    push(&mesh_pass_ms_, {meshing_ms, texture_ms, 0.0});
    ++mesh_passes_;
  }
  /// One planning update that had work (Mapper::updatePlanning(): changed TSDF blocks re-read,
  /// ESDF).
  void recordPlanningUpdate(double ms) {
    std::lock_guard<std::mutex> lock(mutex_);
    planning_ms_.push_back(ms);
    if (planning_ms_.size() > kWindow) planning_ms_.pop_front();
    ++planning_updates_;
  }
  /// One frame on the worker, from the queue to after its publishing: what must stay under the
  /// frame period for no frame to wait (pose wait, conversion, fusion, meshing and publishing
  /// when due); `publish_ms` the publishing part (deferred meshing, messages, planning).
  void recordWorkerFrame(double worker_ms, double publish_ms) {
    std::lock_guard<std::mutex> lock(mutex_);
    push(&worker_ms_, {worker_ms, publish_ms, 0.0});
  }
  /// Frame stamp → publish of its mesh.
  void recordLatency(double seconds) {
    std::lock_guard<std::mutex> lock(mutex_);
    latencies_s_.push_back(seconds);
    if (latencies_s_.size() > kWindow) latencies_s_.pop_front();
  }
  /// Forgets the timings (reset, load_map: a new map).
  void clearTimings() {
    std::lock_guard<std::mutex> lock(mutex_);
    frame_ms_.clear();
    mesh_pass_ms_.clear();
    worker_ms_.clear();
    planning_ms_.clear();
  }

  struct View {
    std::vector<double> latency_s;
    std::vector<double> stage_ms[5];  // lookup, fusion, meshing, texture, total
    uint64_t mesh_passes = 0;
    std::vector<double> planning_ms;
    uint64_t planning_updates = 0;
    std::vector<double> worker_ms, publish_ms;
  };
  View view() const {
    std::lock_guard<std::mutex> lock(mutex_);
    View v;
    v.latency_s.assign(latencies_s_.begin(), latencies_s_.end());
    for (const auto& s : frame_ms_) {
      v.stage_ms[0].push_back(s[0]);
      v.stage_ms[1].push_back(s[1]);
      v.stage_ms[4].push_back(s[2]);
    }
    for (const auto& s : mesh_pass_ms_) {
      v.stage_ms[2].push_back(s[0]);
      v.stage_ms[3].push_back(s[1]);
    }
    for (const auto& s : worker_ms_) {
      v.worker_ms.push_back(s[0]);
      v.publish_ms.push_back(s[1]);
    }
    v.mesh_passes = mesh_passes_;
    v.planning_ms.assign(planning_ms_.begin(), planning_ms_.end());
    v.planning_updates = planning_updates_;
    return v;
  }

  // Mapper::measuredDisparityNoisePx() after the last fused frame (NaN before any).
  std::atomic<double> disparity_noise_measured_px{std::numeric_limits<double>::quiet_NaN()};
  std::atomic<bool> disparity_noise_warned{false};
  // The occupancy grid last built (PlanningPublisher; 0 × 0 until someone subscribed).
  std::atomic<uint32_t> grid_width{0}, grid_height{0};
  std::atomic<bool> grid_windowed{false};  ///< the last grid was a window (grid_max_cells)

 private:
  using Row = std::array<double, 3>;
  static void push(std::deque<Row>* rows, const Row& row) {
    rows->push_back(row);
    if (rows->size() > kWindow) rows->pop_front();
  }
  mutable std::mutex mutex_;
  std::deque<Row> frame_ms_, mesh_pass_ms_, worker_ms_;
  std::deque<double> latencies_s_, planning_ms_;
  uint64_t mesh_passes_ = 0, planning_updates_ = 0;
};

}  // namespace stereo_fusion
