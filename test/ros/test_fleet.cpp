// Three robots, one operator map (issue 51): three fusion nodelets in namespaces robot1..3, each
// fed its own simulated room by one rosbag player, and a base station (MeshAssembler with
// ~robots) in a fourth namespace. The operator mesh the base station saves is the union of each
// robot's own saved mesh carried by its alignment (vertex for vertex, within the one rounding to
// float), before and after robot2's alignment moves by 0.5 m and 5° — with nothing re-sent by
// robot2 — and its fleet costmap is the cell-wise rule (occupied > free > unknown, nearest-cell
// sampling at the merged cells' centres) applied to the robots' grids.
#include <map_msgs/OccupancyGridUpdate.h>
#include <nav_msgs/OccupancyGrid.h>
#include <std_srvs/SetBool.h>
#include <stereo_fusion/MeshUpdate.h>
#include <stereo_fusion/SaveMesh.h>
#include <tf2_eigen/tf2_eigen.h>
#include <tf2_ros/static_transform_broadcaster.h>
#include <unistd.h>

#include <atomic>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <mutex>
#include <optional>

#include "RosTestSupport.h"
#include "readers/PlyReader.h"
#include "stereo_fusion/planning/GridPatch.h"
#include "stereo_fusion/ros/GridMessages.h"

using namespace stereo_fusion;

namespace {

const std::vector<std::string> kRobots = {"robot1", "robot2", "robot3"};
const std::string kOperatorFrame = "operator";
const std::string kBase = "/base/mesh_assembler";

/// T_operator_robot: yaw about z, then a shift. The rooms lie 8 m apart along x (a corridor);
/// robot3's map frame is turned a quarter.
Eigen::Isometry3d alignment(double x_m, double y_m, double yaw_deg) {
  return Eigen::Translation3d(x_m, y_m, 0.0) *
         Eigen::AngleAxisd(yaw_deg * M_PI / 180.0, Eigen::Vector3d::UnitZ());
}

/// A robot's grid as its messages built it (the full grid patched by its updates).
class GridCopy {
 public:
  explicit GridCopy(const std::string& ns) {
    ros::NodeHandle nh(ns);
    grid_sub_ = nh.subscribe("occupancy_grid", 10, &GridCopy::onGrid, this);
    updates_sub_ = nh.subscribe("occupancy_grid_updates", 100, &GridCopy::onUpdate, this);
  }
  ~GridCopy() {
    grid_sub_.shutdown();
    updates_sub_.shutdown();
  }
  std::optional<OccupancyGrid2D> grid() {
    std::lock_guard<std::mutex> lock(mutex_);
    return grid_;
  }
  uint64_t messages() const { return messages_; }
  int refused() const { return refused_; }

