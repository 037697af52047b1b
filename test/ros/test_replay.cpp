// A simulator bag played through launch/replay.launch (sim time) gives the same mesh as the
// offline pipeline on the same bag with the same parameters.
#include <stereo_fusion/ClearBox.h>
#include <stereo_fusion/GetDistance.h>
#include <stereo_fusion/GetEsdfBox.h>
#include <stereo_fusion/GetFullMesh.h>
#include <stereo_fusion/MeshUpdate.h>

#include "RosTestSupport.h"

#include "stereo_fusion/Mapper.h"
#include "stereo_fusion/StageConfigs.h"
#include "stereo_fusion/ros/BagSequence.h"
#include "stereo_fusion/ros/MeshMessages.h"
#include "stereo_fusion/ros/RosParameters.h"

#include <fstream>
#include <random>
#include <mutex>
#include <sstream>

#include "readers/DatasetReader.h"
#include "simulator/SceneLibrary.h"
#include "stereo_fusion/trajectory/PoseCorrection.h"

#include <nav_msgs/Path.h>
#include <tf2_eigen/tf2_eigen.h>

#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <stereo_msgs/DisparityImage.h>

using namespace stereo_fusion;

namespace {
/// Waits (at most `timeout_s`) until the nodelet has fused all `frames` of the bag; fails the
/// test, naming where frames were lost, if it has not. The launch files make the player wait
/// for the nodelet's subscriptions: a frame published before them is lost uncounted.
void expectEveryFrameFused(test::DiagnosticsWatcher& diagnostics, long frames, double timeout_s) {
  auto diag = [&](const char* key) { return diagnostics.value(key); };
  test::waitFor([&] { return diag("frames fused") >= frames; }, timeout_s);
  ASSERT_EQ(diag("frames fused"), frames)
      << "disparities received " << diag("disparities received") << ", missed upstream "
      << diag("disparities missed upstream (header.seq gaps)") << ", not synchronised "
      << diag("dropped: not synchronised (no matching image / camera_info yet)") << ", dropped tf "
      << diag("dropped: tf timeout") << ", queue " << diag("dropped: queue full") << ", bad "
      << diag("dropped: bad input");
}

/// A simulated room sequence and its bag, as the launch file passes them: the test node's
/// parameters bag, sequence and seed.
struct SimulatedRoom {
  std::string bag, sequence;
  std::optional<sim::ScenePreset> room;  ///< the room preset of that seed: the static truth
};

void readSimulatedRoom(SimulatedRoom* out) {
  ros::NodeHandle pnh("~");
  int seed = 0;
  ASSERT_TRUE(pnh.getParam("bag", out->bag));
  ASSERT_TRUE(pnh.getParam("sequence", out->sequence));
  ASSERT_TRUE(pnh.getParam("seed", seed));
  out->room = sim::makePreset("room", static_cast<uint32_t>(seed));
  ASSERT_TRUE(out->room);
}
}  // namespace

TEST(Replay, BagThroughTheNodeletEqualsTheOfflinePipeline) {
  ros::NodeHandle pnh("~");
  std::string bag_path;
  ASSERT_TRUE(pnh.getParam("bag", bag_path));
  std::string error;
  auto bag = BagSequence::open(bag_path, BagTopics{}, &error);
  ASSERT_TRUE(bag) << error;
  const long frames = static_cast<long>(bag->size());
  ASSERT_GT(frames, 5);

  test::DiagnosticsWatcher diagnostics;
  ASSERT_TRUE(test::startPausedPlayer(diagnostics));
  ASSERT_NO_FATAL_FAILURE(expectEveryFrameFused(diagnostics, frames, 120.0));

  // The same parameters as the nodelet, read the way the nodelet reads them.
  MapperConfig config;
  NodeConfig node;
  ASSERT_TRUE(loadParameters(ros::NodeHandle("/stereo_fusion"), &config, &node, &error)) << error;
  Mapper offline(config);
  for (size_t i = 0; i < bag->size(); ++i) {
    StereoFrame f;
    ASSERT_TRUE(bag->load(i, &f, &error)) << error;
    ASSERT_TRUE(offline.integrate(f).accepted);
  }

  GetFullMesh full;
  ASSERT_TRUE(ros::service::call("/stereo_fusion/get_full_mesh", full));
  std::unordered_map<BlockKey, SubMesh, BlockKeyHash> live;
  ASSERT_TRUE(applyMeshUpdate(full.response.mesh, &live));
  const auto& expected = offline.mesh().submeshes();
  ASSERT_GT(expected.size(), 20u);
  test::expectSameSubmeshes(live, expected);
}

