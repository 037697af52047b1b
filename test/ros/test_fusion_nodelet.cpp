// Integration test with a real master, the real nodelet and real messages (rostest).
#include <std_srvs/Empty.h>
#include <stereo_fusion/ClearBox.h>
#include <stereo_fusion/ClearSphere.h>
#include <stereo_fusion/GetFullMesh.h>
#include <stereo_fusion/LoadMap.h>
#include <stereo_fusion/MeshUpdate.h>
#include <stereo_fusion/SaveMap.h>
#include <stereo_fusion/SaveMesh.h>
#include <nav_msgs/Path.h>
#include <visualization_msgs/MarkerArray.h>
#include <tf2_ros/transform_broadcaster.h>

#include <unistd.h>

#include <fstream>
#include <opencv2/core.hpp>
#include <filesystem>
#include <map>
#include <mutex>

#include "../unit/TestSupport.h"
#include "NodeletUnload.h"
#include "RosTestSupport.h"
#include "readers/ObjReader.h"
#include "readers/PlyReader.h"
#include "stereo_fusion/io/MapFile.h"
#include "stereo_fusion/ros/FusionNodelet.h"
#include "stereo_fusion/ros/MeshMessages.h"
#include "stereo_fusion/ros/MessageConversions.h"
#include "stereo_fusion/ros/RosParameters.h"

using namespace stereo_fusion;

namespace {

StereoCamera qvga() { return *StereoCamera::create(320, 240, 262.5, 262.5, 159.5, 119.5, 0.1); }

sim::AnalyticScene scene() {
  sim::AnalyticScene s;
  s.add(sim::makePlane({0, 0.3, 0}, {0, -1, 0}), {180, 160, 120});
  s.add(sim::makeSphere({0.05, 0.1, 1.2}, 0.2), {200, 60, 60});
  return s;
}

/// Publishes frames like a stereo pipeline + SLAM would and watches what the nodelet says.
class NodeletFixture : public testing::Test {
 protected:
  void SetUp() override {
    ros::NodeHandle nh;
    disparity_pub_ = nh.advertise<stereo_msgs::DisparityImage>("/stereo/disparity", 10);
    image_pub_ = nh.advertise<sensor_msgs::Image>("/stereo/left/image_rect_color", 10);
    info_pub_ = nh.advertise<sensor_msgs::CameraInfo>("/stereo/left/camera_info", 10);
    update_sub_ = nh.subscribe("/stereo_fusion/mesh_update", 100, &NodeletFixture::onUpdate, this);
    ASSERT_TRUE(waitFor(
        [&] {
          return disparity_pub_.getNumSubscribers() > 0 && image_pub_.getNumSubscribers() > 0 &&
                 info_pub_.getNumSubscribers() > 0 && update_sub_.getNumPublishers() > 0;
        },
        30.0))
        << "the nodelet did not connect";
    ASSERT_TRUE(test::waitForTfSubscriber(30.0)) << "the nodelet's tf listener did not connect";
    // Each test has its own watcher: without a first report its counters read -1, and a test's
    // baseline ("fused before") would be 0 while the nodelet has fused frames of earlier tests.
    ASSERT_TRUE(diagnostics_.waitForNextReport(30.0)) << "no diagnostics from the nodelet";
  }

  // The subscriber is declared before the members its callback uses, so it would be destroyed
  // after them while the spinner threads may still run onUpdate (the nodelet keeps publishing
  // after a test ends): a use-after-free that crashed the binary now and then. shutdown()
  // waits for a callback in progress and drops the queued ones.
  void TearDown() override { update_sub_.shutdown(); }

  template <typename F>
  bool waitFor(F&& done, double timeout_s) {
    return test::waitFor(std::forward<F>(done), timeout_s);
  }

  /// Publishes `frame` stamped `stamp` (now when zero), with its tf first when `with_tf`.
  void publish(
      const StereoFrame& frame, const std::string& frame_id, bool with_tf,
      const std::function<void(stereo_msgs::DisparityImage*, sensor_msgs::Image*)>& corrupt = {},
      ros::Time stamp = ros::Time()) {
    test::FrameMessages m = test::frameMessages(frame, with_tf ? &tf_ : nullptr, frame_id, stamp);
    if (corrupt) corrupt(&m.disparity, &m.image);
    ros::WallDuration(0.05).sleep();  // tf first, as a SLAM stack running ahead would
    disparity_pub_.publish(m.disparity);
    image_pub_.publish(m.image);
    info_pub_.publish(m.info);
  }

  long diag(const std::string& key) { return diagnostics_.value(key); }

  void onUpdate(const MeshUpdate::ConstPtr& u) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (last_sequence_ && u->sequence != last_sequence_ + 1) ++sequence_gaps_;
    last_sequence_ = u->sequence;
    ++updates_;
    applied_ok_ &= applyMeshUpdate(*u, &streamed_, &streamed_textures_);
  }

  ros::Publisher disparity_pub_, image_pub_, info_pub_;
  ros::Subscriber update_sub_;
  test::DiagnosticsWatcher diagnostics_;
  tf2_ros::TransformBroadcaster tf_;
  std::mutex mutex_;
  std::unordered_map<BlockKey, SubMesh, BlockKeyHash> streamed_;
  std::unordered_map<BlockKey, TexturePatch, BlockKeyHash> streamed_textures_;
  uint64_t last_sequence_ = 0;
  int sequence_gaps_ = 0, updates_ = 0;
  bool applied_ok_ = true;
};

}  // namespace