 private:
  void onGrid(const nav_msgs::OccupancyGrid::ConstPtr& msg) {
    std::lock_guard<std::mutex> lock(mutex_);
    ++messages_;
    OccupancyGrid2D g;
    std::string error;
    if (!fromGridMessage(*msg, &g, &error)) {
      ++refused_;
      return;
    }
    grid_ = g;
  }
  void onUpdate(const map_msgs::OccupancyGridUpdate::ConstPtr& msg) {
    std::lock_guard<std::mutex> lock(mutex_);
    ++messages_;
    GridPatch patch;
    std::string error;
    if (!grid_ || !fromGridUpdateMessage(*msg, &patch, &error) ||
        !applyGridPatch(patch, &*grid_, &error))
      ++refused_;
  }
  std::mutex mutex_;
  std::optional<OccupancyGrid2D> grid_;
  std::atomic<uint64_t> messages_{0};
  std::atomic<int> refused_{0};
  ros::Subscriber grid_sub_, updates_sub_;
};

int rank(int8_t v) { return v < 0 ? 0 : (v == 0 ? 1 : 2); }

/// The rule, written out here independently of FleetGridMerge: for each merged cell, each
/// robot's cell containing the merged cell's centre carried back into its map frame
/// (R(yaw)ᵀ(c − t), floor((p − origin) / resolution)), and of those the highest rank.
/// Returns the number of cells that differ from `merged`; `occupied` counts its occupied cells.
int cellsBreakingTheRule(const OccupancyGrid2D& merged, const std::vector<OccupancyGrid2D>& robots,
                         const std::vector<Eigen::Isometry3d>& T, int* occupied) {
  int wrong = 0;
  *occupied = 0;
  for (int y = 0; y < merged.height; ++y)
    for (int x = 0; x < merged.width; ++x) {
      const Eigen::Vector2d c(merged.origin_x_m + (x + 0.5) * merged.resolution_m,
                              merged.origin_y_m + (y + 0.5) * merged.resolution_m);
      int best = 0;
      for (size_t k = 0; k < robots.size(); ++k) {
        const Eigen::Matrix3d& R = T[k].linear();
        const double yaw = std::atan2(R(1, 0) - R(0, 1), R(0, 0) + R(1, 1));
        const Eigen::Vector2d t = T[k].translation().head<2>();
        const Eigen::Vector2d p = Eigen::Rotation2Dd(yaw).toRotationMatrix().transpose() * (c - t);
        const OccupancyGrid2D& g = robots[k];
        const double ix = std::floor((p.x() - g.origin_x_m) / g.resolution_m);
        const double iy = std::floor((p.y() - g.origin_y_m) / g.resolution_m);
        if (ix < 0 || iy < 0 || ix >= g.width || iy >= g.height) continue;
        best = std::max(best, rank(g.at(static_cast<int>(ix), static_cast<int>(iy))));
      }
      const int8_t want = best == 0 ? -1 : (best == 1 ? 0 : 100);
      wrong += merged.at(x, y) != want ? 1 : 0;
      *occupied += merged.at(x, y) == 100 ? 1 : 0;
    }
  return wrong;
}

/// True when `got` is `exact` rounded once to float, allowing for the base station's T (from
/// tf: our quaternion, sent and turned back into a matrix) differing from ours in the last bits
/// of a double: that moves T · p by at most a few 1e-16 · (|p| + |t|), under 1e-12 m here, which
/// can move the rounding across one float boundary (one ulp), or, for a result within 1e-12 m of
/// zero, leave a remainder of that size.
bool roundedOnce(float got, double exact) {
  const float rounded = static_cast<float>(exact);
  const float ulp = std::nextafter(std::abs(rounded), INFINITY) - std::abs(rounded);
  return std::abs(static_cast<double>(got) - exact) <= ulp + 1e-12;
}

/// Empty when `op` is, robot by robot in kRobots' order, each robot's mesh with every vertex
/// carried by T[k] (positions and normals within one ulp, colours and triangles exact); else
/// the first difference.
std::string operatorMeshDifference(const TriangleMesh& op, const std::vector<TriangleMesh>& robots,
                                   const std::vector<Eigen::Isometry3d>& T) {
  size_t vertices = 0, triangles = 0;
  for (const TriangleMesh& m : robots)
    vertices += m.positions.size(), triangles += m.triangles.size();
  if (op.positions.size() != vertices || op.triangles.size() != triangles)
    return "operator mesh has " + std::to_string(op.positions.size()) + " vertices and " +
           std::to_string(op.triangles.size()) + " triangles, the robots " +
           std::to_string(vertices) + " and " + std::to_string(triangles);
  size_t v0 = 0, t0 = 0;
  for (size_t k = 0; k < robots.size(); ++k) {
    const TriangleMesh& m = robots[k];
    for (size_t i = 0; i < m.positions.size(); ++i) {
      const Eigen::Vector3d p = T[k] * m.positions[i].cast<double>();
      const Eigen::Vector3d n = T[k].linear() * m.normals[i].cast<double>();
      for (int a = 0; a < 3; ++a)
        if (!roundedOnce(op.positions[v0 + i][a], p[a]) ||
            !roundedOnce(op.normals[v0 + i][a], n[a]))
          return kRobots[k] + " vertex " + std::to_string(i) + " axis " + std::to_string(a) +
                 ": operator position " + std::to_string(op.positions[v0 + i][a]) + " normal " +
                 std::to_string(op.normals[v0 + i][a]) + ", the robot's carried by its alignment " +
                 std::to_string(p[a]) + " and " + std::to_string(n[a]);
      if (op.colors[v0 + i] != m.colors[i]) return kRobots[k] + " vertex colour differs";
    }
    for (size_t j = 0; j < m.triangles.size(); ++j)
      for (int a = 0; a < 3; ++a)
        if (op.triangles[t0 + j][a] != m.triangles[j][a] + v0)
          return kRobots[k] + " triangle " + std::to_string(j) + " differs";
    v0 += m.positions.size();
    t0 += m.triangles.size();
  }
  return {};
}

bool saveMesh(const std::string& service, const std::string& path, std::string* message) {
  SaveMesh srv;
  srv.request.path = path;
  if (!ros::service::call(service, srv)) {
    *message = service + " could not be called";
    return false;
  }
  *message = srv.response.message;
  return srv.response.success;
}

class Fleet : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("stereo_fusion_fleet_" + std::to_string(getpid()));
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }

  void sendAlignments() {
    std::vector<geometry_msgs::TransformStamped> transforms;
    for (size_t k = 0; k < kRobots.size(); ++k) {
      geometry_msgs::TransformStamped t = tf2::eigenToTransform(T_[k]);
      t.header.frame_id = kOperatorFrame;
      t.child_frame_id = kRobots[k] + "/map";
      transforms.push_back(t);
    }
    static_tf_.sendTransform(transforms);
  }

  /// Saves each robot's mesh and the operator mesh until they agree (the base station may be
  /// a message behind) or `timeout_s` passes; the last difference, or empty.
  std::string operatorMeshAgrees(double timeout_s, size_t* triangles) {
    std::string difference = "not compared";
    test::waitFor(
        [&] {
          std::vector<TriangleMesh> robots(kRobots.size());
          std::string message;
          for (size_t k = 0; k < kRobots.size(); ++k) {
            const std::string path = (dir_ / (kRobots[k] + ".ply")).string();
            if (!saveMesh("/" + kRobots[k] + "/stereo_fusion/save_mesh", path, &message) ||
                !readPly(path, &robots[k], &message)) {
              difference = kRobots[k] + ": " + message;
              return false;
            }
            if (robots[k].triangles.empty()) {
              difference = kRobots[k] + " has no mesh";
              return false;
            }
          }
          const std::string path = (dir_ / "operator.ply").string();
          TriangleMesh op;
          if (!saveMesh(kBase + "/save_mesh", path, &message) || !readPly(path, &op, &message)) {
            difference = "operator mesh: " + message;
            return false;
          }
          difference = operatorMeshDifference(op, robots, T_);
          *triangles = op.triangles.size();
          return difference.empty();
        },
        timeout_s);
    return difference;
  }

  /// Compares the base station's fleet costmap with the rule over the robots' grids until they
  /// agree or `timeout_s` passes; the last difference, or empty.
  std::string fleetGridAgrees(GridCopy& merged, std::vector<std::unique_ptr<GridCopy>>& robots,
                              double timeout_s, int* occupied) {
    std::string difference = "not compared";
    test::waitFor(
        [&] {
          std::vector<OccupancyGrid2D> grids;
          for (size_t k = 0; k < robots.size(); ++k) {
            const auto g = robots[k]->grid();
            if (!g) {
              difference = "no grid from " + kRobots[k];
              return false;
            }
            grids.push_back(*g);
          }
          auto m = merged.grid();
          if (!m) {
            difference = "no fleet costmap";
            return false;
          }
          // The message holds the resolution as a float32: the merge's cell centres are on the
          // double lattice of the parameter.
          m->resolution_m = ros::NodeHandle().param(kBase + "/grid_resolution_m", 0.05);
          const int wrong = cellsBreakingTheRule(*m, grids, T_, occupied);
          difference = wrong == 0
                           ? ""
                           : std::to_string(wrong) + " of " + std::to_string(m->cells.size()) +
                                 " merged cells break the rule";
          return wrong == 0;
        },
        timeout_s);
    return difference;
  }

  std::filesystem::path dir_;
  tf2_ros::StaticTransformBroadcaster static_tf_;
  std::vector<Eigen::Isometry3d> T_ = {alignment(0, 0, 0), alignment(8, 0, 0),
                                       alignment(16, 0.5, 90)};
};

