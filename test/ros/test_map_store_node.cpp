// The map store through the real nodelet (checkpoint_period_s, resume): a nodelet fuses a
// corridor and checkpoints it with ~save_map and an empty path; it is unloaded, and a second
// one started with resume: true comes up with the same mesh (~mesh_update, ~get_full_mesh) and
// the same occupancy grid, and goes on fusing. A store that cannot be read leaves the node
// mapping without it, with an ERROR on /diagnostics.
#include <diagnostic_msgs/DiagnosticArray.h>
#include <nav_msgs/OccupancyGrid.h>
#include <nodelet/loader.h>
#include <stereo_fusion/GetFullMesh.h>
#include <stereo_fusion/MeshUpdate.h>
#include <stereo_fusion/SaveMap.h>
#include <tf2_ros/transform_broadcaster.h>

#include <boost/make_shared.hpp>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <optional>

#include "../unit/TestSupport.h"
#include "RosTestSupport.h"
#include "stereo_fusion/ros/FusionNodelet.h"
#include "stereo_fusion/ros/MeshMessages.h"
#include "stereo_fusion/ros/MessageConversions.h"

using namespace stereo_fusion;
namespace fs = std::filesystem;

namespace {

/// One FusionNodelet loaded into this process as /stereo_fusion, unloaded on destruction.
class LoadedNodelet {
 public:
  LoadedNodelet()
      : loader_(boost::function<boost::shared_ptr<nodelet::Nodelet>(const std::string&)>(
            [](const std::string&) { return boost::make_shared<FusionNodelet>(); })) {
    ok_ = loader_.load("/stereo_fusion", "stereo_fusion/FusionNodelet", {}, {});
  }
  ~LoadedNodelet() { loader_.unload("/stereo_fusion"); }
  bool ok() const { return ok_; }

 private:
  nodelet::Loader loader_;
  bool ok_ = false;
};

/// The corridor of the paging test, and frames along it.
struct Corridor {
  sim::AnalyticScene scene;
  StereoCamera camera = *StereoCamera::create(320, 240, 262.5, 262.5, 159.5, 119.5, 0.1);
  Corridor() {
    scene.add(sim::makePlane({0, 0.5, 0}, {0, -1, 0}), {180, 160, 120});
    scene.add(sim::makePlane({0, 0, 2.0}, {0, 0, -1}), {90, 120, 200});
    scene.add(sim::makeSphere({1.5, 0.2, 1.6}, 0.25), {200, 60, 60});
  }
  StereoFrame frame(int k) const {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.translation().x() = 0.2 * k;
    return test::renderFrame(scene, camera, T);
  }
};

struct FrameTopics {
  ros::NodeHandle nh;
  ros::Publisher disparity = nh.advertise<stereo_msgs::DisparityImage>("/disparity", 10);
  ros::Publisher image = nh.advertise<sensor_msgs::Image>("/image", 10);
  ros::Publisher info = nh.advertise<sensor_msgs::CameraInfo>("/camera_info", 10);
  tf2_ros::TransformBroadcaster tf;

  bool connected() const {
    return disparity.getNumSubscribers() > 0 && image.getNumSubscribers() > 0 &&
           info.getNumSubscribers() > 0;
  }
  void send(const StereoFrame& frame) {
    const test::FrameMessages m = test::frameMessages(frame, &tf);
    ros::WallDuration(0.05).sleep();
    disparity.publish(m.disparity);
    image.publish(m.image);
    info.publish(m.info);
  }
};

/// What the mesh and grid topics last said.
struct Outputs {
  std::mutex mutex;
  std::unordered_map<BlockKey, SubMesh, BlockKeyHash> streamed;
  bool applied_ok = true;
  size_t updates = 0;
  ros::Subscriber mesh_sub;

  Outputs() {
    ros::NodeHandle nh;
    mesh_sub = nh.subscribe<MeshUpdate>("/stereo_fusion/mesh_update", 100,
                                        [this](const MeshUpdate::ConstPtr& u) {
                                          std::lock_guard<std::mutex> lock(mutex);
                                          applied_ok &= applyMeshUpdate(*u, &streamed);
                                          ++updates;
                                        });
  }
  ~Outputs() { mesh_sub.shutdown(); }
};

/// The occupancy grid as a new subscriber gets it (the whole grid, as the planning timer last
/// built it).
nav_msgs::OccupancyGrid gridNow() {
  std::mutex mutex;
  std::optional<nav_msgs::OccupancyGrid> grid;
  ros::Subscriber sub = ros::NodeHandle().subscribe<nav_msgs::OccupancyGrid>(
      "/stereo_fusion/occupancy_grid", 1, [&](const nav_msgs::OccupancyGrid::ConstPtr& g) {
        std::lock_guard<std::mutex> lock(mutex);
        if (!grid) grid = *g;
      });
  EXPECT_TRUE(test::waitFor(
      [&] {
        std::lock_guard<std::mutex> lock(mutex);
        return grid.has_value();
      },
      30.0))
      << "no occupancy grid";
  sub.shutdown();
  std::lock_guard<std::mutex> lock(mutex);
  return grid.value_or(nav_msgs::OccupancyGrid());
}

std::unordered_map<BlockKey, SubMesh, BlockKeyHash> fullMesh() {
  GetFullMesh full;
  std::unordered_map<BlockKey, SubMesh, BlockKeyHash> mesh;
  EXPECT_TRUE(ros::service::call("/stereo_fusion/get_full_mesh", full));
  EXPECT_TRUE(applyMeshUpdate(full.response.mesh, &mesh));
  return mesh;
}

int occupiedCells(const nav_msgs::OccupancyGrid& grid) {
  return static_cast<int>(std::count(grid.data.begin(), grid.data.end(), 100));
}

}  // namespace