TEST_F(NodeletFixture, StreamedMeshEqualsFullMeshAndSavedPly) {
  const sim::AnalyticScene s = scene();
  for (int f = 0; f < 4; ++f) {
    const auto pose =
        sim::lookAt({-0.15 + 0.1 * f, -0.2, 0.0}, {0.05, 0.1, 1.2}, -Eigen::Vector3d::UnitY());
    publish(test::renderFrame(s, qvga(), pose), "left_optical", true);
  }
  ASSERT_TRUE(waitFor([&] { return diag("frames fused") >= 4; }, 60.0))
      << "fused " << diag("frames fused");
  ros::WallDuration(1.0).sleep();  // let the last update arrive
  EXPECT_EQ(diag("dropped: tf timeout"), 0);
  EXPECT_EQ(diag("dropped: bad input"), 0);
  // Recorded (a fused frame with textures takes over a millisecond on the worker), and the
  // worker's time per frame holds the frame's publishing, so it is never the smaller.
  EXPECT_GE(diag("worker per frame p99 (ms)"), 1);
  EXPECT_GE(diag("worker per frame p99 (ms)"), diag("publishing per frame p99 (ms)"));

  GetFullMesh full;
  ASSERT_TRUE(ros::service::call("/stereo_fusion/get_full_mesh", full));
  EXPECT_TRUE(full.response.mesh.full);
  std::unordered_map<BlockKey, SubMesh, BlockKeyHash> reference;
  std::unordered_map<BlockKey, TexturePatch, BlockKeyHash> reference_textures;
  ASSERT_TRUE(applyMeshUpdate(full.response.mesh, &reference, &reference_textures));
  ASSERT_GT(reference.size(), 10u);
  // fusion_nodelet.test turns texture patches on: textured blocks carry a PNG and one UV per
  // vertex.
  ASSERT_GT(reference_textures.size(), 3u);
  for (const auto& [key, patch] : reference_textures) {
    ASSERT_EQ(patch.uvs.size(), reference.at(key).positions.size()) << key;
    EXPECT_LE(patch.image_rgb.cols, 64);  // texture_max_patch_px default
    EXPECT_LE(patch.image_rgb.rows, 64);
    EXPECT_GT(patch.image_rgb.total(), 0u);
  }
  // UVs without a texture are refused.
  MeshUpdate no_texture = full.response.mesh;
  for (auto& b : no_texture.blocks)
    if (!b.uvs.empty()) b.texture.data.clear();
  std::unordered_map<BlockKey, SubMesh, BlockKeyHash> unchanged = reference;
  EXPECT_FALSE(applyMeshUpdate(no_texture, &unchanged));
  // A malformed update (a triangle index past the last vertex) is refused and changes nothing.
  MeshUpdate broken = full.response.mesh;
  broken.blocks.back().triangles.back() = 1u << 30;
  std::unordered_map<BlockKey, SubMesh, BlockKeyHash> untouched = reference;
  EXPECT_FALSE(applyMeshUpdate(broken, &untouched));
  EXPECT_EQ(untouched.size(), reference.size());
  std::lock_guard<std::mutex> lock(mutex_);
  EXPECT_TRUE(applied_ok_);
  EXPECT_EQ(sequence_gaps_, 0);
  EXPECT_GE(updates_, 4);
  EXPECT_EQ(full.response.mesh.sequence, last_sequence_);
  test::expectSameSubmeshes(streamed_, reference, test::kWithColors);
  // The streamed textures equal the full mesh's: same blocks, same texels, same UVs.
  ASSERT_EQ(streamed_textures_.size(), reference_textures.size());
  for (const auto& [key, ref] : reference_textures) {
    auto it = streamed_textures_.find(key);
    ASSERT_NE(it, streamed_textures_.end()) << key;
    EXPECT_EQ(it->second.uvs, ref.uvs) << key;
    ASSERT_EQ(it->second.image_rgb.size(), ref.image_rgb.size()) << key;
    EXPECT_EQ(cv::norm(it->second.image_rgb, ref.image_rgb, cv::NORM_INF), 0.0) << key;
  }
  const TriangleMesh welded = weldSubmeshes(reference);
  SaveMesh save;
  save.request.path = testing::TempDir() + "stereo_fusion_rostest_mesh.ply";
  ASSERT_TRUE(ros::service::call("/stereo_fusion/save_mesh", save));
  ASSERT_TRUE(save.response.success) << save.response.message;
  TriangleMesh saved;
  std::string error;
  ASSERT_TRUE(readPly(save.request.path, &saved, &error)) << error;
  EXPECT_EQ(saved.positions.size(), welded.positions.size());
  EXPECT_EQ(saved.triangles.size(), welded.triangles.size());

  // save_mesh with a .obj path writes the textured mesh: OBJ + MTL + atlas PNG.
  save.request.path =
      testing::TempDir() + "stereo_fusion_rostest_mesh_" + std::to_string(getpid()) + ".obj";
  ASSERT_TRUE(ros::service::call("/stereo_fusion/save_mesh", save));
  ASSERT_TRUE(save.response.success) << save.response.message;
  ObjMesh obj;
  ASSERT_TRUE(readObj(save.request.path, &obj, &error)) << error;
  size_t triangles = 0;
  for (const auto& [key, sub] : reference) triangles += sub.triangles.size();
  EXPECT_EQ(obj.faces.size(), triangles);
  size_t textured_faces = 0;
  for (const ObjFace& f : obj.faces) textured_faces += f.vt[0] >= 0;
  EXPECT_GT(textured_faces, 0u);
  bool atlas_found = false;
  for (const ObjMaterial& m : obj.materials)
    atlas_found |= !m.diffuse_map.empty() && std::ifstream(m.diffuse_map).good();
  EXPECT_TRUE(atlas_found);
}

// ~mesh_markers go out at markers_publish_rate_hz (2 Hz) while the mesh follows every frame
// here (texture patches): each carries the changes merged since the last, so rviz ends with
// every triangle of the mesh.
TEST_F(NodeletFixture, MarkersAtTheirOwnRateEndWithTheWholeMesh) {
  std::mutex markers_mutex;
  std::map<int, size_t> triangles_by_id;  // what rviz would draw
  size_t arrays = 0;
  ros::NodeHandle nh;
  ros::Subscriber markers_sub = nh.subscribe<visualization_msgs::MarkerArray>(
      "/stereo_fusion/mesh_markers", 100, [&](const visualization_msgs::MarkerArray::ConstPtr& a) {
        std::lock_guard<std::mutex> lock(markers_mutex);
        ++arrays;
        for (const visualization_msgs::Marker& m : a->markers) {
          if (m.action == visualization_msgs::Marker::DELETEALL) triangles_by_id.clear();
          if (m.action == visualization_msgs::Marker::DELETE) triangles_by_id.erase(m.id);
          if (m.action == visualization_msgs::Marker::ADD)
            triangles_by_id[m.id] = m.points.size() / 3;
        }
      });
  ASSERT_TRUE(waitFor([&] { return markers_sub.getNumPublishers() > 0; }, 30.0));
  // An empty map: the fixture's ~mesh_update copy (subscribed for this test) is then whole.
  std_srvs::Empty reset;
  ASSERT_TRUE(ros::service::call("/stereo_fusion/reset", reset));
  ASSERT_TRUE(diagnostics_.waitForNextReport(30.0));  // baselines no older than the reset
  const long fused_before = std::max(0L, diag("frames fused"));
  const ros::WallTime start = ros::WallTime::now();
  const sim::AnalyticScene s = scene();
  for (int f = 0; f < 12; ++f) {  // a mesh pass each (texture patches), ~50 ms apart
    const auto pose =
        sim::lookAt({-0.2 + 0.04 * f, -0.15, 0.0}, {0.05, 0.1, 1.2}, -Eigen::Vector3d::UnitY());
    publish(test::renderFrame(s, qvga(), pose), "left_optical", true);
  }
  ASSERT_TRUE(waitFor([&] { return diag("frames fused") >= fused_before + 12; }, 60.0));
  auto drawn = [&] {
    std::lock_guard<std::mutex> lock(markers_mutex);
    size_t n = 0;
    for (const auto& [id, triangles] : triangles_by_id) n += triangles;
    return n;
  };
  auto streamed = [&] {  // the ~mesh_update subscriber's mesh
    std::lock_guard<std::mutex> lock(mutex_);
    size_t n = 0;
    for (const auto& [key, sub] : streamed_) n += sub.triangles.size();
    return n;
  };
  // Unforced: the backlog goes out by the rate (and the idle worker's flush) alone.
  EXPECT_TRUE(waitFor([&] { return streamed() > 0 && drawn() == streamed(); }, 10.0))
      << drawn() << " triangles drawn, ~mesh_update holds " << streamed();
  const double elapsed_s = (ros::WallTime::now() - start).toSec();
  {
    std::lock_guard<std::mutex> lock(markers_mutex);
    // The whole mesh on connecting, the reset's DELETEALL, then at most one array per 0.5 s
    // (the first at once): not one per mesh pass.
    EXPECT_LE(arrays, 3u + static_cast<size_t>(2.0 * elapsed_s)) << "in " << elapsed_s << " s";
  }
  GetFullMesh full;
  ASSERT_TRUE(ros::service::call("/stereo_fusion/get_full_mesh", full));
  size_t mesh_triangles = 0;
  for (const MeshBlock& b : full.response.mesh.blocks) mesh_triangles += b.triangles.size() / 3;
  ASSERT_GT(mesh_triangles, 0u);
  EXPECT_TRUE(waitFor([&] { return drawn() == mesh_triangles; }, 10.0))
      << drawn() << " triangles drawn, the mesh has " << mesh_triangles;
  markers_sub.shutdown();
}