TEST_F(Fleet, OperatorMapIsTheRobotsMapsPlacedByTheirAlignments) {
  ros::NodeHandle nh;
  sendAlignments();
  // Updates each robot sends (robot2's must stay 0 while only its alignment changes).
  std::atomic<int> updates[3]{};
  std::vector<ros::Subscriber> update_subs;
  for (size_t k = 0; k < kRobots.size(); ++k)
    update_subs.push_back(
        nh.subscribe<MeshUpdate>("/" + kRobots[k] + "/stereo_fusion/mesh_update", 100,
                                 [&updates, k](const MeshUpdate::ConstPtr&) { ++updates[k]; }));
  std::vector<std::unique_ptr<GridCopy>> grids;
  for (const std::string& robot : kRobots)
    grids.push_back(std::make_unique<GridCopy>("/" + robot + "/stereo_fusion"));
  GridCopy fleet_grid(kBase);
  test::DiagnosticsWatcher robot2_assembly("mesh assembler robot2");

  // Every nodelet and the base station run, then the player (waiting for every topic's
  // subscriber) plays the three bags.
  for (const std::string& robot : kRobots)
    ASSERT_TRUE(ros::service::waitForService("/" + robot + "/stereo_fusion/save_mesh", 60000))
        << robot;
  ASSERT_TRUE(ros::service::waitForService(kBase + "/save_mesh", 60000));
  ASSERT_TRUE(ros::service::waitForService("/player/pause_playback", 60000));
  ros::WallDuration(2.0).sleep();  // the base station's subscriptions connect
  std_srvs::SetBool play;
  play.request.data = false;
  ASSERT_TRUE(ros::service::call("/player/pause_playback", play));
  // The player exits when the bags end; then the robots' streams fall quiet.
  ASSERT_TRUE(test::waitFor(
      [] {
        std::vector<std::string> nodes;
        return ros::master::getNodes(nodes) &&
               std::find(nodes.begin(), nodes.end(), "/player") == nodes.end();
      },
      240.0))
      << "the bags did not finish";
  int quiet_since[3] = {-1, -1, -1};
  ASSERT_TRUE(test::waitFor(
      [&] {
        bool quiet = true;
        for (size_t k = 0; k < kRobots.size(); ++k) {
          quiet = quiet && updates[k].load() == quiet_since[k];
          quiet_since[k] = updates[k].load();
        }
        if (!quiet) ros::WallDuration(3.0).sleep();
        return quiet;
      },
      120.0));
  for (size_t k = 0; k < kRobots.size(); ++k) EXPECT_GT(updates[k].load(), 0) << kRobots[k];

  size_t triangles = 0;
  std::string difference = operatorMeshAgrees(60.0, &triangles);
  ASSERT_EQ(difference, "") << "before the alignment change";
  EXPECT_GT(triangles, 1000u);
  int occupied = 0;
  difference = fleetGridAgrees(fleet_grid, grids, 30.0, &occupied);
  EXPECT_EQ(difference, "") << "before the alignment change";
  EXPECT_GT(occupied, 0);
  {
    const auto m = fleet_grid.grid();
    ASSERT_TRUE(m);
    std::cout << "[fleet] operator mesh: " << triangles << " triangles; fleet costmap " << m->width
              << " x " << m->height << " cells, " << occupied << " occupied; robots' grids";
    for (auto& g : grids)
      if (const auto rg = g->grid()) std::cout << " " << rg->width << " x " << rg->height;
    std::cout << std::endl;
  }
  for (size_t k = 0; k < kRobots.size(); ++k) EXPECT_EQ(grids[k]->refused(), 0) << kRobots[k];
  EXPECT_EQ(fleet_grid.refused(), 0);

  // A multi-robot SLAM moves robot2's map by 0.5 m and 5°: its mesh is re-placed on the base
  // station from what it holds, nothing is re-sent.
  ASSERT_TRUE(robot2_assembly.waitForNextReport(10.0));
  const long full_requests = robot2_assembly.value("full mesh requests");
  const int robot2_updates = updates[1].load();
  T_[1] = alignment(8.5, 0, 5);
  sendAlignments();
  difference = operatorMeshAgrees(30.0, &triangles);
  EXPECT_EQ(difference, "") << "after the alignment change";
  difference = fleetGridAgrees(fleet_grid, grids, 30.0, &occupied);
  EXPECT_EQ(difference, "") << "after the alignment change";
  EXPECT_EQ(updates[1].load(), robot2_updates) << "robot2 sent mesh updates";
  ASSERT_TRUE(robot2_assembly.waitForNextReport(10.0));
  EXPECT_EQ(robot2_assembly.value("full mesh requests"), full_requests)
      << "the base station fetched robot2's mesh again";

  // The fleet costmap in map_server format.
  SaveMesh save;
  save.request.path = (dir_ / "operator_grid.pgm").string();
  ASSERT_TRUE(ros::service::call(kBase + "/save_grid", save));
  EXPECT_TRUE(save.response.success) << save.response.message;
  EXPECT_TRUE(std::filesystem::is_regular_file(dir_ / "operator_grid.pgm"));
  EXPECT_TRUE(std::filesystem::is_regular_file(dir_ / "operator_grid.yaml"));
  save.request.path = (dir_ / "operator_grid.png").string();
  ASSERT_TRUE(ros::service::call(kBase + "/save_grid", save));
  EXPECT_FALSE(save.response.success);
}

