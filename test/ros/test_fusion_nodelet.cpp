// Integration test with a real master, the real nodelet and real messages (rostest).
#include <std_srvs/Empty.h>
#include <stereo_fusion/GetFullMesh.h>
#include <stereo_fusion/MeshUpdate.h>
#include <stereo_fusion/SaveMesh.h>
#include <tf2_ros/transform_broadcaster.h>

#include <unistd.h>

#include <fstream>
#include <opencv2/core.hpp>
#include <map>
#include <mutex>

#include "../unit/TestSupport.h"
#include "RosTestSupport.h"
#include "stereo_fusion/io/ObjReader.h"
#include "stereo_fusion/io/PlyReader.h"
#include "stereo_fusion/ros/MeshMessages.h"
#include "stereo_fusion/ros/MessageConversions.h"

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
    ASSERT_TRUE(waitFor([&] {
      return disparity_pub_.getNumSubscribers() > 0 && image_pub_.getNumSubscribers() > 0 &&
             info_pub_.getNumSubscribers() > 0 && update_sub_.getNumPublishers() > 0;
    }, 30.0)) << "the nodelet did not connect";
  }

  template <typename F>
  bool waitFor(F&& done, double timeout_s) {
    return test::waitFor(std::forward<F>(done), timeout_s);
  }

  void publish(const StereoFrame& frame, const std::string& frame_id, bool with_tf,
               const std::function<void(stereo_msgs::DisparityImage*, sensor_msgs::Image*)>& corrupt = {}) {
    std_msgs::Header header;
    header.stamp = ros::Time::now();
    header.frame_id = frame_id;
    if (with_tf) tf_.sendTransform(toTransform(frame.T_world_camera, "world", header));
    stereo_msgs::DisparityImage d;
    sensor_msgs::Image i;
    sensor_msgs::CameraInfo c;
    toMessages(frame, header, 128.0f, &d, &i, &c);
    if (corrupt) corrupt(&d, &i);
    ros::WallDuration(0.05).sleep();  // tf first, as a SLAM stack running ahead would
    disparity_pub_.publish(d);
    image_pub_.publish(i);
    info_pub_.publish(c);
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
    const auto pose = sim::lookAt({-0.15 + 0.1 * f, -0.2, 0.0}, {0.05, 0.1, 1.2}, -Eigen::Vector3d::UnitY());
    publish(test::renderFrame(s, qvga(), pose), "left_optical", true);
  }
  ASSERT_TRUE(waitFor([&] { return diag("frames fused") >= 4; }, 60.0)) << "fused " << diag("frames fused");
  ros::WallDuration(1.0).sleep();  // let the last update arrive
  EXPECT_EQ(diag("dropped: tf timeout"), 0);
  EXPECT_EQ(diag("dropped: bad input"), 0);

  GetFullMesh full;
  ASSERT_TRUE(ros::service::call("/stereo_fusion/get_full_mesh", full));
  EXPECT_TRUE(full.response.mesh.full);
  std::unordered_map<BlockKey, SubMesh, BlockKeyHash> reference;
  std::unordered_map<BlockKey, TexturePatch, BlockKeyHash> reference_textures;
  ASSERT_TRUE(applyMeshUpdate(full.response.mesh, &reference, &reference_textures));
  ASSERT_GT(reference.size(), 10u);
  // fusion_nodelet.test turns texture patches on: textured blocks carry a PNG and one UV per vertex.
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
  ASSERT_EQ(streamed_.size(), reference.size());
  for (const auto& [key, ref] : reference) {
    auto it = streamed_.find(key);
    ASSERT_NE(it, streamed_.end()) << key;
    EXPECT_EQ(it->second.positions, ref.positions) << key;
    EXPECT_EQ(it->second.triangles, ref.triangles) << key;
    EXPECT_EQ(it->second.colors, ref.colors) << key;
  }
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
  save.request.path = testing::TempDir() + "stereo_fusion_rostest_mesh_" + std::to_string(getpid()) + ".obj";
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
  for (const ObjMaterial& m : obj.materials) atlas_found |= !m.diffuse_map.empty() && std::ifstream(m.diffuse_map).good();
  EXPECT_TRUE(atlas_found);
}

TEST_F(NodeletFixture, MissingTfAndBadInputAreDroppedCountedAndSurvived) {
  const sim::AnalyticScene s = scene();
  const StereoFrame frame = test::renderFrame(s, qvga(), Eigen::Isometry3d::Identity());
  const long fused_before = std::max(0L, diag("frames fused"));
  GetFullMesh before;
  ASSERT_TRUE(ros::service::call("/stereo_fusion/get_full_mesh", before));
  publish(frame, "camera_without_tf", false);
  publish(frame, "left_optical", true, [](stereo_msgs::DisparityImage* d, sensor_msgs::Image*) { d->T = 0.0f; });
  publish(frame, "left_optical", true, [](stereo_msgs::DisparityImage*, sensor_msgs::Image* i) {
    i->encoding = "yuv422";
  });
  publish(frame, "left_optical", true, [](stereo_msgs::DisparityImage* d, sensor_msgs::Image*) {
    d->image.data.resize(d->image.data.size() / 2);  // truncated payload
  });
  publish(frame, "left_optical", true, [](stereo_msgs::DisparityImage*, sensor_msgs::Image* i) {
    i->width /= 2;  // image and disparity sizes differ
    i->step /= 2;
    i->data.resize(i->step * i->height);
  });
  ASSERT_TRUE(waitFor([&] { return diag("dropped: tf timeout") >= 1 && diag("dropped: bad input") >= 4; }, 30.0))
      << "tf " << diag("dropped: tf timeout") << ", bad " << diag("dropped: bad input");
  // A disparity image full of NaN is valid input with nothing in it: fused, map unchanged.
  const long fused_mid = diag("frames fused");
  publish(frame, "left_optical", true, [](stereo_msgs::DisparityImage* d, sensor_msgs::Image*) {
    float* px = reinterpret_cast<float*>(d->image.data.data());
    for (size_t k = 0; k < d->image.data.size() / 4; ++k) px[k] = NAN;
  });
  ASSERT_TRUE(waitFor([&] { return diag("frames fused") >= fused_mid + 1; }, 30.0));
  GetFullMesh after;
  ASSERT_TRUE(ros::service::call("/stereo_fusion/get_full_mesh", after));
  ASSERT_EQ(after.response.mesh.blocks.size(), before.response.mesh.blocks.size()) << "bad input changed the map";
  for (size_t b = 0; b < before.response.mesh.blocks.size(); ++b) {
    EXPECT_EQ(after.response.mesh.blocks[b].key, before.response.mesh.blocks[b].key);
    EXPECT_EQ(after.response.mesh.blocks[b].vertices, before.response.mesh.blocks[b].vertices);
  }
  // The node keeps running and fusing.
  publish(frame, "left_optical", true);
  EXPECT_TRUE(waitFor([&] { return diag("frames fused") >= fused_before + 2; }, 30.0));
  EXPECT_EQ(diag("dropped: tf timeout"), 1);
  EXPECT_EQ(diag("dropped: bad input"), 4);
  std_srvs::Empty reset;
  EXPECT_TRUE(ros::service::call("/stereo_fusion/reset", reset));
  GetFullMesh full;
  ASSERT_TRUE(ros::service::call("/stereo_fusion/get_full_mesh", full));
  EXPECT_TRUE(full.response.mesh.blocks.empty());
}

int main(int argc, char** argv) { return test::runRosTests(argc, argv, "stereo_fusion_rostest"); }
