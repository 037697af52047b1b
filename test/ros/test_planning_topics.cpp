// The planning topics of the real nodelet under a real master (rostest, planning_topics.test):
// ~occupancy_grid with ~occupancy_grid_updates, ~esdf_slice and ~occupied_voxels against an
// analytic scene, and clears and resets reaching the grid within one planning update.
#include <map_msgs/OccupancyGridUpdate.h>
#include <nav_msgs/OccupancyGrid.h>
#include <sensor_msgs/PointCloud2.h>
#include <sensor_msgs/point_cloud2_iterator.h>
#include <std_srvs/Empty.h>
#include <stereo_fusion/ClearBox.h>
#include <tf2_ros/transform_broadcaster.h>

#include <cmath>
#include <mutex>
#include <optional>
#include <vector>

#include "../unit/TestSupport.h"
#include "RosTestSupport.h"

using namespace stereo_fusion;

namespace {

StereoCamera qvga() { return *StereoCamera::create(320, 240, 262.5, 262.5, 159.5, 119.5, 0.1); }

// World z up: a floor, a wall 3 m ahead and a ball in between, at the camera's height.
const Eigen::Vector3d kBall(1.8, 0.0, 0.6);
constexpr double kBallRadius = 0.35;
constexpr double kCell = 0.08;        // planning cell at voxel_size_m 0.02 (auto: nearest to 8 cm)
constexpr double kSliceHeight = 0.6;  // planning_topics.test's esdf_slice_height_m

sim::AnalyticScene scene() {
  sim::AnalyticScene s;
  s.add(sim::makePlane({0, 0, 0}, {0, 0, 1}), {150, 150, 150});
  s.add(sim::makePlane({3.0, 0, 0}, {-1, 0, 0}), {180, 160, 120});
  s.add(sim::makeSphere(kBall, kBallRadius), {200, 60, 60});
  return s;
}

std::vector<Eigen::Isometry3d> poses() {
  std::vector<Eigen::Isometry3d> out;
  const Eigen::Vector3d eye(0.0, 0.0, 0.6);
  for (double yaw : {-0.3, -0.15, 0.0, 0.15, 0.3})
    out.push_back(sim::lookAt(eye, eye + Eigen::Vector3d(std::cos(yaw), std::sin(yaw), -0.15)));
  return out;
}

/// The grid a subscriber holds: the last full grid patched with every update after it, and
/// what it was after each message (stamp → cells).
struct HeldGrid {
  nav_msgs::OccupancyGrid grid;
  bool have = false;
  int fulls = 0, updates_since_full = 0, updates_before_grid = 0, bad_updates = 0;
  std::vector<nav_msgs::OccupancyGrid> history;  // the grid after each message, stamped by it