// replay_odom.test and replay_odom_yaml.test: a bag whose /tf holds only odom -> camera (no
// map), replayed with world_frame odom — replay.launch's argument in the one, the config YAML's
// key with no argument in the other (fusion.launch must not overwrite it with its own) — is
// fused whole: not one frame dropped as "tf timeout", the outputs in odom.
TEST(ReplayWorldFrame, ABagInTheConfiguredFrameLosesNoFrameToTf) {
  ros::NodeHandle pnh("~");
  std::string bag_path, world_frame, error;
  ASSERT_TRUE(pnh.getParam("bag", bag_path));
  ASSERT_TRUE(pnh.getParam("world_frame", world_frame));
  ASSERT_NE(world_frame, NodeConfig{}.world_frame)
      << "the test needs a frame other than the default";
  BagTopics topics;
  topics.world_frame = world_frame;
  auto bag = BagSequence::open(bag_path, topics, &error);
  ASSERT_TRUE(bag) << error;
  const long frames = static_cast<long>(bag->size());
  ASSERT_GT(frames, 5);
  {  // In the default frame the bag has no pose at all: a node left at it would fuse nothing.
    auto in_default = BagSequence::open(bag_path, BagTopics{}, &error);
    ASSERT_TRUE(in_default) << error;
    StereoFrame f;
    EXPECT_FALSE(in_default->load(0, &f, &error));
    EXPECT_NE(error.find("no transform " + NodeConfig{}.world_frame + " <- "), std::string::npos)
        << error;
  }
  std::string node_frame;
  ASSERT_TRUE(ros::param::get("/stereo_fusion/world_frame", node_frame));
  EXPECT_EQ(node_frame, world_frame);

  std::mutex mutex;
  std::string path_frame;
  ros::NodeHandle nh;
  ros::Subscriber path_sub = nh.subscribe<nav_msgs::Path>(
      "/stereo_fusion/camera_path", 1, [&](const nav_msgs::Path::ConstPtr& path) {
        std::lock_guard<std::mutex> lock(mutex);
        path_frame = path->header.frame_id;
      });
  test::DiagnosticsWatcher diagnostics;
  ASSERT_TRUE(test::startPausedPlayer(diagnostics));
  ASSERT_NO_FATAL_FAILURE(expectEveryFrameFused(diagnostics, frames, 120.0));
  EXPECT_EQ(diagnostics.value("dropped: tf timeout"), 0);
  EXPECT_EQ(diagnostics.droppedTotal(), 0);
  test::waitFor(
      [&] {
        std::lock_guard<std::mutex> lock(mutex);
        return !path_frame.empty();
      },
      10.0);
  std::lock_guard<std::mutex> lock(mutex);
  EXPECT_EQ(path_frame, world_frame) << "~camera_path";
}

// At 50x the bag's rate (replay_fast.test) most frames are dropped somewhere: in rosbag's or the
// nodelet's subscriber queues (seen as gaps in header.seq), in the synchroniser or in the worker's
// queue. Frames in the bag = received + missed upstream; received = fused + every "dropped:".
TEST(ReplayFast, EveryFrameOfTheBagIsFusedOrCountedAsLost) {
  ros::NodeHandle pnh("~");
  std::string bag_path;
  ASSERT_TRUE(pnh.getParam("bag", bag_path));
  long frames = 0;
  {
    rosbag::Bag bag(bag_path, rosbag::bagmode::Read);
    for (const rosbag::MessageInstance& m :
         rosbag::View(bag, rosbag::TopicQuery(std::string("/stereo/disparity")))) {
      const auto disparity = m.instantiate<stereo_msgs::DisparityImage>();
      ASSERT_TRUE(disparity);
      ASSERT_EQ(disparity->header.seq, static_cast<uint32_t>(++frames))
          << "the simulator numbers its frames";
    }
  }
  ASSERT_GT(frames, 100);

  test::DiagnosticsWatcher diagnostics;
  auto diag = [&](const std::string& key) { return std::max(0L, diagnostics.value(key)); };
  long received = 0, missed = 0, fused = 0, dropped = 0;
  auto read = [&] {
    received = diag("disparities received");
    missed = diag("disparities missed upstream (header.seq gaps)");
    fused = diag("frames fused");
    dropped = diagnostics.droppedTotal();
  };
  // The node counts a lost disparity from the gap it leaves between two numbers it received, so
  // losses at the bag's very start or end would go unseen: numbered disparities of this test
  // bracket the bag, seq 0 before it (the bag starts at 1) and frames + 1 once its counters stop
  // moving. Each finds no image: it is counted as received and not synchronised.
  ros::NodeHandle nh;
  // Like rosbag play, a publisher without the header flag: roscpp keeps the seq set below
  // instead of numbering this publisher's messages from 0.
  ros::AdvertiseOptions options = ros::AdvertiseOptions::create<stereo_msgs::DisparityImage>(
      "/stereo/disparity", 1, ros::SubscriberStatusCallback(), ros::SubscriberStatusCallback(),
      ros::VoidConstPtr(), nullptr);
  options.has_header = false;
  ros::Publisher bracket_pub = nh.advertise(options);
  ASSERT_TRUE(test::waitFor([&] { return bracket_pub.getNumSubscribers() > 0; }, 30.0));
  stereo_msgs::DisparityImage first;
  first.header.seq = 0;
  first.header.stamp =
      ros::Time(0, 1000000);  // 1 ms: before the bag's first stamp, on none of them
  bracket_pub.publish(first);
  ASSERT_TRUE(test::waitFor([&] { return diag("disparities received") >= 1; }, 30.0));
  ASSERT_TRUE(test::startPausedPlayer(diagnostics));
  long settled = -1;
  ASSERT_TRUE(test::waitFor(
      [&] {
        read();
        const long now = received + missed;
        const bool still =
            now > 1 && now == settled;  // more than the first bracket: the bag has begun
        settled = now;
        if (!still) ros::WallDuration(2.0).sleep();
        return still;
      },
      120.0));
  stereo_msgs::DisparityImage last;
  last.header.seq = static_cast<uint32_t>(frames + 1);
  last.header.stamp = ros::Time::now() + ros::Duration(1.0);
  bracket_pub.publish(last);
  test::waitFor(
      [&] {
        read();
        return received + missed >= frames + 2 && fused + dropped >= received;
      },
      60.0);
  ros::WallDuration(2.0).sleep();
  ASSERT_TRUE(diagnostics.waitForNextReport(10.0));
  read();
  std::printf(
      "[replay 50x] %ld frames in the bag + 2: %ld received, %ld missed upstream, %ld fused, %ld "
      "dropped\n",
      frames, received, missed, fused, dropped);
  EXPECT_EQ(received + missed, frames + 2);
  EXPECT_EQ(fused + dropped, received);
  EXPECT_GT(fused, 0);
}