TEST_F(NodeletFixture, MissingTfAndBadInputAreDroppedCountedAndSurvived) {
  const sim::AnalyticScene s = scene();
  const StereoFrame frame = test::renderFrame(s, qvga(), Eigen::Isometry3d::Identity());
  ASSERT_TRUE(diagnostics_.waitForNextReport(10.0));
  const long fused_before = std::max(0L, diag("frames fused"));
  GetFullMesh before;
  ASSERT_TRUE(ros::service::call("/stereo_fusion/get_full_mesh", before));
  publish(frame, "camera_without_tf", false);
  publish(frame, "left_optical", true,
          [](stereo_msgs::DisparityImage* d, sensor_msgs::Image*) { d->T = 0.0f; });
  publish(frame, "left_optical", true,
          [](stereo_msgs::DisparityImage*, sensor_msgs::Image* i) { i->encoding = "yuv422"; });
  publish(frame, "left_optical", true, [](stereo_msgs::DisparityImage* d, sensor_msgs::Image*) {
    d->image.data.resize(d->image.data.size() / 2);  // truncated payload
  });
  publish(frame, "left_optical", true, [](stereo_msgs::DisparityImage*, sensor_msgs::Image* i) {
    i->width /= 2;  // image and disparity sizes differ
    i->step /= 2;
    i->data.resize(i->step * i->height);
  });
  publish(frame, "left_optical", true, [](stereo_msgs::DisparityImage* d, sensor_msgs::Image*) {
    float* px = reinterpret_cast<float*>(d->image.data.data());  // a broken matcher: random values
    cv::RNG rng(11);
    for (size_t k = 0; k < d->image.data.size() / 4; ++k) px[k] = rng.uniform(1.0f, 64.0f);
  });
  ASSERT_TRUE(waitFor(
      [&] {
        return diag("dropped: tf timeout") >= 1 && diag("dropped: bad input") >= 4 &&
               diag("dropped: incoherent disparity") >= 1;
      },
      30.0))
      << "tf " << diag("dropped: tf timeout") << ", bad " << diag("dropped: bad input")
      << ", incoherent " << diag("dropped: incoherent disparity");
  // A disparity image full of NaN is valid input with nothing in it: fused, map unchanged.
  const long fused_mid = diag("frames fused");
  publish(frame, "left_optical", true, [](stereo_msgs::DisparityImage* d, sensor_msgs::Image*) {
    float* px = reinterpret_cast<float*>(d->image.data.data());
    for (size_t k = 0; k < d->image.data.size() / 4; ++k) px[k] = NAN;
  });
  ASSERT_TRUE(waitFor([&] { return diag("frames fused") >= fused_mid + 1; }, 30.0));
  GetFullMesh after;
  ASSERT_TRUE(ros::service::call("/stereo_fusion/get_full_mesh", after));
  ASSERT_EQ(after.response.mesh.blocks.size(), before.response.mesh.blocks.size())
      << "bad input changed the map";
  for (size_t b = 0; b < before.response.mesh.blocks.size(); ++b) {
    EXPECT_EQ(after.response.mesh.blocks[b].key, before.response.mesh.blocks[b].key);
    EXPECT_EQ(after.response.mesh.blocks[b].vertices, before.response.mesh.blocks[b].vertices);
  }
  // The node keeps running and fusing.
  publish(frame, "left_optical", true);
  EXPECT_TRUE(waitFor([&] { return diag("frames fused") >= fused_before + 2; }, 30.0));
  EXPECT_EQ(diag("dropped: tf timeout"), 1);
  EXPECT_EQ(diag("dropped: bad input"), 4);
  EXPECT_EQ(diag("dropped: incoherent disparity"), 1);
  EXPECT_EQ(diag("dropped: superseded by reset/load"), 0);
  std_srvs::Empty reset;
  EXPECT_TRUE(ros::service::call("/stereo_fusion/reset", reset));
  GetFullMesh full;
  ASSERT_TRUE(ros::service::call("/stereo_fusion/get_full_mesh", full));
  EXPECT_TRUE(full.response.mesh.blocks.empty());
}

namespace {
/// Equal submesh keys, vertices and triangles in two full meshes.
void expectSameMesh(const MeshUpdate& a, const MeshUpdate& b) {
  ASSERT_EQ(a.blocks.size(), b.blocks.size());
  for (size_t k = 0; k < a.blocks.size(); ++k) {
    EXPECT_EQ(a.blocks[k].key, b.blocks[k].key);
    EXPECT_EQ(a.blocks[k].vertices, b.blocks[k].vertices);
    EXPECT_EQ(a.blocks[k].triangles, b.blocks[k].triangles);
  }
}
}  // namespace

