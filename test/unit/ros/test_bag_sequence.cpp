// Reading stereo frames from a real rosbag written with the rosbag C++ API.
#include <gtest/gtest.h>
#include <cv_bridge/cv_bridge.h>
#include <rosbag/bag.h>
#include <sensor_msgs/image_encodings.h>
#include <tf2_eigen/tf2_eigen.h>
#include <tf2_msgs/TFMessage.h>

#include <filesystem>
#include <fstream>

#include "MeshTestSupport.h"
#include "fuser/OfflineFuser.h"
#include "stereo_fusion/ros/BagSequence.h"
#include "stereo_fusion/ros/MessageConversions.h"
#include "stereo_fusion/ros/StereoBagWriter.h"

using namespace stereo_fusion;
using namespace stereo_fusion::test;
namespace fs = std::filesystem;

namespace {

struct BagMessages {
  stereo_msgs::DisparityImage disparity;
  sensor_msgs::Image image;
  sensor_msgs::CameraInfo info;
};

BagMessages toMessages(const StereoFrame& f, const ros::Time& stamp) {
  BagMessages m;
  std_msgs::Header header;
  header.stamp = stamp;
  header.frame_id = "left_optical";
  stereo_fusion::toMessages(f, header, 128.0f, &m.disparity, &m.image, &m.info);
  return m;
}

/// Three frames; the last has no transform in /tf (tf2 interpolates between transforms, so
/// a gap is only missing when no later transform exists).
struct SmallBag {
  std::string path;
  std::vector<StereoFrame> frames;
  SmallBag() {
    // One file per test: ctest runs the tests of this binary in parallel processes.
    path = testing::TempDir() + "stereo_fusion_" +
           testing::UnitTest::GetInstance()->current_test_info()->name() + ".bag";
    const sim::AnalyticScene scene = floorAndSphere();
    rosbag::Bag bag(path, rosbag::bagmode::Write);
    for (int i = 0; i < 3; ++i) {
      const ros::Time stamp(100.0 + 0.1 * i);
      const Eigen::Isometry3d T =
          sim::lookAt({-0.1 + 0.1 * i, -0.2, 0.0}, {0.05, 0.1, 1.2}, -Eigen::Vector3d::UnitY());
      StereoFrame f = renderFrame(scene, qvgaCamera(), T);
      f.timestamp_s = stamp.toSec();
      frames.push_back(f);
      if (i != 2) {
        std_msgs::Header camera;
        camera.stamp = stamp;
        camera.frame_id = "left_optical";
        tf2_msgs::TFMessage tf;
        tf.transforms.push_back(toTransform(T, "world", camera));
        bag.write("/tf", stamp, tf);
      }
      const BagMessages m = toMessages(f, stamp);
      bag.write("/stereo/disparity", stamp, m.disparity);
      bag.write("/stereo/left/image_rect_color", stamp, m.image);
      bag.write("/stereo/left/camera_info", stamp, m.info);
    }
    bag.close();
  }
  ~SmallBag() { fs::remove(path); }
};

}  // namespace

TEST(BagSequence, ReadsFramesAndPosesAndReportsMissingTf) {
  SmallBag bag;
  std::string error;
  auto seq = BagSequence::open(bag.path, BagTopics{}, &error);
  ASSERT_TRUE(seq) << error;
  ASSERT_EQ(seq->size(), 3u);
  for (int i : {0, 1}) {
    StereoFrame f;
    ASSERT_TRUE(seq->load(i, &f, &error)) << error;
    EXPECT_NEAR(f.timestamp_s, bag.frames[i].timestamp_s, 1e-9);
    EXPECT_LT(
        (f.T_world_camera.matrix() - bag.frames[i].T_world_camera.matrix()).cwiseAbs().maxCoeff(),
        1e-9);
    EXPECT_EQ(cv::norm(f.disparity_px, bag.frames[i].disparity_px, cv::NORM_INF), 0.0);
    EXPECT_EQ(cv::norm(f.color, bag.frames[i].color, cv::NORM_INF), 0.0);
    EXPECT_DOUBLE_EQ(f.camera.fx(), 262.5);
    EXPECT_DOUBLE_EQ(f.camera.baseline(), static_cast<float>(0.1));
  }
  StereoFrame f;
  EXPECT_FALSE(seq->load(2, &f, &error));
  EXPECT_NE(error.find("no transform world <- left_optical"), std::string::npos) << error;
}