namespace {
/// The "ghost_region x0 y0 z0 x1 y1 z1" lines of a simulator sequence's dynamic.txt.
std::vector<Eigen::AlignedBox3d> ghostRegions(const std::string& sequence) {
  std::vector<Eigen::AlignedBox3d> regions;
  std::ifstream in(sequence + "/dynamic.txt");
  std::string line, kind;
  while (std::getline(in, line)) {
    std::istringstream fields(line);
    Eigen::Vector3d lo, hi;
    if (fields >> kind >> lo.x() >> lo.y() >> lo.z() >> hi.x() >> hi.y() >> hi.z() &&
        kind == "ghost_region")
      regions.emplace_back(lo, hi);
  }
  return regions;
}

/// True if one of `frames` sees through `point`: it projects into the image where the measured
/// depth lies more than 10 cm beyond it. Only what later frames see through can be cleared by
/// their evidence; a ghost no later frame looks at stays with any mapper.
bool seenThrough(const std::vector<StereoFrame>& frames, const Eigen::Vector3d& point) {
  for (const StereoFrame& f : frames) {
    const Eigen::Vector3d p = f.T_world_camera.inverse() * point;
    if (p.z() <= 0.0) continue;
    const long u = std::lround(f.camera.fx() * p.x() / p.z() + f.camera.cx());
    const long v = std::lround(f.camera.fy() * p.y() / p.z() + f.camera.cy());
    if (u < 0 || v < 0 || u >= f.camera.width() || v >= f.camera.height()) continue;
    const float disparity = f.disparity_px.at<float>(v, u);
    if (disparity > 0.0f && f.camera.fx() * f.camera.baseline() / disparity > p.z() + 0.1)
      return true;
  }
  return false;
}

/// Vertices of `mesh` inside a ghost region, more than 5 cm from every surface of the static
/// scene `truth`, that one of `later` sees through: what is left of the objects that went where
/// later frames looked.
template <typename Mesh>
size_t ghostVertices(const Mesh& mesh, const std::vector<Eigen::AlignedBox3d>& regions,
                     const sim::AnalyticScene& truth, const std::vector<StereoFrame>& later) {
  size_t n = 0;
  for (const auto& [key, sub] : mesh)
    for (const Eigen::Vector3f& p : sub.positions) {
      const Eigen::Vector3d q = p.cast<double>();
      bool inside = false;
      for (const Eigen::AlignedBox3d& r : regions) inside = inside || r.contains(q);
      n += inside && truth.distanceToSurface(q) > 0.05 && seenThrough(later, q);
    }
  return n;
}
}  // namespace