  void onFull(const nav_msgs::OccupancyGrid& g) {
    grid = g;
    have = true;
    ++fulls;
    updates_since_full = 0;
    history.push_back(g);
  }
  void onUpdate(const map_msgs::OccupancyGridUpdate& u) {
    if (!have) {
      ++updates_before_grid;
      return;
    }
    if (u.x < 0 || u.y < 0 || u.x + u.width > grid.info.width ||
        u.y + u.height > grid.info.height ||
        u.data.size() != static_cast<size_t>(u.width) * u.height) {
      ++bad_updates;
      return;
    }
    for (uint32_t y = 0; y < u.height; ++y)
      std::copy_n(u.data.begin() + static_cast<size_t>(y) * u.width, u.width,
                  grid.data.begin() + static_cast<size_t>(u.y + y) * grid.info.width + u.x);
    ++updates_since_full;
    history.push_back(grid);
    history.back().header.stamp = u.header.stamp;
  }
};

/// Value of the column holding world (x, y) in `data` laid out as `grid`; -2 outside it.
int cellAt(const nav_msgs::OccupancyGrid& grid, const std::vector<int8_t>& data, double x,
           double y) {
  const int i =
      static_cast<int>(std::floor((x - grid.info.origin.position.x) / grid.info.resolution));
  const int j =
      static_cast<int>(std::floor((y - grid.info.origin.position.y) / grid.info.resolution));
  if (i < 0 || j < 0 || i >= static_cast<int>(grid.info.width) ||
      j >= static_cast<int>(grid.info.height))
    return -2;
  return data[static_cast<size_t>(j) * grid.info.width + i];
}

struct CloudPoint {
  Eigen::Vector3d p;
  double value = 0.0;
};
std::vector<CloudPoint> readCloud(const sensor_msgs::PointCloud2& cloud, bool with_intensity) {
  std::vector<CloudPoint> out;
  sensor_msgs::PointCloud2ConstIterator<float> x(cloud, "x"), y(cloud, "y"), z(cloud, "z");
  std::optional<sensor_msgs::PointCloud2ConstIterator<float>> v;
  if (with_intensity) v.emplace(cloud, "intensity");
  for (; x != x.end(); ++x, ++y, ++z) {
    out.push_back({Eigen::Vector3d(*x, *y, *z), v ? double(**v) : 0.0});
    if (v) ++*v;
  }
  return out;
}

class PlanningTopics : public testing::Test {
 protected:
  void SetUp() override {
    ros::NodeHandle nh;
    disparity_pub_ = nh.advertise<stereo_msgs::DisparityImage>("/stereo/disparity", 10);
    image_pub_ = nh.advertise<sensor_msgs::Image>("/stereo/left/image_rect_color", 10);
    info_pub_ = nh.advertise<sensor_msgs::CameraInfo>("/stereo/left/camera_info", 10);
    grid_sub_ = nh.subscribe<nav_msgs::OccupancyGrid>(
        "/stereo_fusion/occupancy_grid", 10, [this](const nav_msgs::OccupancyGrid::ConstPtr& g) {
          std::lock_guard<std::mutex> lock(mutex_);
          held_.onFull(*g);
        });
    updates_sub_ = nh.subscribe<map_msgs::OccupancyGridUpdate>(
        "/stereo_fusion/occupancy_grid_updates", 100,
        [this](const map_msgs::OccupancyGridUpdate::ConstPtr& u) {
          std::lock_guard<std::mutex> lock(mutex_);
          held_.onUpdate(*u);
        });
    slice_sub_ = nh.subscribe<sensor_msgs::PointCloud2>(
        "/stereo_fusion/esdf_slice", 10, [this](const sensor_msgs::PointCloud2::ConstPtr& c) {
          std::lock_guard<std::mutex> lock(mutex_);
          slice_ = *c;
          tick_stamps_.push_back(c->header.stamp);
        });
    occupied_sub_ = nh.subscribe<sensor_msgs::PointCloud2>(
        "/stereo_fusion/occupied_voxels", 10, [this](const sensor_msgs::PointCloud2::ConstPtr& c) {
          std::lock_guard<std::mutex> lock(mutex_);
          occupied_ = *c;
        });
    ASSERT_TRUE(test::waitFor(
        [&] {
          return disparity_pub_.getNumSubscribers() > 0 && image_pub_.getNumSubscribers() > 0 &&
                 info_pub_.getNumSubscribers() > 0 && grid_sub_.getNumPublishers() > 0 &&
                 updates_sub_.getNumPublishers() > 0 && slice_sub_.getNumPublishers() > 0 &&
                 occupied_sub_.getNumPublishers() > 0;
        },
        30.0))
        << "the nodelet did not connect";
    ASSERT_TRUE(test::waitForTfSubscriber(30.0)) << "the nodelet's tf listener did not connect";
    ASSERT_TRUE(diagnostics_.waitForNextReport(30.0)) << "no diagnostics from the nodelet";
    // Each test starts from an empty map: the grid is sent whole (0 × 0) within one update.
    const ros::Time before_reset = ros::Time::now();
    std_srvs::Empty reset;
    ASSERT_TRUE(ros::service::call("/stereo_fusion/reset", reset));
    ASSERT_TRUE(test::waitFor(
        [&] {
          std::lock_guard<std::mutex> lock(mutex_);
          return held_.have && held_.grid.header.stamp >= before_reset &&
                 held_.grid.info.width == 0;
        },
        10.0))
        << "no empty full grid after ~reset";
  }

  void TearDown() override {
    grid_sub_.shutdown();
    updates_sub_.shutdown();
    slice_sub_.shutdown();
    occupied_sub_.shutdown();
  }

  void publish(const StereoFrame& frame) {
    test::FrameMessages m = test::frameMessages(frame, &tf_, "left_optical");
    ros::WallDuration(0.05).sleep();  // tf first, as a SLAM stack running ahead would
    disparity_pub_.publish(m.disparity);
    image_pub_.publish(m.image);
    info_pub_.publish(m.info);
  }

  /// Publishes a frame at every pose, waits until all are fused and a planning update ran
  /// after that (an ~esdf_slice stamped later: the slice goes out after the grid of its tick).
  void fuseAll(const sim::AnalyticScene& s) {
    const long fused_before = std::max(0L, diagnostics_.value("frames fused"));
    const std::vector<Eigen::Isometry3d> all = poses();
    for (const Eigen::Isometry3d& pose : all) publish(test::renderFrame(s, qvga(), pose));
    ASSERT_TRUE(test::waitFor(
        [&] { return diagnostics_.value("frames fused") >= fused_before + long(all.size()); },
        60.0))
        << "fused " << diagnostics_.value("frames fused") << " of " << fused_before + all.size();
    // Two ticks: the grid messages of the first may arrive after its slice (another topic).
    const ros::Time first = waitForTickAfter(ros::Time::now());
    waitForTickAfter(first + ros::Duration(1e-6));
  }