TEST_F(NodeletFixture, OutOfOrderDuplicateJumpingAndFutureTfFramesAreDroppedByReason) {
  const sim::AnalyticScene s = scene();
  const auto pose = sim::lookAt({0.05, -0.2, 0.0}, {0.05, 0.1, 1.2}, -Eigen::Vector3d::UnitY());
  const StereoFrame frame = test::renderFrame(s, qvga(), pose);
  const long fused_before = std::max(0L, diag("frames fused"));
  const ros::Time t0 = ros::Time::now();
  publish(frame, "left_optical", true, {}, t0);
  ASSERT_TRUE(waitFor([&] { return diag("frames fused") >= fused_before + 1; }, 30.0));
  GetFullMesh before;
  ASSERT_TRUE(ros::service::call("/stereo_fusion/get_full_mesh", before));

  publish(frame, "left_optical", true, {}, t0);                       // the same stamp again
  publish(frame, "left_optical", true, {}, t0 - ros::Duration(0.5));  // older than the last fused
  StereoFrame jumped = frame;
  jumped.T_world_camera.translation().x() += 5000.0;  // 5 km away
  publish(jumped, "left_optical", true, {}, t0 + ros::Duration(0.1));
  // A broken driver clock (its own frame id: a tf stamp 1000 s ahead would prune left_optical's
  // tf history, which tf2 keeps for 10 s behind its newest stamp).
  publish(frame, "clock_skew_optical", true, {}, ros::Time::now() + ros::Duration(1000.0));
  ASSERT_TRUE(waitFor(
      [&] {
        return diag("dropped: duplicate frame") >= 1 && diag("dropped: timestamp backwards") >= 1 &&
               diag("dropped: pose jump") >= 1 && diag("dropped: bad timestamp") >= 1;
      },
      30.0))
      << "duplicate " << diag("dropped: duplicate frame") << ", backwards "
      << diag("dropped: timestamp backwards") << ", jump " << diag("dropped: pose jump")
      << ", bad stamp " << diag("dropped: bad timestamp");
  // tf only in the future of the frame: no transform at the frame's stamp.
  const long tf_before = std::max(0L, diag("dropped: tf timeout"));
  std_msgs::Header later;
  later.stamp = t0 + ros::Duration(30.0);
  later.frame_id = "future_only_optical";
  tf_.sendTransform(toTransform(frame.T_world_camera, "map", later));
  publish(frame, "future_only_optical", false, {}, t0 + ros::Duration(0.2));
  ASSERT_TRUE(waitFor([&] { return diag("dropped: tf timeout") >= tf_before + 1; }, 30.0));

  GetFullMesh after;
  ASSERT_TRUE(ros::service::call("/stereo_fusion/get_full_mesh", after));
  expectSameMesh(before.response.mesh, after.response.mesh);
  EXPECT_EQ(diag("dropped: duplicate frame"), 1);
  EXPECT_EQ(diag("dropped: timestamp backwards"), 1);
  EXPECT_EQ(diag("dropped: pose jump"), 1);
  EXPECT_EQ(diag("dropped: bad timestamp"), 1);
  // A disparity alone stamped 0 (its image and camera_info carry a real stamp) is a bad stamp,
  // not a frame waiting for synchronisation.
  const long unsynchronised =
      diag("dropped: not synchronised (no matching image / camera_info yet)");
  publish(
      frame, "left_optical", true,
      [](stereo_msgs::DisparityImage* d, sensor_msgs::Image*) { d->header.stamp = ros::Time(0); },
      t0 + ros::Duration(0.3));
  ASSERT_TRUE(waitFor([&] { return diag("dropped: bad timestamp") >= 2; }, 30.0));
  // A disparity alone re-using the newest fused frame's stamp is a duplicate frame, not unmatched.
  publish(
      frame, "left_optical", true,
      [&](stereo_msgs::DisparityImage* d, sensor_msgs::Image*) { d->header.stamp = t0; },
      t0 + ros::Duration(0.4));
  ASSERT_TRUE(waitFor([&] { return diag("dropped: duplicate frame") >= 2; }, 30.0));
  EXPECT_EQ(diag("dropped: not synchronised (no matching image / camera_info yet)"),
            unsynchronised);

  // Neither the jumped frame nor the future stamp became a reference: the next good frame at the
  // original place is fused (a glitch costs one frame).
  const long fused_mid = diag("frames fused");
  publish(frame, "left_optical", true);
  ASSERT_TRUE(waitFor([&] { return diag("frames fused") >= fused_mid + 1; }, 30.0));
  // tf arriving late (after the images, within tf_timeout_s) costs nothing.
  const ros::Time t1 = ros::Time::now();
  std_msgs::Header late;
  late.stamp = t1;
  late.frame_id = "late_optical";
  publish(frame, "late_optical", false, {}, t1);
  ros::WallDuration(0.1).sleep();  // late, yet well inside tf_timeout_s = 0.5 s
  tf_.sendTransform(toTransform(frame.T_world_camera, "map", late));
  late.stamp =
      t1 + ros::Duration(0.5);  // a later transform, so t1 is interpolated, not extrapolated
  tf_.sendTransform(toTransform(frame.T_world_camera, "map", late));
  EXPECT_TRUE(waitFor([&] { return diag("frames fused") >= fused_mid + 2; }, 30.0));
  EXPECT_EQ(diag("dropped: pose jump"), 1);
  EXPECT_EQ(diag("dropped: tf timeout"), tf_before + 1)
      << "a late tf within tf_timeout_s must not drop the frame";
  EXPECT_EQ(diag("blocks evicted"), 0);
}

TEST_F(NodeletFixture, APathWhosePosesCarryNoRotationIsRefusedWholeAndTheMapStays) {
  const sim::AnalyticScene s = scene();
  const long fused_before = std::max(0L, diag("frames fused"));
  for (int i = 0; i < 2; ++i) {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.translation().x() = 0.01 * i;
    publish(test::renderFrame(s, qvga(), T), "left_optical", true);
  }
  ASSERT_TRUE(waitFor([&] { return diag("frames fused") >= fused_before + 2; }, 30.0));
  GetFullMesh before;
  ASSERT_TRUE(ros::service::call("/stereo_fusion/get_full_mesh", before));
  ros::NodeHandle nh;
  ros::Publisher trajectory_pub = nh.advertise<nav_msgs::Path>("/trajectory", 5);
  ASSERT_TRUE(waitFor([&] { return trajectory_pub.getNumSubscribers() > 0; }, 30.0));
  const long bad_before = std::max(0L, diag("trajectories rejected: bad pose"));
  const long applied_before = std::max(0L, diag("corrections applied"));
  auto path = [&](double qx, double qy, double qz, double qw) {
    nav_msgs::Path p;
    p.header.frame_id = "map";
    p.header.stamp = ros::Time::now();
    geometry_msgs::PoseStamped pose;
    pose.header.frame_id = "map";
    pose.header.stamp = before.response.mesh.header.stamp;
    pose.pose.orientation.w = 1.0;
    p.poses.push_back(pose);  // a good first pose: the second one names the path's fault
    pose.pose.position.x = 0.3;
    pose.pose.orientation.x = qx;
    pose.pose.orientation.y = qy;
    pose.pose.orientation.z = qz;
    pose.pose.orientation.w = qw;
    p.poses.push_back(pose);
    return p;
  };
  trajectory_pub.publish(path(0, 0, 0, 0));  // was taken as the identity
  trajectory_pub.publish(path(0, 0, 0, 2));  // |q| = 2: was taken as a scaled matrix
  trajectory_pub.publish(path(0, 0, NAN, 1));
  ASSERT_TRUE(
      waitFor([&] { return diag("trajectories rejected: bad pose") >= bad_before + 3; }, 30.0))
      << diag("trajectories rejected: bad pose");
  ros::WallDuration(0.5).sleep();
  EXPECT_EQ(diag("corrections applied"), applied_before);
  GetFullMesh after;
  ASSERT_TRUE(ros::service::call("/stereo_fusion/get_full_mesh", after));
  ASSERT_EQ(after.response.mesh.blocks.size(), before.response.mesh.blocks.size())
      << "a bad path changed the map";
  for (size_t b = 0; b < before.response.mesh.blocks.size(); ++b)
    EXPECT_EQ(after.response.mesh.blocks[b].vertices, before.response.mesh.blocks[b].vertices);
}

TEST_F(NodeletFixture, ASecondDisparityOfAStampArrivingBeforeItsFrameIsMatchedIsHeldBack) {
  // message_filters' ExactTime policy lets a second disparity of a stamp replace the first while
  // the image and camera_info are still on their way: a corrupt copy would be fused instead of
  // the good frame. The first of a stamp must win and the second be counted.
  std_srvs::Empty empty;
  ASSERT_TRUE(ros::service::call("/stereo_fusion/reset", empty));
  ASSERT_TRUE(diagnostics_.waitForNextReport(30.0));  // baselines no older than the reset
  const sim::AnalyticScene s = scene();
  const auto pose = sim::lookAt({0.0, -0.2, 0.0}, {0.05, 0.1, 1.2}, -Eigen::Vector3d::UnitY());
  test::FrameMessages good = test::frameMessages(test::renderFrame(s, qvga(), pose), &tf_);
  stereo_msgs::DisparityImage corrupt = good.disparity;  // every surface 1.7 times as far
  float* d = reinterpret_cast<float*>(corrupt.image.data.data());
  for (size_t k = 0; k < corrupt.image.data.size() / sizeof(float); ++k) d[k] *= 0.6f;
  const long disparities_before = std::max(0L, diag("disparities received"));
  const long fused_before = std::max(0L, diag("frames fused"));
  const long held_before = std::max(0L, diag("dropped: duplicate stamp before synchronisation"));
  ros::WallDuration(0.05).sleep();  // tf first
  disparity_pub_.publish(good.disparity);
  disparity_pub_.publish(corrupt);
  // Both disparities are in before the rest of the set, so the synchroniser holds an incomplete
  // set.
  ASSERT_TRUE(
      waitFor([&] { return diag("disparities received") >= disparities_before + 2; }, 30.0));
  image_pub_.publish(good.image);
  info_pub_.publish(good.info);
  ASSERT_TRUE(waitFor([&] { return diag("frames fused") >= fused_before + 1; }, 30.0))
      << diag("frames fused");
  EXPECT_EQ(diag("dropped: duplicate stamp before synchronisation"), held_before + 1);

  GetFullMesh full;
  ASSERT_TRUE(ros::service::call("/stereo_fusion/get_full_mesh", full));
  std::unordered_map<BlockKey, SubMesh, BlockKeyHash> mesh;
  ASSERT_TRUE(applyMeshUpdate(full.response.mesh, &mesh));
  ASSERT_GT(mesh.size(), 10u);
  size_t vertices = 0, off_surface = 0;
  for (const auto& [key, sub] : mesh)
    for (const Eigen::Vector3f& p : sub.positions) {
      ++vertices;
      off_surface += s.distanceToSurface(p.cast<double>()) > 0.03;  // a few at the image border
    }
  EXPECT_LT(off_surface, vertices / 100)
      << "of " << vertices << " vertices: the corrupt copy was fused";
}