TEST(MapStoreNode, AResumedNodeComesUpWithTheCheckpointedMapAndGoesOn) {
  const fs::path store = fs::temp_directory_path() / ("sf_map_store_" + std::to_string(::getpid()));
  fs::remove_all(store);
  ros::param::set("/stereo_fusion/map_store_path", store.string());
  ros::param::set("/stereo_fusion/checkpoint_period_s", 600.0);  // only ~save_map writes
  ros::param::set("/stereo_fusion/resume", false);
  Corridor corridor;
  FrameTopics topics;
  std::unordered_map<BlockKey, SubMesh, BlockKeyHash> saved_mesh;
  nav_msgs::OccupancyGrid saved_grid;
  const int frames = 8;
  {
    LoadedNodelet first;
    ASSERT_TRUE(first.ok());
    Outputs outputs;
    test::DiagnosticsWatcher diagnostics;
    ASSERT_TRUE(test::waitFor([&] { return topics.connected(); }, 30.0));
    ASSERT_TRUE(test::waitForTfSubscriber(30.0));
    for (int k = 0; k < frames; ++k) {
      topics.send(corridor.frame(k));
      ASSERT_TRUE(test::waitFor([&] { return diagnostics.value("frames fused") >= k + 1; }, 30.0))
          << "frame " << k;
    }
    SaveMap save;  // an empty path: a checkpoint of the map store
    ASSERT_TRUE(ros::service::call("/stereo_fusion/save_map", save));
    EXPECT_TRUE(save.response.success) << save.response.message;
    EXPECT_NE(save.response.message.find("checkpoint"), std::string::npos) << save.response.message;
    EXPECT_TRUE(fs::exists(store / "map.sqlite"));
    saved_mesh = fullMesh();
    EXPECT_FALSE(saved_mesh.empty());
    // The grid after the last frame (the planning timer runs at 4 Hz).
    ros::WallDuration(1.0).sleep();
    saved_grid = gridNow();
    EXPECT_GT(occupiedCells(saved_grid), 0);
  }

  ros::param::set("/stereo_fusion/resume", true);
  {
    Outputs outputs;  // subscribed before the node comes up: it hears the resumed map's update
    LoadedNodelet resumed;
    ASSERT_TRUE(resumed.ok());
    test::DiagnosticsWatcher diagnostics;
    // The mesh topic comes up with the checkpointed mesh, without a frame.
    ASSERT_TRUE(test::waitFor(
        [&] {
          std::lock_guard<std::mutex> lock(outputs.mutex);
          return outputs.streamed.size() >= saved_mesh.size();
        },
        30.0));
    {
      std::lock_guard<std::mutex> lock(outputs.mutex);
      EXPECT_TRUE(outputs.applied_ok);
      test::expectSameSubmeshes(outputs.streamed, saved_mesh);
    }
    test::expectSameSubmeshes(fullMesh(), saved_mesh);
    // So does the occupancy grid.
    const nav_msgs::OccupancyGrid grid = gridNow();
    EXPECT_EQ(occupiedCells(grid), occupiedCells(saved_grid));
    EXPECT_EQ(grid.info.width, saved_grid.info.width);
    EXPECT_EQ(grid.data, saved_grid.data);
    ASSERT_TRUE(diagnostics.waitForNextReport(10.0));
    EXPECT_EQ(diagnostics.value("map store: frames at the last checkpoint"), 0)
        << "no checkpoint since the resume";
    // It goes on fusing into the resumed map.
    ASSERT_TRUE(test::waitFor([&] { return topics.connected(); }, 30.0));
    for (int k = frames; k < frames + 3; ++k) {
      topics.send(corridor.frame(k));
      ASSERT_TRUE(
          test::waitFor([&] { return diagnostics.value("frames fused") >= k - frames + 1; }, 30.0))
          << "frame " << k;
    }
    SaveMap save;
    ASSERT_TRUE(ros::service::call("/stereo_fusion/save_map", save));
    EXPECT_TRUE(save.response.success) << save.response.message;
    EXPECT_NE(save.response.message.find(std::to_string(frames + 3) + " frames"), std::string::npos)
        << save.response.message;
  }

  // A store that is not one: the node maps without it and says so.
  fs::remove_all(store);
  fs::create_directories(store);
  {
    std::ofstream garbage(store / "map.sqlite", std::ios::binary);
    garbage << std::string(4096, 'x');
  }
  {
    LoadedNodelet refused;
    ASSERT_TRUE(refused.ok());
    std::mutex mutex;
    std::string error_message;
    ros::NodeHandle nh;
    ros::Subscriber levels = nh.subscribe<diagnostic_msgs::DiagnosticArray>(
        "/diagnostics", 10, [&](const diagnostic_msgs::DiagnosticArray::ConstPtr& a) {
          std::lock_guard<std::mutex> lock(mutex);
          for (const auto& s : a->status)
            if (s.name.find(": fusion") != std::string::npos &&
                s.level == diagnostic_msgs::DiagnosticStatus::ERROR)
              error_message = s.message;
        });
    ASSERT_TRUE(test::waitFor(
        [&] {
          std::lock_guard<std::mutex> lock(mutex);
          return !error_message.empty();
        },
        30.0));
    std::lock_guard<std::mutex> lock(mutex);
    EXPECT_NE(error_message.find("map.sqlite"), std::string::npos) << error_message;
    levels.shutdown();
  }
  fs::remove_all(store);
}

int main(int argc, char** argv) {
  return test::runRosTests(argc, argv, "stereo_fusion_map_store_test");
}