// dynamic_replay.test: a simulated room orbited twice with a person standing in it during the
// first lap (stereo_fusion_simulate --dynamic person), played through replay.launch. Without
// free-space carving the person stays in the mesh; the nodelet with its defaults (carving on)
// leaves at most 5 % of the ghost the second lap sees through (the lap's radius differs: the
// top of the person, seen at the image's edge in the first lap, is not looked at again), and
// gives the offline pipeline's mesh.
TEST(DynamicReplay, APersonWhoLeftIsClearedFromTheLiveMesh) {
  SimulatedRoom sim;
  ASSERT_NO_FATAL_FAILURE(readSimulatedRoom(&sim));
  const std::vector<Eigen::AlignedBox3d> regions = ghostRegions(sim.sequence);
  ASSERT_EQ(regions.size(), 1u) << sim.sequence << "/dynamic.txt";
  // The stream, as a base station receives it from the first update on (the bag starts once it
  // is connected): carving empties the person's submeshes, which must arrive as removals.
  std::mutex stream_mutex;
  std::unordered_map<BlockKey, SubMesh, BlockKeyHash> streamed;
  uint64_t first_sequence = 0, last_sequence = 0, sequence_gaps = 0, removals = 0;
  bool applied_ok = true;
  ros::NodeHandle nh;
  ros::Subscriber stream = nh.subscribe<MeshUpdate>(
      "/stereo_fusion/mesh_update", 1000, [&](const MeshUpdate::ConstPtr& u) {
        std::lock_guard<std::mutex> lock(stream_mutex);
        if (first_sequence == 0) first_sequence = u->sequence;
        if (last_sequence != 0 && u->sequence != last_sequence + 1) ++sequence_gaps;
        last_sequence = u->sequence;
        removals += u->removed_keys.size() / 3;
        applied_ok &= applyMeshUpdate(*u, &streamed);
      });
  std::string error;
  auto bag = BagSequence::open(sim.bag, BagTopics{}, &error);
  ASSERT_TRUE(bag) << error;
  const long frames = static_cast<long>(bag->size());

  test::DiagnosticsWatcher diagnostics;
  ASSERT_TRUE(test::waitFor([&] { return stream.getNumPublishers() > 0; }, 60.0))
      << "no ~mesh_update publisher";
  ASSERT_TRUE(test::startPausedPlayer(diagnostics));
  ASSERT_NO_FATAL_FAILURE(expectEveryFrameFused(diagnostics, frames, 150.0));

  MapperConfig config;
  NodeConfig node;
  ASSERT_TRUE(loadParameters(ros::NodeHandle("/stereo_fusion"), &config, &node, &error)) << error;
  ASSERT_TRUE(config.free_space_carving) << "the default";
  auto fuse = [&](bool carving) {
    MapperConfig c = config;
    c.free_space_carving = carving;
    auto mapper = std::make_unique<Mapper>(c);
    for (size_t i = 0; i < bag->size(); ++i) {
      StereoFrame f;
      EXPECT_TRUE(bag->load(i, &f, &error)) << error;
      EXPECT_TRUE(mapper->integrate(f).accepted);
    }
    return mapper;
  };
  const auto without_carving = fuse(false);
  const auto with_carving = fuse(true);
  std::vector<StereoFrame> second_lap;  // the person has gone
  for (size_t i = bag->size() / 2; i < bag->size(); ++i) {
    StereoFrame f;
    ASSERT_TRUE(bag->load(i, &f, &error)) << error;
    second_lap.push_back(f);
  }

  GetFullMesh full;
  ASSERT_TRUE(ros::service::call("/stereo_fusion/get_full_mesh", full));
  std::unordered_map<BlockKey, SubMesh, BlockKeyHash> live;
  ASSERT_TRUE(applyMeshUpdate(full.response.mesh, &live));
  const size_t ghost_off =
      ghostVertices(without_carving->mesh().submeshes(), regions, sim.room->scene, second_lap);
  const size_t ghost_live = ghostVertices(live, regions, sim.room->scene, second_lap);
  std::printf("[dynamic replay] %ld frames: ghost vertices %zu without carving, %zu live with it\n",
              frames, ghost_off, ghost_live);
  ASSERT_GT(ghost_off, 300u) << "the person must leave a ghost when nothing clears it";
  EXPECT_LE(ghost_live, ghost_off / 20) << "more than 5 % of the ghost is left";
  test::expectSameSubmeshes(live, with_carving->mesh().submeshes());

  // The full mesh answers with the last published sequence: once the stream reached it, the
  // streamed copy must equal it.
  ASSERT_TRUE(test::waitFor(
      [&] {
        std::lock_guard<std::mutex> lock(stream_mutex);
        return last_sequence >= full.response.mesh.sequence;
      },
      10.0));
  stream.shutdown();
  std::lock_guard<std::mutex> lock(stream_mutex);
  EXPECT_EQ(first_sequence, 1u) << "the test subscribed after the first update";
  EXPECT_EQ(sequence_gaps, 0u);
  EXPECT_TRUE(applied_ok);
  EXPECT_GT(removals, 0u) << "carving emptied no submesh?";
  test::expectSameSubmeshes(streamed, live);
}