  /// The stamp of the first planning update (tick) that took the map after `t`.
  ros::Time waitForTickAfter(const ros::Time& t) {
    ros::Time tick;
    EXPECT_TRUE(test::waitFor(
        [&] {
          std::lock_guard<std::mutex> lock(mutex_);
          for (const ros::Time& s : tick_stamps_)
            if (s >= t) {
              tick = s;
              return true;
            }
          return false;
        },
        10.0))
        << "no planning update after " << t;
    return tick;
  }

  ros::Publisher disparity_pub_, image_pub_, info_pub_;
  ros::Subscriber grid_sub_, updates_sub_, slice_sub_, occupied_sub_;
  test::DiagnosticsWatcher diagnostics_;
  tf2_ros::TransformBroadcaster tf_;
  std::mutex mutex_;
  HeldGrid held_;
  sensor_msgs::PointCloud2 slice_, occupied_;
  std::vector<ros::Time> tick_stamps_;
};

}  // namespace

// The grid shows the scene; a clear reaches it within one planning update; the first grid
// patched with every update equals the grid a new subscriber gets.
TEST_F(PlanningTopics, GridPatchedWithItsUpdatesIsTheCurrentGridAndAClearReachesItWithinOneUpdate) {
  const sim::AnalyticScene s = scene();
  fuseAll(s);
  nav_msgs::OccupancyGrid grid;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    grid = held_.grid;
  }
  ASSERT_GT(grid.info.width, 10u);
  ASSERT_GT(grid.info.height, 10u);
  EXPECT_EQ(grid.header.frame_id, "map");
  EXPECT_FLOAT_EQ(grid.info.resolution, kCell);
  // The wall and the ball's front are occupied, the space before the ball free, the space beside
  // the camera (outside every view) unknown. Cells are probed a quarter cell inside the solids.
  EXPECT_EQ(cellAt(grid, grid.data, 3.02, 0.0), 100) << "wall";
  EXPECT_EQ(cellAt(grid, grid.data, kBall.x() - kBallRadius + 0.03, 0.0), 100) << "ball";
  EXPECT_EQ(cellAt(grid, grid.data, 1.0, 0.0), 0) << "before the ball";
  EXPECT_EQ(cellAt(grid, grid.data, 0.5, 0.05), 0) << "before the camera";
  EXPECT_EQ(cellAt(grid, grid.data, 0.3, 1.2), -1) << "beside the camera";
  size_t occupied = 0, free = 0, unknown = 0;
  for (int8_t v : grid.data) {
    occupied += v == 100, free += v == 0, unknown += v == -1;
    ASSERT_TRUE(v == 100 || v == 0 || v == -1) << int(v);
  }
  EXPECT_GT(occupied, 20u);
  EXPECT_GT(free, 100u);
  EXPECT_GT(unknown, 100u);

  // Clear a box of free space before the ball, through the whole height band.
  stereo_fusion::ClearBox box;
  box.request.min.x = 0.64, box.request.min.y = -0.32, box.request.min.z = -1.0;
  box.request.max.x = 1.28, box.request.max.y = 0.32, box.request.max.z = 3.0;
  ASSERT_TRUE(ros::service::call("/stereo_fusion/clear_box", box));
  ASSERT_TRUE(box.response.success) << box.response.message;
  const ros::Time cleared = ros::Time::now();
  const ros::Time tick = waitForTickAfter(cleared);
  // The grid of that very update (an update message carries its tick's stamp) reads unknown in
  // the box: the columns whose cells lie inside it with a cell to spare.
  nav_msgs::OccupancyGrid after_clear;
  ASSERT_TRUE(test::waitFor(
      [&] {
        std::lock_guard<std::mutex> lock(mutex_);
        for (const nav_msgs::OccupancyGrid& g : held_.history)
          if (g.header.stamp == tick) {
            after_clear = g;
            return true;
          }
        return false;
      },
      5.0))
      << "the planning update after the clear sent no grid change";
  int inside = 0;
  for (double x = 0.64 + 1.5 * kCell; x < 1.28 - kCell; x += kCell)
    for (double y = -0.32 + 1.5 * kCell; y < 0.32 - kCell; y += kCell) {
      EXPECT_EQ(cellAt(after_clear, after_clear.data, x, y), -1) << x << " " << y;
      ++inside;
    }
  EXPECT_GE(inside, 9);
  EXPECT_EQ(cellAt(after_clear, after_clear.data, 3.02, 0.0), 100) << "the wall is outside the box";

  // The same frames again fill the box; then a new subscriber's first grid is what ours holds.
  // Subscribers of one topic in one process share its connection: ours goes first (the updates
  // keep coming to held_), so the new one connects anew and gets the grid as it is now.
  fuseAll(s);
  grid_sub_.shutdown();
  ros::NodeHandle nh;
  std::mutex late_mutex;
  std::optional<nav_msgs::OccupancyGrid> late;
  ros::Subscriber late_sub = nh.subscribe<nav_msgs::OccupancyGrid>(
      "/stereo_fusion/occupancy_grid", 1, [&](const nav_msgs::OccupancyGrid::ConstPtr& g) {
        std::lock_guard<std::mutex> lock(late_mutex);
        if (!late) late = *g;
      });
  ASSERT_TRUE(test::waitFor(
      [&] {
        std::lock_guard<std::mutex> lock(late_mutex);
        return late.has_value();
      },
      10.0))
      << "a new subscriber got no grid";
  late_sub.shutdown();
  // An update sent just before the new subscriber's grid may still be on its way to ours.
  EXPECT_TRUE(test::waitFor(
      [&] {
        std::lock_guard<std::mutex> lock(mutex_);
        return held_.grid.info.width == late->info.width &&
               held_.grid.info.height == late->info.height &&
               held_.grid.info.origin.position.x == late->info.origin.position.x &&
               held_.grid.info.origin.position.y == late->info.origin.position.y &&
               held_.grid.data == late->data;
      },
      5.0))
      << "the grid patched with its updates differs from the current grid";
  std::lock_guard<std::mutex> lock(mutex_);
  EXPECT_EQ(held_.bad_updates, 0);
  EXPECT_EQ(held_.updates_before_grid, 0);
  EXPECT_GE(held_.updates_since_full, 2)
      << "the clear and the refill came as updates, not as full grids";
  EXPECT_EQ(cellAt(held_.grid, held_.grid.data, 1.0, 0.0), 0) << "the box is seen free again";
  EXPECT_GT(diagnostics_.value("planning updates"), 0);
  EXPECT_GT(diagnostics_.value("occupancy grid width (cells)"), 0);
}

