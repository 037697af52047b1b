// stereo_fusion_planning_probe: what a planner sees of a running stereo_fusion node. Calls
// ~get_distance with batches of 1, 1 000 and 100 000 points (round robin, back to back) and
// records each call's round trip; counts the serialized bytes of ~occupancy_grid and
// ~occupancy_grid_updates, and what the same updates would have cost as full grids (the grid a
// subscriber holds, patched, serialized once per update). Used by scripts/bench_planning_live.sh.
//   stereo_fusion_planning_probe --duration-s S [--sizes "1 1000 100000"] [--node /stereo_fusion]
//                                [--box "xmin ymin zmin xmax ymax zmax"] [--calls-hz 10]
//                                [--unpause /player/pause_playback] [--json FILE]
// Calls are paced at --calls-hz (a planner's replanning rate), never overlapping. With --unpause
// the probe starts a paused rosbag player (std_srvs/SetBool) when it is ready, so the window it
// measures is the replay. It also reports the node's frames fused and dropped (/diagnostics).
#include <diagnostic_msgs/DiagnosticArray.h>
#include <map_msgs/OccupancyGridUpdate.h>
#include <nav_msgs/OccupancyGrid.h>
#include <ros/ros.h>
#include <std_srvs/SetBool.h>
#include <stereo_fusion/GetDistance.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <cstdio>
#include <fstream>
#include <mutex>
#include <random>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "cli/CommandLine.h"
#include "cli/NumberChecks.h"

namespace {

struct Options {
  double duration_s = 10.0;
  std::vector<size_t> sizes{1, 1000, 100000};
  std::string node = "/stereo_fusion";
  std::vector<double> box{-3.0, -3.0, 0.0, 3.0, 3.0, 2.5};  ///< x0 y0 z0 x1 y1 z1
  double calls_hz = 10.0;
  std::string unpause;
  std::string json;
};

void addProbeArguments(CLI::App* app, Options* o) {
  app->description(
      "What a planner sees of a running stereo_fusion node: calls ~get_distance with batches\n"
      "of points (round robin, back to back, paced at --calls-hz) and records each call's round\n"
      "trip; counts the serialized bytes of ~occupancy_grid and ~occupancy_grid_updates, and the\n"
      "node's frames fused and dropped (/diagnostics).");
  app->footer("Exit codes: 0 done, 1 the node or the player did not answer, 2 bad arguments.");
  app->add_option("--duration-s", o->duration_s, "how long to call, in seconds (default 10)")
      ->check(stereo_fusion::cli::positiveNumber());
  app->add_option(
         "--sizes", o->sizes,
         "points per request, one request of each size in turn (default \"1 1000 100000\")")
      ->delimiter(' ')
      ->check(stereo_fusion::cli::positiveNumber());
  app->add_option("--node", o->node, "the node's name (default /stereo_fusion)");
  app->add_option("--box", o->box,
                  "the points are drawn uniformly in this box, metres in the world frame\n"
                  "(default \"-3 -3 0 3 3 2.5\")")
      ->delimiter(' ')
      ->expected(6)
      ->check(stereo_fusion::cli::finiteNumber());
  app->add_option("--calls-hz", o->calls_hz,
                  "calls per second, never overlapping (a planner's replanning rate; default 10)")
      ->check(stereo_fusion::cli::positiveNumber());
  app->add_option("--unpause", o->unpause,
                  "start a paused rosbag player through this std_srvs/SetBool service when ready,\n"
                  "so the window measured is the replay (e.g. /player/pause_playback)")
      ->type_name("SERVICE");
  app->add_option("--json", o->json, "also write the results as JSON")->type_name("FILE");
}

/// The grid a costmap's static layer holds, and the bytes that reached it.
class GridCounter {
 public:
  void onFull(const nav_msgs::OccupancyGrid& g) {
    std::lock_guard<std::mutex> lock(mutex_);
    grid_ = g;
    have_ = true;
    ++fulls_;
    full_bytes_ += ros::serialization::serializationLength(g);
  }
  void onUpdate(const map_msgs::OccupancyGridUpdate& u) {
    std::lock_guard<std::mutex> lock(mutex_);
    ++updates_;
    update_bytes_ += ros::serialization::serializationLength(u);
    if (!have_ || u.x < 0 || u.y < 0 || u.x + u.width > grid_.info.width ||
        u.y + u.height > grid_.info.height || u.data.size() != size_t(u.width) * u.height) {
      ++unusable_updates_;
      return;
    }
    for (uint32_t y = 0; y < u.height; ++y)
      std::copy_n(u.data.begin() + size_t(y) * u.width, u.width,
                  grid_.data.begin() + size_t(u.y + y) * grid_.info.width + u.x);
    // Without updates the node would have sent this whole grid instead.
    as_full_grids_bytes_ += ros::serialization::serializationLength(grid_);
  }
  std::string json(double seconds) const {
    std::lock_guard<std::mutex> lock(mutex_);
    const double with = double(full_bytes_ + update_bytes_);
    const double without = double(full_bytes_ + as_full_grids_bytes_);
    std::ostringstream s;
    s << "{\"full_grids\": " << fulls_ << ", \"updates\": " << updates_
      << ", \"unusable_updates\": " << unusable_updates_ << ", \"full_grid_bytes\": " << full_bytes_
      << ", \"update_bytes\": " << update_bytes_
      << ", \"bytes_per_s_with_updates\": " << with / seconds
      << ", \"bytes_per_s_full_grids_only\": " << without / seconds
      << ", \"grid_cells\": " << grid_.data.size() << "}";
    return s.str();
  }