namespace {
/// Median and p90 of the distances of `mesh`'s vertices to the scene.
template <typename Mesh>
std::pair<double, double> vertexErrors(const Mesh& mesh, const sim::AnalyticScene& truth) {
  std::vector<double> d;
  for (const auto& [key, sub] : mesh)
    for (const Eigen::Vector3f& p : sub.positions)
      d.push_back(truth.distanceToSurface(p.cast<double>()));
  if (d.empty()) return {1e9, 1e9};
  std::sort(d.begin(), d.end());
  return {d[d.size() / 2], d[d.size() * 9 / 10]};
}

/// The last message of a latched topic.
template <typename M>
typename M::ConstPtr latest(const std::string& topic, double timeout_s) {
  typename M::ConstPtr got;
  ros::NodeHandle nh;
  ros::Subscriber sub = nh.subscribe<M>(topic, 1, [&](const typename M::ConstPtr& m) { got = m; });
  test::waitFor([&] { return got != nullptr; }, timeout_s);
  return got;
}
}  // namespace

// loop_closure.test: a room orbited twice whose /tf drifts like odometry (4° and 0.15 m by the
// end), with the SLAM's corrected keyframe poses on /trajectory after the middle frame and after
// the last (simulator --drift). The nodelet re-fuses its kept frames at the corrected poses while
// it goes on fusing: its final mesh is the offline pipeline's at the corrected poses, lies as close
// to the truth as fusing at the true poses (within 1.25×), and ~camera_path is corrected.
TEST(LoopClosureReplay, TheLiveMapFollowsTheCorrectedTrajectory) {
  SimulatedRoom sim;
  ASSERT_NO_FATAL_FAILURE(readSimulatedRoom(&sim));
  std::string error;
  auto bag = BagSequence::open(sim.bag, BagTopics{}, &error);
  ASSERT_TRUE(bag) << error;
  const long frames = static_cast<long>(bag->size());

  test::DiagnosticsWatcher diagnostics;
  auto diag = [&](const char* key) { return diagnostics.value(key); };
  ASSERT_TRUE(test::startPausedPlayer(diagnostics));
  ASSERT_NO_FATAL_FAILURE(expectEveryFrameFused(diagnostics, frames, 150.0));
  // Two trajectories: the first may be superseded by the second while it is re-fused; the
  // second, after the last frame, is applied.
  ASSERT_TRUE(test::waitFor(
      [&] {
        return diag("corrections applied") >= 1 &&
               diag("corrections applied") + diag("corrections superseded by a newer trajectory") >=
                   2;
      },
      120.0))
      << diag("corrections applied") << " applied, " << diag("trajectories rejected")
      << " rejected, " << diag("trajectories received") << " received, "
      << diag("corrections superseded by a newer trajectory") << " superseded, "
      << diag("trajectories taken without re-fusion") << " taken without re-fusion, "
      << diag("corrections dropped by reset/load") << " dropped by reset/load, "
      << diag("loop closure: frames kept") << " frames kept";
  EXPECT_EQ(diag("trajectories received"), 2);
  EXPECT_EQ(diag("trajectories rejected"), 0);
  std::printf("[loop closure] %ld frames; last correction: %ld frames fused again in %ld ms\n",
              frames, diag("loop closure: last correction, frames fused again"),
              diag("loop closure: last correction (ms)"));

  MapperConfig config;
  NodeConfig node;
  ASSERT_TRUE(loadParameters(ros::NodeHandle("/stereo_fusion"), &config, &node, &error)) << error;
  // The frames as the nodelet fused them, the trajectory it got last, the true poses.
  std::vector<StereoFrame> loaded(bag->size());
  std::vector<StampedPose> originals;
  for (size_t i = 0; i < bag->size(); ++i) {
    ASSERT_TRUE(bag->load(i, &loaded[i], &error)) << error;
    originals.push_back({loaded[i].timestamp_s, loaded[i].T_world_camera});
  }
  std::vector<StampedPose> trajectory;
  {
    rosbag::Bag raw(sim.bag, rosbag::bagmode::Read);
    for (const rosbag::MessageInstance& m :
         rosbag::View(raw, rosbag::TopicQuery(std::string("/trajectory")))) {
      const auto path = m.instantiate<nav_msgs::Path>();
      ASSERT_TRUE(path);
      trajectory.clear();
      for (const auto& p : path->poses) {
        Eigen::Isometry3d T;
        tf2::fromMsg(p.pose, T);
        trajectory.push_back({p.header.stamp.toSec(), T});
      }
    }
  }
  ASSERT_GT(trajectory.size(), 10u);
  std::vector<DatasetFrameInfo> truth_lines;
  ASSERT_TRUE(readTumPoses(sim.sequence + "/poses_true.txt", &truth_lines, &error)) << error;
  ASSERT_EQ(truth_lines.size(), loaded.size());
  const PoseCorrection correction(originals, trajectory, loaded.back().timestamp_s);
  auto fuse = [&](auto pose_of) {
    auto mapper = std::make_unique<Mapper>(config);
    for (size_t i = 0; i < loaded.size(); ++i) {
      StereoFrame f = loaded[i];
      f.T_world_camera = pose_of(i);
      EXPECT_TRUE(mapper->integrate(f, MeshTiming::kDeferred).accepted);
    }
    mapper->updateMesh();
    return mapper;
  };
  const auto corrected = fuse([&](size_t i) {
    return correction.corrected(originals[i].stamp_s, originals[i].T_world_camera);
  });
  const auto drifting = fuse([&](size_t i) { return originals[i].T_world_camera; });
  const auto at_truth = fuse([&](size_t i) { return truth_lines[i].T_world_camera; });

  GetFullMesh full;
  ASSERT_TRUE(ros::service::call("/stereo_fusion/get_full_mesh", full));
  std::unordered_map<BlockKey, SubMesh, BlockKeyHash> live;
  ASSERT_TRUE(applyMeshUpdate(full.response.mesh, &live));
  test::expectSameSubmeshes(live, corrected->mesh().submeshes());

  const auto [live_median, live_p90] = vertexErrors(live, sim.room->scene);
  const auto [drift_median, drift_p90] =
      vertexErrors(drifting->mesh().submeshes(), sim.room->scene);
  const auto [true_median, true_p90] = vertexErrors(at_truth->mesh().submeshes(), sim.room->scene);
  std::printf(
      "[loop closure] vertex error median / p90 (mm): drifting %.1f / %.1f, live corrected %.1f / "
      "%.1f, "
      "true poses %.1f / %.1f\n",
      1e3 * drift_median, 1e3 * drift_p90, 1e3 * live_median, 1e3 * live_p90, 1e3 * true_median,
      1e3 * true_p90);
  EXPECT_GT(drift_p90, 2.0 * true_p90) << "the drift must double the walls";
  EXPECT_LE(live_median, 1.25 * true_median);
  EXPECT_LE(live_p90, 1.25 * true_p90);

  // ~camera_path shows the corrected path: its last pose is the last keyframe's true pose.
  const auto path = latest<nav_msgs::Path>("/stereo_fusion/camera_path", 10.0);
  ASSERT_TRUE(path);
  ASSERT_EQ(path->poses.size(), loaded.size());
  Eigen::Isometry3d last;
  tf2::fromMsg(path->poses.back().pose, last);
  EXPECT_LT((last.translation() - truth_lines.back().T_world_camera.translation()).norm(), 1e-3);
}