TEST_F(NodeletFixture, SaveMapAndLoadMapRoundTripAndABadFileChangesNothing) {
  const sim::AnalyticScene s = scene();
  const long fused_before = std::max(0L, diag("frames fused"));
  for (int f = 0; f < 3; ++f) {
    const auto pose =
        sim::lookAt({-0.1 + 0.1 * f, -0.25, 0.0}, {0.05, 0.1, 1.2}, -Eigen::Vector3d::UnitY());
    publish(test::renderFrame(s, qvga(), pose), "left_optical", true);
  }
  // All three fused before the reference mesh is taken, or save_map would see a later map.
  ASSERT_TRUE(waitFor([&] { return diag("frames fused") >= fused_before + 3; }, 60.0))
      << diag("frames fused");
  GetFullMesh original;
  ASSERT_TRUE(ros::service::call("/stereo_fusion/get_full_mesh", original));
  ASSERT_GT(original.response.mesh.blocks.size(), 10u);

  const std::string path =
      testing::TempDir() + "stereo_fusion_rostest_" + std::to_string(::getpid()) + ".sfmap";
  SaveMap save;
  save.request.path = path;
  ASSERT_TRUE(ros::service::call("/stereo_fusion/save_map", save));
  ASSERT_TRUE(save.response.success) << save.response.message;
  EXPECT_GT(save.response.blocks, 10u);
  {  // A whole map file of that many blocks, as this build reads it.
    MapperConfig config;
    BlockOctree saved(config.blockSizeM());
    MapFileInfo info;
    std::string error;
    ASSERT_TRUE(readMapFile(path, config, &saved, &info, &error)) << error;
    EXPECT_EQ(info.version, kMapFileVersion);
    EXPECT_EQ(saved.blockCount(), save.response.blocks);
  }

  // A truncated copy is refused and the map stays as it was.
  const std::string truncated = path + ".cut";
  std::filesystem::copy_file(path, truncated, std::filesystem::copy_options::overwrite_existing);
  std::filesystem::resize_file(truncated, std::filesystem::file_size(path) / 2);
  LoadMap bad;
  bad.request.path = truncated;
  ASSERT_TRUE(ros::service::call("/stereo_fusion/load_map", bad));
  EXPECT_FALSE(bad.response.success);
  EXPECT_NE(bad.response.message.find("truncated map file"), std::string::npos)
      << bad.response.message;
  EXPECT_NE(bad.response.message.find("current map is unchanged"), std::string::npos)
      << bad.response.message;
  GetFullMesh after_bad;
  ASSERT_TRUE(ros::service::call("/stereo_fusion/get_full_mesh", after_bad));
  expectSameMesh(original.response.mesh, after_bad.response.mesh);

  // Reset, load: the identical mesh, also in what subscribers were sent.
  std_srvs::Empty reset;
  ASSERT_TRUE(ros::service::call("/stereo_fusion/reset", reset));
  LoadMap load;
  load.request.path = path;
  ASSERT_TRUE(ros::service::call("/stereo_fusion/load_map", load));
  ASSERT_TRUE(load.response.success) << load.response.message;
  EXPECT_EQ(load.response.blocks, save.response.blocks);
  GetFullMesh loaded;
  ASSERT_TRUE(ros::service::call("/stereo_fusion/get_full_mesh", loaded));
  expectSameMesh(original.response.mesh, loaded.response.mesh);
  ASSERT_TRUE(waitFor(
      [&] {
        std::lock_guard<std::mutex> lock(mutex_);
        return streamed_.size() == loaded.response.mesh.blocks.size();
      },
      10.0))
      << "the full update after load_map did not arrive";
  {
    std::lock_guard<std::mutex> lock(mutex_);
    EXPECT_TRUE(applied_ok_);
    for (const auto& block : loaded.response.mesh.blocks) {
      auto it = streamed_.find(BlockKey{block.key[0], block.key[1], block.key[2]});
      ASSERT_NE(it, streamed_.end());
      EXPECT_EQ(it->second.triangles.size() * 3, block.triangles.size());
    }
  }
  std::filesystem::remove(path);
  std::filesystem::remove(truncated);
}

namespace {
/// Run by fusion_nodelet_epoch.test, whose tf_timeout_s of 10 s lets a frame wait for its tf
/// across a reset or load_map however slow the machine is.
class NodeletEpoch : public NodeletFixture {
 protected:
  /// Publishes `frame` without its tf and waits until the worker has surely taken it up and
  /// is waiting for the transform; returns the stamp.
  ros::Time publishHeldForTf(const StereoFrame& frame, const std::string& frame_id) {
    const ros::Time stamp = ros::Time::now();
    publish(frame, frame_id, false, {}, stamp);
    ros::WallDuration(1.0).sleep();
    return stamp;
  }
  /// The held frame's transform (and a later one, so `stamp` is interpolated).
  void releaseTf(const StereoFrame& frame, const std::string& frame_id, const ros::Time& stamp) {
    std_msgs::Header header;
    header.frame_id = frame_id;
    header.stamp = stamp;
    tf_.sendTransform(toTransform(frame.T_world_camera, "map", header));
    header.stamp = stamp + ros::Duration(0.5);
    tf_.sendTransform(toTransform(frame.T_world_camera, "map", header));
  }
};
}  // namespace