 private:
  mutable std::mutex mutex_;
  nav_msgs::OccupancyGrid grid_;
  bool have_ = false;
  int fulls_ = 0, updates_ = 0, unusable_updates_ = 0;
  uint64_t full_bytes_ = 0, update_bytes_ = 0, as_full_grids_bytes_ = 0;
};

/// The node's frame counters from /diagnostics: frames fused and every "dropped: …" reason.
class FrameCounter {
 public:
  void onDiagnostics(const diagnostic_msgs::DiagnosticArray& msg) {
    std::lock_guard<std::mutex> lock(mutex_);
    for (const diagnostic_msgs::DiagnosticStatus& status : msg.status) {
      if (status.name.find("fusion") == std::string::npos) continue;
      double dropped = 0.0;
      for (const diagnostic_msgs::KeyValue& kv : status.values) {
        if (kv.key == "frames fused") fused_ = std::atof(kv.value.c_str());
        if (kv.key.rfind("dropped: ", 0) == 0) dropped += std::atof(kv.value.c_str());
      }
      dropped_ = dropped;
    }
  }
  std::string json() const {
    std::lock_guard<std::mutex> lock(mutex_);
    std::ostringstream s;
    s << "{\"frames_fused\": " << fused_ << ", \"frames_dropped\": " << dropped_ << "}";
    return s.str();
  }

 private:
  mutable std::mutex mutex_;
  double fused_ = 0.0, dropped_ = 0.0;
};

double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, size_t(q * double(v.size() - 1) + 0.5))];
}

}  // namespace