TEST_F(Fleet, OperatorMeshIsRefusedWhileARobotHasNoAlignment) {
  // Runs after the first test (gtest keeps the order): every robot has a mesh. Without the
  // transform to robot3's frame the save is refused, naming it, and nothing is written.
  sendAlignments();
  ros::NodeHandle nh;
  geometry_msgs::TransformStamped elsewhere = tf2::eigenToTransform(T_[2]);
  elsewhere.header.frame_id = "elsewhere";
  elsewhere.child_frame_id = "robot3/map";
  // robot3/map gets another parent: the operator frame no longer reaches it.
  std::vector<geometry_msgs::TransformStamped> transforms;
  for (size_t k = 0; k < 2; ++k) {
    geometry_msgs::TransformStamped t = tf2::eigenToTransform(T_[k]);
    t.header.frame_id = kOperatorFrame;
    t.child_frame_id = kRobots[k] + "/map";
    transforms.push_back(t);
  }
  transforms.push_back(elsewhere);
  static_tf_.sendTransform(transforms);
  const std::string path = (dir_ / "refused.ply").string();
  std::string message;
  // Until the base station's tf has the new tree, a save still succeeds.
  ASSERT_TRUE(test::waitFor([&] { return !saveMesh(kBase + "/save_mesh", path, &message); }, 20.0))
      << message;
  std::filesystem::remove(path);
  EXPECT_FALSE(saveMesh(kBase + "/save_mesh", path, &message));
  EXPECT_NE(message.find("robot3"), std::string::npos) << message;
  EXPECT_FALSE(std::filesystem::exists(path));
}

}  // namespace

int main(int argc, char** argv) { return test::runRosTests(argc, argv, "fleet_test"); }