// A frame that arrived before a reset or load_map belongs to the old map: whether it still
// waits in the queue or already waits for its tf, it is dropped as superseded, never fused into
// the new map.
TEST_F(NodeletEpoch, AFrameWaitingForTfAcrossResetOrLoadMapIsDroppedAsSuperseded) {
  const sim::AnalyticScene s = scene();
  auto frame_at = [&](double x) {
    return test::renderFrame(
        s, qvga(), sim::lookAt({x, -0.25, 0.0}, {0.05, 0.1, 1.2}, -Eigen::Vector3d::UnitY()));
  };
  for (int f = 0; f < 2; ++f) publish(frame_at(-0.1 + 0.1 * f), "left_optical", true);
  ASSERT_TRUE(waitFor([&] { return diag("frames fused") >= 2; }, 60.0)) << diag("frames fused");
  const std::string path =
      testing::TempDir() + "stereo_fusion_epoch_" + std::to_string(::getpid()) + ".sfmap";
  SaveMap save;
  save.request.path = path;
  ASSERT_TRUE(ros::service::call("/stereo_fusion/save_map", save));
  ASSERT_TRUE(save.response.success) << save.response.message;
  GetFullMesh saved;
  ASSERT_TRUE(ros::service::call("/stereo_fusion/get_full_mesh", saved));
  ASSERT_GT(saved.response.mesh.blocks.size(), 10u);
  const long fused = diag("frames fused");
  EXPECT_EQ(diag("dropped: superseded by reset/load"), 0);

  // Reset while a frame waits for its tf: the map stays empty.
  const StereoFrame held = frame_at(0.15);
  const ros::Time held_stamp = publishHeldForTf(held, "held_optical");
  std_srvs::Empty reset;
  ASSERT_TRUE(ros::service::call("/stereo_fusion/reset", reset));
  releaseTf(held, "held_optical", held_stamp);
  ASSERT_TRUE(waitFor([&] { return diag("dropped: superseded by reset/load") >= 1; }, 30.0));
  GetFullMesh after_reset;
  ASSERT_TRUE(ros::service::call("/stereo_fusion/get_full_mesh", after_reset));
  EXPECT_TRUE(after_reset.response.mesh.blocks.empty())
      << "a frame from before the reset was fused";

  // load_map while a frame waits for its tf: exactly the saved map.
  const StereoFrame held_again = frame_at(0.2);
  const ros::Time held_again_stamp = publishHeldForTf(held_again, "held_again_optical");
  LoadMap load;
  load.request.path = path;
  ASSERT_TRUE(ros::service::call("/stereo_fusion/load_map", load));
  ASSERT_TRUE(load.response.success) << load.response.message;
  releaseTf(held_again, "held_again_optical", held_again_stamp);
  ASSERT_TRUE(waitFor([&] { return diag("dropped: superseded by reset/load") >= 2; }, 30.0));
  GetFullMesh after_load;
  ASSERT_TRUE(ros::service::call("/stereo_fusion/get_full_mesh", after_load));
  expectSameMesh(saved.response.mesh, after_load.response.mesh);

  EXPECT_EQ(diag("dropped: superseded by reset/load"), 2);
  EXPECT_EQ(diag("frames fused"), fused);
  EXPECT_EQ(diag("dropped: tf timeout"), 0);
  // Frames arriving after the load are fused into the loaded map.
  publish(frame_at(0.0), "left_optical", true);
  EXPECT_TRUE(waitFor([&] { return diag("frames fused") >= fused + 1; }, 30.0));
  std::filesystem::remove(path);
}

namespace {
/// Vertices of the whole mesh `full` within `radius_m` of `centre`.
size_t verticesNear(const MeshUpdate& full, const Eigen::Vector3d& centre, double radius_m) {
  std::unordered_map<BlockKey, SubMesh, BlockKeyHash> mesh;
  EXPECT_TRUE(applyMeshUpdate(full, &mesh));
  size_t n = 0;
  for (const auto& [key, sub] : mesh)
    for (const Eigen::Vector3f& p : sub.positions)
      n += (p.cast<double>() - centre).norm() < radius_m;
  return n;
}
}  // namespace

// ~clear_sphere / ~clear_box forget a region; the streamed mesh follows with removals. A frame
// that arrived before the clear (here: still waiting for its tf) is fused, but the region is
// cleared again after it, so it does not bring back what the operator cleared; frames after
// the clear fill the region again.
TEST_F(NodeletEpoch, ClearedRegionsStayClearOfFramesFromBeforeTheClear) {
  const sim::AnalyticScene s = scene();
  const Eigen::Vector3d ball(0.05, 0.1, 1.2);
  auto frame_at = [&](double x) {
    return test::renderFrame(s, qvga(),
                             sim::lookAt({x, -0.25, 0.0}, ball, -Eigen::Vector3d::UnitY()));
  };
  std_srvs::Empty reset;
  ASSERT_TRUE(ros::service::call("/stereo_fusion/reset", reset));
  const long fused_start = std::max(0L, diag("frames fused"));
  const long superseded_start = std::max(0L, diag("dropped: superseded by reset/load"));
  for (int f = 0; f < 3; ++f) publish(frame_at(-0.1 + 0.1 * f), "left_optical", true);
  ASSERT_TRUE(waitFor([&] { return diag("frames fused") >= fused_start + 3; }, 60.0))
      << diag("frames fused");
  GetFullMesh before;
  ASSERT_TRUE(ros::service::call("/stereo_fusion/get_full_mesh", before));
  ASSERT_GT(verticesNear(before.response.mesh, ball, 0.25), 200u);

  // An invalid region is refused and changes nothing.
  ClearSphere bad;
  bad.request.center.z = 1.2;
  bad.request.radius = -0.5;
  ASSERT_TRUE(ros::service::call("/stereo_fusion/clear_sphere", bad));
  EXPECT_FALSE(bad.response.success);
  EXPECT_NE(bad.response.message.find("radius must be positive"), std::string::npos)
      << bad.response.message;
  GetFullMesh unchanged;
  ASSERT_TRUE(ros::service::call("/stereo_fusion/get_full_mesh", unchanged));
  expectSameMesh(before.response.mesh, unchanged.response.mesh);

  // A frame from before the clear waits for its tf while the operator clears the ball.
  const StereoFrame held = frame_at(0.15);
  const ros::Time held_stamp = publishHeldForTf(held, "held_clear_optical");
  ClearSphere clear;
  clear.request.center.x = ball.x();
  clear.request.center.y = ball.y();
  clear.request.center.z = ball.z();
  clear.request.radius = 0.35;
  ASSERT_TRUE(ros::service::call("/stereo_fusion/clear_sphere", clear));
  ASSERT_TRUE(clear.response.success) << clear.response.message;
  EXPECT_GT(clear.response.voxels_cleared, 1000u);
  EXPECT_GT(clear.response.blocks_erased, 0u);
  GetFullMesh cleared;
  ASSERT_TRUE(ros::service::call("/stereo_fusion/get_full_mesh", cleared));
  EXPECT_EQ(verticesNear(cleared.response.mesh, ball, 0.34), 0u);
  EXPECT_GT(verticesNear(cleared.response.mesh, ball, 1.0), 100u)
      << "the floor around the ball is kept";
  // The stream carried the removals: the subscriber's copy equals the full mesh.
  ASSERT_TRUE(waitFor(
      [&] {
        std::lock_guard<std::mutex> lock(mutex_);
        return streamed_.size() == cleared.response.mesh.blocks.size();
      },
      10.0))
      << "the removals did not arrive on ~mesh_update";

  releaseTf(held, "held_clear_optical", held_stamp);
  ASSERT_TRUE(waitFor([&] { return diag("frames fused") >= fused_start + 4; }, 30.0));
  ASSERT_TRUE(diagnostics_.waitForNextReport(10.0));
  EXPECT_EQ(diag("frames fused from before a clear (region cleared again)"), 1);
  GetFullMesh after_held;
  ASSERT_TRUE(ros::service::call("/stereo_fusion/get_full_mesh", after_held));
  EXPECT_EQ(verticesNear(after_held.response.mesh, ball, 0.34), 0u)
      << "a frame from before the clear refilled it";

  // A frame after the clear sees the ball again; a box clears it again.
  publish(frame_at(0.05), "left_optical", true);
  ASSERT_TRUE(waitFor([&] { return diag("frames fused") >= fused_start + 5; }, 30.0));
  GetFullMesh refilled;
  ASSERT_TRUE(ros::service::call("/stereo_fusion/get_full_mesh", refilled));
  EXPECT_GT(verticesNear(refilled.response.mesh, ball, 0.25), 100u);
  ClearBox box;
  box.request.min.x = ball.x() - 0.3;
  box.request.min.y = ball.y() - 0.3;
  box.request.min.z = ball.z() - 0.3;
  box.request.max.x = ball.x() + 0.3;
  box.request.max.y = ball.y() + 0.3;
  box.request.max.z = ball.z() + 0.3;
  ASSERT_TRUE(ros::service::call("/stereo_fusion/clear_box", box));
  ASSERT_TRUE(box.response.success) << box.response.message;
  GetFullMesh boxed;
  ASSERT_TRUE(ros::service::call("/stereo_fusion/get_full_mesh", boxed));
  EXPECT_EQ(verticesNear(boxed.response.mesh, ball, 0.29), 0u);
  EXPECT_TRUE(
      waitFor([&] { return diag("regions cleared (~clear_box, ~clear_sphere)") == 2; }, 10.0))
      << diag("regions cleared (~clear_box, ~clear_sphere)");
  EXPECT_EQ(diag("dropped: superseded by reset/load"), superseded_start)
      << "a clear drops no frame";
}