TEST(BagSequence, OfflineFuserReadsABagAndCountsTheFrameWithoutTf) {
  SmallBag bag;
  FuseOptions options;
  std::string error;
  const fs::path out = fs::path(testing::TempDir()) / "stereo_fusion_bag_out";
  ASSERT_TRUE(parseFuseArguments({bag.path, out.string(), "--quiet"}, &options, &error)) << error;
  FuseReport report;
  ASSERT_TRUE(runOfflineFusion(options, &report, &error)) << error;
  EXPECT_EQ(report.frames_total, 3u);
  EXPECT_EQ(report.frames_used, 2u);
  EXPECT_EQ(report.skipped.at("unreadable"), 1u);
  EXPECT_GT(report.mesh_triangles, 500u);
  fs::remove_all(out);
}

TEST(BagSequence, BadBagsAndTopicsAreClearErrors) {
  std::string error;
  const std::string garbage = testing::TempDir() + "stereo_fusion_garbage.bag";
  std::ofstream(garbage) << "not a bag at all";
  EXPECT_FALSE(BagSequence::open(garbage, BagTopics{}, &error));
  EXPECT_NE(error.find("cannot read the bag"), std::string::npos) << error;
  fs::remove(garbage);
  SmallBag bag;
  BagTopics topics;
  topics.disparity = "/elsewhere/disparity";
  EXPECT_FALSE(BagSequence::open(bag.path, topics, &error));
  EXPECT_NE(error.find("no stereo_msgs/DisparityImage on topic /elsewhere/disparity"),
            std::string::npos)
      << error;
}

TEST(StereoBagWriter, WritesWhatBagSequenceReads) {
  const std::string path = testing::TempDir() + "stereo_fusion_written.bag";
  sim::AnalyticScene scene;
  scene.add(sim::makeSphere({0, 0, 1.0}, 0.3), {90, 180, 200});
  std::vector<StereoFrame> frames;
  std::string error;
  {
    auto writer = StereoBagWriter::open(path, BagTopics{}, "cam", 1.0, &error);
    ASSERT_TRUE(writer) << error;
    for (int i = 0; i < 2; ++i) {
      StereoFrame f =
          renderFrame(scene, qvgaCamera(),
                      sim::lookAt({0.05 * i, 0, 0}, {0, 0, 1.0}, -Eigen::Vector3d::UnitY()));
      f.timestamp_s = 0.1 * i;  // starts at 0: the writer's offset keeps it away from "latest"
      ASSERT_TRUE(writer->write(f, 128.0f, &error)) << error;
      frames.push_back(f);
    }
  }
  auto seq = BagSequence::open(path, BagTopics{}, &error);
  ASSERT_TRUE(seq) << error;
  ASSERT_EQ(seq->size(), 2u);
  for (size_t i = 0; i < 2; ++i) {
    StereoFrame f;
    ASSERT_TRUE(seq->load(i, &f, &error)) << error;
    EXPECT_NEAR(f.timestamp_s, 1.0 + frames[i].timestamp_s, 1e-6);
    EXPECT_LT((f.T_world_camera.matrix() - frames[i].T_world_camera.matrix()).cwiseAbs().maxCoeff(),
              1e-9);
    EXPECT_EQ(cv::norm(f.disparity_px, frames[i].disparity_px, cv::NORM_INF), 0.0);
  }
  fs::remove(path);
}

TEST(MessageConversions, RejectsInconsistentMessages) {
  const StereoFrame f =
      renderFrame(sim::AnalyticScene(), qvgaCamera(), Eigen::Isometry3d::Identity());
  const BagMessages good = toMessages(f, ros::Time(1.0));
  StereoFrame out;
  std::string error;
  ASSERT_TRUE(toStereoFrame(good.disparity, good.image, good.info, Eigen::Isometry3d::Identity(),
                            &out, &error))
      << error;
  auto expectError = [&](BagMessages m, const char* fragment) {
    EXPECT_FALSE(
        toStereoFrame(m.disparity, m.image, m.info, Eigen::Isometry3d::Identity(), &out, &error))
        << fragment;
    EXPECT_NE(error.find(fragment), std::string::npos) << error;
  };
  BagMessages m = good;
  m.disparity.T = 0;
  expectError(m, "T > 0");
  m = good;
  m.disparity.f = 0;
  expectError(m, "f > 0");
  m = good;
  m.image.encoding = "yuv422";
  expectError(m, "unsupported image encoding 'yuv422'");
  m = good;
  m.disparity.image.encoding = "16UC1";
  expectError(m, "32FC1");
  m = good;
  m.image.width = 100;
  expectError(m, "image is 100x240");
  m = good;
  m.disparity.image.data.resize(10);
  expectError(m, "shorter than step");
  m = good;
  m.info.P[0] = 400;
  expectError(m, "disagrees with DisparityImage f");
}