// ~esdf_slice: cell centres at the slice's height with the distance to the scene; ~occupied_voxels:
// cells at or inside the scene's solids.
TEST_F(PlanningTopics, EsdfSliceMatchesTheSceneAndOccupiedVoxelsLieOnItsSurfaces) {
  const sim::AnalyticScene s = scene();
  fuseAll(s);
  std::vector<CloudPoint> slice, occupied;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    EXPECT_EQ(slice_.header.frame_id, "map");
    slice = readCloud(slice_, true);
    occupied = readCloud(occupied_, false);
  }
  ASSERT_GT(slice.size(), 100u);
  const double tolerance = 2.0 * kCell;
  int near_ball = 0;
  for (const CloudPoint& c : slice) {
    // The cells of the layer holding the height: their centres are 0.60 here.
    ASSERT_NEAR(c.p.z(), kSliceHeight, 1e-4) << c.p.transpose();
    const double clearance = s.clearance(c.p);
    // Never nearer an obstacle than the scene puts it (unseen surfaces can only make it farther).
    EXPECT_GE(c.value, std::min(clearance, 2.0) - tolerance) << c.p.transpose();
    if (c.value < 0)
      EXPECT_LE(clearance, tolerance) << "a cell inside an obstacle lies at a surface";
    // Before the ball, on its axis, the nearest surface is the ball's seen front.
    // (The floor is 0.6 m below, the wall farther than 1 m.)
    const double to_ball = (c.p - kBall).norm() - kBallRadius;
    if (c.p.x() < kBall.x() - kBallRadius - 2 * kCell && std::abs(c.p.y()) < 0.15 &&
        to_ball < 0.3) {
      EXPECT_NEAR(c.value, to_ball, tolerance) << c.p.transpose();
      ++near_ball;
    }
  }
  EXPECT_GE(near_ball, 3);
  ASSERT_GT(occupied.size(), 50u);
  int on_ball = 0;
  for (const CloudPoint& c : occupied) {
    EXPECT_LE(s.clearance(c.p), 1.5 * kCell)
        << "an occupied cell in free space at " << c.p.transpose();
    on_ball += std::abs((c.p - kBall).norm() - kBallRadius) < 1.5 * kCell;
  }
  EXPECT_GT(on_ball, 10);
}

int main(int argc, char** argv) {
  return test::runRosTests(argc, argv, "stereo_fusion_planning_test");
}