TEST(NodeParameters, OutOfRangeValuesAtStartUpNameTheParameter) {
  // loadParameters() is what FusionNodelet::onInit() runs before anything else; it throws with
  // this message. Parameters go through a real master, with the types YAML would give them.
  struct Case {
    const char* name;
    std::function<void(const std::string& ns)> set;
    const char* message;
  };
  const std::vector<Case> cases = {
      {"truncation_vox",
       [](const std::string& ns) { ros::param::set(ns + "/truncation_vox", 100); },
       "parameter '/bad_truncation_vox/truncation_vox' = 100 is out of range [1, 8]"},
      {"max_blocks", [](const std::string& ns) { ros::param::set(ns + "/max_blocks", -1); },
       "= -1 is out of range [0, 100000000]"},
      {"max_pose_jump_m",
       [](const std::string& ns) { ros::param::set(ns + "/max_pose_jump_m", -5.0); },
       "is out of range [0, 1e+06]"},
      {"voxel_size_m",
       [](const std::string& ns) { ros::param::set(ns + "/voxel_size_m", std::string("abc")); },
       "is not a finite number"},
      {"depths", [](const std::string& ns) { ros::param::set(ns + "/min_depth_m", 9.0); },
       "min_depth_m must be < max_depth_m"},
      {"queue_size", [](const std::string& ns) { ros::param::set(ns + "/queue_size", 0); },
       "parameter '/bad_queue_size/queue_size' = 0 is out of range [1, 1000] frames"},
      {"negative_queue_size",
       [](const std::string& ns) { ros::param::set(ns + "/queue_size", -4); },
       "parameter '/bad_negative_queue_size/queue_size' = -4 is out of range [1, 1000] frames"},
      {"fractional_queue_size",
       [](const std::string& ns) { ros::param::set(ns + "/queue_size", 2.5); },
       "parameter '/bad_fractional_queue_size/queue_size': '2.5' is not an integer"},
      {"tf_timeout_s", [](const std::string& ns) { ros::param::set(ns + "/tf_timeout_s", -1.0); },
       "parameter '/bad_tf_timeout_s/tf_timeout_s' = -1 is out of range [0, 10] s"},
      {"mesh_publish_rate_hz",
       [](const std::string& ns) { ros::param::set(ns + "/mesh_publish_rate_hz", 5000); },
       "mesh_publish_rate_hz' = 5000 is out of range [0, 1000] Hz"},
      {"queue_policy",
       [](const std::string& ns) {
         ros::param::set(ns + "/queue_policy", std::string("drop_all"));
       },
       "parameter '/bad_queue_policy/queue_policy': 'drop_all' is not one of drop_oldest | "
       "drop_newest"},
      {"sync_mode",
       [](const std::string& ns) {
         ros::param::set(ns + "/approximate_sync", std::string("sometimes"));
       },
       "parameter '/bad_sync_mode/approximate_sync': 'sometimes' is not true or false"},
      {"sync_queue_size",
       [](const std::string& ns) { ros::param::set(ns + "/sync_queue_size", 0); },
       "sync_queue_size' = 0 is out of range [1, 1000] messages"},
      {"mesh_encoding",
       [](const std::string& ns) { ros::param::set(ns + "/mesh_encoding", std::string("png")); },
       "mesh_encoding': 'png' is not one of float32 | compact"},
      {"world_frame",
       [](const std::string& ns) { ros::param::set(ns + "/world_frame", std::string()); },
       "parameter '/bad_world_frame/world_frame' must not be empty"},
      {"input",
       [](const std::string& ns) { ros::param::set(ns + "/input", std::string("pointcloud")); },
       "parameter '/bad_input/input': 'pointcloud' is not one of disparity | depth"},
      {"depth_baseline_m",
       [](const std::string& ns) { ros::param::set(ns + "/depth_baseline_m", 0.0); },
       "depth_baseline_m' = 0 is out of range (0, 10] m"},
      {"image_transport",
       [](const std::string& ns) { ros::param::set(ns + "/image_transport", std::string()); },
       "parameter '/bad_image_transport/image_transport' must not be empty"},
      {"loop_closure_max_frames",
       [](const std::string& ns) { ros::param::set(ns + "/loop_closure_max_frames", -1); },
       "loop_closure_max_frames' = -1 is out of range [0, 100000] frames"},
      {"max_request_wait_s",
       [](const std::string& ns) { ros::param::set(ns + "/max_request_wait_s", 0.0); },
       "parameter '/bad_max_request_wait_s/max_request_wait_s' = 0 is out of range (0, 60] s"},
      {"list",
       [](const std::string& ns) {
         ros::param::set(ns + "/max_weight", std::vector<double>{1, 2});
       },
       "must be a single value"},
      {"node_list",
       [](const std::string& ns) {
         ros::param::set(ns + "/frustum_depth_m", std::vector<double>{1, 2});
       },
       "parameter '/bad_node_list/frustum_depth_m' must be a single value"},
  };
  for (const Case& c : cases) {
    const std::string ns = std::string("/bad_") + c.name;
    c.set(ns);
    MapperConfig mapper;
    NodeConfig node;
    std::string error;
    EXPECT_FALSE(loadParameters(ros::NodeHandle(ns), &mapper, &node, &error)) << c.name;
    EXPECT_NE(error.find(c.message), std::string::npos) << c.name << ": " << error;
    EXPECT_EQ(node.queue_size, NodeConfig{}.queue_size)
        << c.name << ": a refused load changes nothing";
    EXPECT_EQ(node.world_frame, NodeConfig{}.world_frame) << c.name;
  }
  MapperConfig mapper;
  NodeConfig node;
  std::string error;
  EXPECT_TRUE(loadParameters(ros::NodeHandle("/no_parameters_here"), &mapper, &node, &error))
      << error;
}