int main(int argc, char** argv) {
  ros::init(argc, argv, "stereo_fusion_planning_probe", ros::init_options::AnonymousName);
  // ros::init() has taken the ROS arguments (name:=value remappings) out of argv.
  Options opt;
  CLI::App app("", "stereo_fusion_planning_probe");
  addProbeArguments(&app, &opt);
  if (const auto exit_code = stereo_fusion::cli::parseOrExitCode(app, argc, argv))
    return *exit_code;
  ros::NodeHandle nh;
  GridCounter grid;
  ros::Subscriber full =
      nh.subscribe(opt.node + "/occupancy_grid", 10, &GridCounter::onFull, &grid);
  ros::Subscriber upd =
      nh.subscribe(opt.node + "/occupancy_grid_updates", 1000, &GridCounter::onUpdate, &grid);
  FrameCounter frames;
  ros::Subscriber diag = nh.subscribe("/diagnostics", 10, &FrameCounter::onDiagnostics, &frames);
  ros::AsyncSpinner spinner(1);
  spinner.start();

  const std::string service = opt.node + "/get_distance";
  if (!ros::service::waitForService(service, ros::Duration(60.0))) {
    std::fprintf(stderr, "[probe] %s did not come up within 60 s\n", service.c_str());
    return 1;
  }
  ros::ServiceClient client = nh.serviceClient<stereo_fusion::GetDistance>(service, true);

  // One request per size, prepared once: random points in the box.
  std::mt19937 rng(7);
  std::vector<stereo_fusion::GetDistance> requests(opt.sizes.size());
  for (size_t s = 0; s < opt.sizes.size(); ++s) {
    std::uniform_real_distribution<double> u(0.0, 1.0);
    requests[s].request.points.resize(opt.sizes[s]);
    for (geometry_msgs::Point& p : requests[s].request.points) {
      p.x = opt.box[0] + u(rng) * (opt.box[3] - opt.box[0]);
      p.y = opt.box[1] + u(rng) * (opt.box[4] - opt.box[1]);
      p.z = opt.box[2] + u(rng) * (opt.box[5] - opt.box[2]);
    }
  }
  std::vector<std::vector<double>> latency_ms(opt.sizes.size());
  std::vector<int> refused(opt.sizes.size(), 0), failed(opt.sizes.size(), 0);
  std::vector<size_t> known(opt.sizes.size(), 0);

  if (!opt.unpause.empty()) {
    std_srvs::SetBool play;
    play.request.data = false;
    if (!ros::service::waitForService(opt.unpause, ros::Duration(30.0)) ||
        !ros::service::call(opt.unpause, play)) {
      std::fprintf(stderr, "[probe] could not start the player through %s\n", opt.unpause.c_str());
      return 1;
    }
  }
  using Clock = std::chrono::steady_clock;
  const Clock::time_point start = Clock::now();
  const auto elapsed_s = [&] {
    return std::chrono::duration<double>(Clock::now() - start).count();
  };
  const auto period = std::chrono::duration<double>(1.0 / opt.calls_hz);
  Clock::time_point next = start;
  for (size_t round = 0; ros::ok() && elapsed_s() < opt.duration_s; ++round) {
    std::this_thread::sleep_until(next);
    next += std::chrono::duration_cast<Clock::duration>(period);
    const size_t s = round % opt.sizes.size();
    stereo_fusion::GetDistance call = requests[s];
    const Clock::time_point t0 = Clock::now();
    const bool ok = client.call(call);
    const double ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
    next = std::max(next, Clock::now());  // a slow call delays the next, it does not burst
    if (!ok) {
      ++failed[s];
      if (!client.isValid()) client = nh.serviceClient<stereo_fusion::GetDistance>(service, true);
      continue;
    }
    if (!call.response.success) {
      ++refused[s];
      continue;
    }
    latency_ms[s].push_back(ms);
    known[s] = size_t(std::count_if(call.response.states.begin(), call.response.states.end(),
                                    [](uint8_t st) { return st != 0; }));
  }
  const double seconds = elapsed_s();
  ros::WallDuration(2.0).sleep();  // the node's next /diagnostics (1 Hz) after the last frame

  std::ostringstream out;
  out << "{\"duration_s\": " << seconds << ", \"get_distance\": [";
  for (size_t s = 0; s < opt.sizes.size(); ++s) {
    const std::vector<double>& v = latency_ms[s];
    out << (s ? ", " : "") << "{\"points\": " << opt.sizes[s] << ", \"calls\": " << v.size()
        << ", \"refused\": " << refused[s] << ", \"failed\": " << failed[s]
        << ", \"p50_ms\": " << percentile(v, 0.5) << ", \"p99_ms\": " << percentile(v, 0.99)
        << ", \"max_ms\": " << percentile(v, 1.0) << ", \"known_in_last_answer\": " << known[s]
        << "}";
    std::printf(
        "[probe] get_distance %7zu points: %5zu calls, p50 %8.2f ms, p99 %8.2f ms, "
        "max %8.2f ms, %d refused, %d failed\n",
        opt.sizes[s], v.size(), percentile(v, 0.5), percentile(v, 0.99), percentile(v, 1.0),
        refused[s], failed[s]);
  }
  out << "], \"occupancy_grid\": " << grid.json(seconds) << ", \"node\": " << frames.json() << "}";
  std::printf("[probe] occupancy grid: %s\n", grid.json(seconds).c_str());
  std::printf("[probe] node: %s\n", frames.json().c_str());
  if (!opt.json.empty()) std::ofstream(opt.json) << out.str() << "\n";
  spinner.stop();
  return 0;
}