namespace {
double percentileOf(std::vector<double> v, double p) {
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  return v[static_cast<size_t>(p * (v.size() - 1))];
}
}  // namespace

TEST(PlanningReplay, DistancesMatchTheAnalyticRoomAndBadRequestsChangeNothing) {
  SimulatedRoom sim;
  ASSERT_NO_FATAL_FAILURE(readSimulatedRoom(&sim));
  std::string error;
  auto bag = BagSequence::open(sim.bag, BagTopics{}, &error);
  ASSERT_TRUE(bag) << error;
  test::DiagnosticsWatcher diagnostics;
  ASSERT_TRUE(test::startPausedPlayer(diagnostics));
  ASSERT_NO_FATAL_FAILURE(
      expectEveryFrameFused(diagnostics, static_cast<long>(bag->size()), 150.0));
  // Frames fused are in the planning layer after the next meshing pass: a full mesh forces one.
  GetFullMesh full;
  ASSERT_TRUE(ros::service::call("/stereo_fusion/get_full_mesh", full));

  // 100 000 points over the room's interior and a margin beyond its walls.
  const sim::AnalyticScene& scene = sim.room->scene;
  Eigen::AlignedBox3d box = sim.room->room_interior;
  box.min() -= Eigen::Vector3d::Constant(0.3);
  box.max() += Eigen::Vector3d::Constant(0.3);
  std::mt19937 rng(7);
  GetDistance query;
  std::vector<Eigen::Vector3d> points;
  for (int k = 0; k < 100000; ++k) {
    Eigen::Vector3d p;
    for (int a = 0; a < 3; ++a)
      p[a] = std::uniform_real_distribution<double>(box.min()[a], box.max()[a])(rng);
    points.push_back(p);
    geometry_msgs::Point q;
    q.x = p.x();
    q.y = p.y();
    q.z = p.z();
    query.request.points.push_back(q);
  }
  const ros::WallTime start = ros::WallTime::now();
  ASSERT_TRUE(ros::service::call("/stereo_fusion/get_distance", query));
  const double call_ms = (ros::WallTime::now() - start).toSec() * 1e3;
  ASSERT_TRUE(query.response.success) << query.response.message;
  ASSERT_EQ(query.response.distances.size(), points.size());
  ASSERT_EQ(query.response.states.size(), points.size());
  ASSERT_EQ(query.response.gradients.size(), points.size());

  MapperConfig config;
  NodeConfig node;
  ASSERT_TRUE(loadParameters(ros::NodeHandle("/stereo_fusion"), &config, &node, &error)) << error;
  const double cell_m = stageConfigs(config).planning.planning.cell_m;
  const double max_m = config.esdf_max_distance_m;
  std::vector<double> errors_m;
  size_t free = 0, occupied = 0, unknown = 0, free_inside_solid = 0, gradients_checked = 0,
         gradients_agree = 0;
  for (size_t k = 0; k < points.size(); ++k) {
    const double truth_m = scene.clearance(points[k]);
    const uint8_t state = query.response.states[k];
    const double d = query.response.distances[k];
    if (state == GetDistance::Response::UNKNOWN) {
      ++unknown;
      EXPECT_TRUE(std::isnan(d));
      continue;
    }
    (state == GetDistance::Response::FREE ? free : occupied) += 1;
    // Seen empty deep inside a wall or a piece of furniture is an error.
    if (state == GetDistance::Response::FREE && truth_m < -2.0 * cell_m) ++free_inside_solid;
    if (state == GetDistance::Response::FREE && truth_m > 2.0 * cell_m &&
        truth_m < max_m - 2.0 * cell_m) {
      errors_m.push_back(std::abs(d - truth_m));
      const geometry_msgs::Vector3& g = query.response.gradients[k];
      const Eigen::Vector3d gradient(g.x, g.y, g.z);
      if (gradient.norm() > 0.5) {  // interpolated
        Eigen::Vector3d numeric;
        for (int a = 0; a < 3; ++a) {
          Eigen::Vector3d step = Eigen::Vector3d::Zero();
          step[a] = 0.01;
          numeric[a] =
              (scene.clearance(points[k] + step) - scene.clearance(points[k] - step)) / 0.02;
        }
        ++gradients_checked;
        if (gradient.normalized().dot(numeric.normalized()) > 0.7) ++gradients_agree;
      }
    }
  }
  const double median_m = percentileOf(errors_m, 0.5), p95_m = percentileOf(errors_m, 0.95);
  std::printf(
      "[planning] 100000 points in %.0f ms: %zu free, %zu occupied, %zu unknown; |ESDF - "
      "clearance| of "
      "free points median %.1f mm, p95 %.1f mm (cell %.0f mm); gradients agreeing %zu / %zu; free "
      "more than "
      "2 cells inside a solid: %zu\n",
      call_ms, free, occupied, unknown, 1e3 * median_m, 1e3 * p95_m, 1e3 * cell_m, gradients_agree,
      gradients_checked, free_inside_solid);
  // The samples reach 0.3 m beyond the walls (unknown there): a fifth of the box is the room's
  // free interior the orbit saw.
  EXPECT_GT(free, points.size() / 7) << "the orbit sees most of the room empty";
  EXPECT_GT(occupied, 100u);
  EXPECT_GT(unknown, 100u) << "behind the walls stays unknown";
  // Noisy disparities of the far walls put a few rays' ends behind them (measured: 0.2 % of the
  // samples, all within 0.3 m behind a wall that stays occupied).
  EXPECT_LT(free_inside_solid, points.size() / 200) << "space inside solids read as seen empty";
  ASSERT_GT(errors_m.size(), 1000u);
  EXPECT_LT(median_m, 0.5 * cell_m);
  EXPECT_LT(p95_m, 1.5 * cell_m);
  EXPECT_GT(gradients_checked, 1000u);
  EXPECT_GT(gradients_agree, 0.9 * gradients_checked);

  // The box service answers the same field: each sample equals get_distance at its point.
  GetEsdfBox grid;
  grid.request.min.x = -0.5;
  grid.request.min.y = -0.5;
  grid.request.min.z = 0.5;
  grid.request.max.x = 0.5;
  grid.request.max.y = 0.5;
  grid.request.max.z = 1.0;
  ASSERT_TRUE(ros::service::call("/stereo_fusion/get_esdf_box", grid));
  ASSERT_TRUE(grid.response.success) << grid.response.message;
  EXPECT_DOUBLE_EQ(grid.response.resolution_m, cell_m);
  const size_t n =
      static_cast<size_t>(grid.response.size_x) * grid.response.size_y * grid.response.size_z;
  ASSERT_EQ(grid.response.distances.size(), n);
  EXPECT_EQ(grid.response.size_x, static_cast<uint32_t>(std::floor(1.0 / cell_m + 1e-9)) + 1);
  GetDistance same;
  for (uint32_t z = 0; z < grid.response.size_z; ++z)
    for (uint32_t y = 0; y < grid.response.size_y; ++y)
      for (uint32_t x = 0; x < grid.response.size_x; ++x) {
        geometry_msgs::Point q;
        q.x = grid.response.origin.x + x * cell_m;
        q.y = grid.response.origin.y + y * cell_m;
        q.z = grid.response.origin.z + z * cell_m;
        same.request.points.push_back(q);
      }
  ASSERT_TRUE(ros::service::call("/stereo_fusion/get_distance", same));
  for (size_t k = 0; k < n; ++k) {
    EXPECT_EQ(grid.response.states[k], same.response.states[k]);
    if (!std::isnan(same.response.distances[k]))
      EXPECT_EQ(grid.response.distances[k], same.response.distances[k]);
  }

  // Invalid requests: success false, a message, and the map as it was.
  GetDistance nan_point;
  nan_point.request.points.resize(3);
  nan_point.request.points[1].y = NAN;
  ASSERT_TRUE(ros::service::call("/stereo_fusion/get_distance", nan_point));
  EXPECT_FALSE(nan_point.response.success);
  EXPECT_NE(nan_point.response.message.find("point 1 is not finite"), std::string::npos)
      << nan_point.response.message;
  GetEsdfBox inverted = grid;
  inverted.request.max.x = -1.0;
  ASSERT_TRUE(ros::service::call("/stereo_fusion/get_esdf_box", inverted));
  EXPECT_FALSE(inverted.response.success);
  GetEsdfBox huge = grid;
  huge.request.resolution_m = 1e-4;  // 10 000 × 10 000 × 5 000 samples
  ASSERT_TRUE(ros::service::call("/stereo_fusion/get_esdf_box", huge));
  EXPECT_FALSE(huge.response.success);
  EXPECT_NE(huge.response.message.find("planning_max_box_cells"), std::string::npos)
      << huge.response.message;
  GetEsdfBox negative = grid;
  negative.request.resolution_m = -0.1;
  ASSERT_TRUE(ros::service::call("/stereo_fusion/get_esdf_box", negative));
  EXPECT_FALSE(negative.response.success);
  GetDistance again;
  again.request.points = same.request.points;
  ASSERT_TRUE(ros::service::call("/stereo_fusion/get_distance", again));
  EXPECT_EQ(again.response.states, same.response.states);
  GetFullMesh after;
  ASSERT_TRUE(ros::service::call("/stereo_fusion/get_full_mesh", after));
  EXPECT_EQ(after.response.mesh.blocks.size(), full.response.mesh.blocks.size());

  // After ~clear_box the box reads unknown (its cells were known before).
  GetDistance cleared;
  for (const geometry_msgs::Point& q : same.request.points) {
    // Cells wholly inside the box: one that straddles its face keeps the voxels beyond it.
    geometry_msgs::Point c;
    c.x = (std::floor(q.x / cell_m) + 0.5) * cell_m;
    c.y = (std::floor(q.y / cell_m) + 0.5) * cell_m;
    c.z = (std::floor(q.z / cell_m) + 0.5) * cell_m;
    const double h = 0.5 * cell_m;
    if (c.x - h >= grid.request.min.x && c.x + h <= grid.request.max.x &&
        c.y - h >= grid.request.min.y && c.y + h <= grid.request.max.y &&
        c.z - h >= grid.request.min.z && c.z + h <= grid.request.max.z)
      cleared.request.points.push_back(c);
  }
  ASSERT_GT(cleared.request.points.size(), 10u);
  GetDistance before_clear = cleared;
  ASSERT_TRUE(ros::service::call("/stereo_fusion/get_distance", before_clear));
  size_t known_before = 0;
  for (uint8_t state : before_clear.response.states)
    known_before += state != GetDistance::Response::UNKNOWN;
  EXPECT_GT(known_before, cleared.request.points.size() / 2);
  ClearBox clear;
  clear.request.min = grid.request.min;
  clear.request.max = grid.request.max;
  ASSERT_TRUE(ros::service::call("/stereo_fusion/clear_box", clear));
  ASSERT_TRUE(clear.response.success) << clear.response.message;
  ASSERT_TRUE(ros::service::call("/stereo_fusion/get_distance", cleared));
  size_t still_known = 0;
  for (uint8_t state : cleared.response.states)
    still_known += state != GetDistance::Response::UNKNOWN;
  EXPECT_EQ(still_known, 0u) << "of " << cleared.request.points.size()
                             << " cells inside the cleared box";
}

int main(int argc, char** argv) {
  return test::runRosTests(argc, argv, "stereo_fusion_replay_test");
}