// Every node parameter is read from the master through its registry, with the types YAML would
// give the values (an int where a double is expected, a double holding a whole number of frames).
TEST(NodeParameters, EveryNodeParameterIsReadThroughTheRegistry) {
  const std::string ns = "/all_node_parameters";
  ros::param::set(ns + "/world_frame", std::string("map"));
  ros::param::set(ns + "/input", std::string("depth"));
  ros::param::set(ns + "/depth_baseline_m", 0.095);
  ros::param::set(ns + "/image_transport", std::string("compressed"));
  ros::param::set(ns + "/depth_image_transport", std::string("compressedDepth"));
  ros::param::set(ns + "/queue_size", 12.0);
  ros::param::set(ns + "/queue_policy", std::string("drop_newest"));
  ros::param::set(ns + "/approximate_sync", true);
  ros::param::set(ns + "/sync_queue_size", 3);
  ros::param::set(ns + "/tf_timeout_s", 1);
  ros::param::set(ns + "/max_stamp_ahead_s", 0.0);
  ros::param::set(ns + "/mesh_publish_rate_hz", 0.5);
  ros::param::set(ns + "/publish_markers", false);
  ros::param::set(ns + "/publish_path", false);
  ros::param::set(ns + "/publish_frustum", false);
  ros::param::set(ns + "/frustum_depth_m", 2.5);
  ros::param::set(ns + "/publish_block_bounds", true);
  ros::param::set(ns + "/mesh_encoding", std::string("compact"));
  ros::param::set(ns + "/loop_closure_max_frames", 0);
  ros::param::set(ns + "/trajectory_frame", std::string("base_link"));
  ros::param::set(ns + "/max_request_wait_s", 0.5);
  ros::param::set(ns + "/allow_unknown_parameters", true);
  ros::param::set(ns + "/voxel_size_m", 0.04);
  MapperConfig mapper;
  NodeConfig node;
  std::string error;
  ASSERT_TRUE(loadParameters(ros::NodeHandle(ns), &mapper, &node, &error)) << error;
  EXPECT_EQ(mapper.voxel_size_m, 0.04);
  EXPECT_EQ(node.world_frame, "map");
  EXPECT_EQ(node.input, InputMode::kDepth);
  EXPECT_EQ(node.depth_baseline_m, 0.095);
  EXPECT_EQ(node.image_transport, "compressed");
  EXPECT_EQ(node.depth_image_transport, "compressedDepth");
  EXPECT_EQ(node.queue_size, 12);
  EXPECT_FALSE(node.drop_oldest);
  EXPECT_TRUE(node.approximate_sync);
  EXPECT_EQ(node.sync_queue_size, 3);
  EXPECT_EQ(node.tf_timeout_s, 1.0);
  EXPECT_EQ(node.max_stamp_ahead_s, 0.0);
  EXPECT_EQ(node.mesh_publish_rate_hz, 0.5);
  EXPECT_FALSE(node.publish_markers);
  EXPECT_FALSE(node.publish_path);
  EXPECT_FALSE(node.publish_frustum);
  EXPECT_EQ(node.frustum_depth_m, 2.5);
  EXPECT_TRUE(node.publish_block_bounds);
  EXPECT_EQ(node.mesh_encoding, MeshEncoding::kCompact);
  EXPECT_EQ(node.loop_closure_max_frames, 0);
  EXPECT_EQ(node.trajectory_frame, "base_link");
  EXPECT_EQ(node.max_request_wait_s, 0.5);
  EXPECT_TRUE(node.allow_unknown_parameters);
}

// A name in the node's namespace that no parameter has (a misspelt key, a nested namespace) is
// refused: loadParameters() names it with the nearest known name, and the nodelet does not start.
// allow_unknown_parameters: true turns each into a warning, and the nodelet starts.
TEST(NodeParameters, AMisspeltNameStopsTheStartAndNamesTheNearestName) {
  const std::string ns = "/misspelt/stereo_fusion";
  ros::param::set(ns + "/voxel_size_m", 0.04);
  ros::param::set(ns + "/tf_timout_s", 1.0);
  ros::param::set(ns + "/meshing/rate_hz", 2.0);
  ros::param::set(ns + "/diagnostic_period", 1.0);  // diagnostic_updater's, allowed
  const std::string misspelt =
      "unknown parameter '/misspelt/stereo_fusion/tf_timout_s' (did you mean 'tf_timeout_s'?)";
  MapperConfig mapper;
  NodeConfig node;
  std::string error;
  EXPECT_FALSE(loadParameters(ros::NodeHandle(ns), &mapper, &node, &error));
  EXPECT_NE(error.find(misspelt), std::string::npos) << error;
  EXPECT_NE(error.find("unknown parameter '/misspelt/stereo_fusion/meshing'"), std::string::npos)
      << error;
  EXPECT_EQ(error.find("diagnostic_period"), std::string::npos) << error;
  EXPECT_NE(error.find("allow_unknown_parameters"), std::string::npos) << error;
  EXPECT_EQ(mapper.voxel_size_m, MapperConfig{}.voxel_size_m) << "a refused load changes nothing";

  // The nodelet itself, as a manager loads it (onInit() refuses by throwing).
  auto load = [&](std::string* why) {
    // boost::function, not the lambda: a captureless lambda converts to bool, Loader's other
    // constructor's argument.
    const boost::function<boost::shared_ptr<nodelet::Nodelet>(const std::string&)> create =
        [](const std::string&) { return boost::make_shared<FusionNodelet>(); };
    nodelet::Loader loader(create);
    bool loaded = false;
    try {
      loaded = loader.load(ns, "stereo_fusion/FusionNodelet", {}, {});
    } catch (const std::exception& e) {
      *why = e.what();
    }
    if (loaded) loader.unload(ns);
    return loaded;
  };
  std::string why;
  EXPECT_FALSE(load(&why)) << "the nodelet started with a misspelt parameter";

  ros::param::set(ns + "/allow_unknown_parameters", true);
  std::vector<std::string> warnings;
  ASSERT_TRUE(loadParameters(ros::NodeHandle(ns), &mapper, &node, &error, &warnings)) << error;
  ASSERT_EQ(warnings.size(), 2u);
  EXPECT_EQ(warnings[1], misspelt);
  EXPECT_EQ(mapper.voxel_size_m, 0.04);
  EXPECT_TRUE(load(&why)) << why;
  ros::param::del("/misspelt");
}

// The registry's mesh_encoding labels are the ones the messages' parseMeshEncoding() takes.
TEST(NodeParameters, MeshEncodingLabelsAreTheMessages) {
  for (const ParameterSpec& spec : nodeParameterSpecs()) {
    if (spec.name != "mesh_encoding") continue;
    EXPECT_EQ(spec.range, "float32 | compact");
    for (const char* label : {"float32", "compact"}) {
      NodeConfig node;
      std::string error;
      ASSERT_TRUE(setNodeParameter(&node, "mesh_encoding", label, &error)) << error;
      MeshEncoding parsed = node.mesh_encoding == MeshEncoding::kFloat32 ? MeshEncoding::kCompact
                                                                         : MeshEncoding::kFloat32;
      ASSERT_TRUE(parseMeshEncoding(label, &parsed)) << label;
      EXPECT_EQ(parsed, node.mesh_encoding) << label;
    }
    return;
  }
  FAIL() << "no mesh_encoding in the node registry";
}

// Last in this file: the probe runs beside the launched nodelet, in a namespace of its own.
TEST(NodeletUnload, QueuesLiveUntilTheNodeletIsDestroyed) {
  test::expectQueuesLiveUntilTheNodeletIsDestroyed<FusionNodelet>("/queue_probe/stereo_fusion");
}

int main(int argc, char** argv) { return test::runRosTests(argc, argv, "stereo_fusion_rostest"); }
