// The bad-input catalogue (doc/reliability.md, "Bad input") cases of the ROS layer: CameraInfo and
// DisparityImage calibration, empty images, and truncated bags in the offline path. Each checks
// the message, or that frames that cannot be read are skipped and counted. The Mapper's cases are
// in test/unit/mapper/test_bad_input.cpp.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <functional>
#include <stdexcept>

#include "MeshTestSupport.h"
#include "fuser/FuseArguments.h"
#include "fuser/OfflineFuser.h"
#include "stereo_fusion/ros/BagSequence.h"
#include "stereo_fusion/ros/MessageConversions.h"
#include "stereo_fusion/ros/StereoBagWriter.h"

using namespace stereo_fusion;
using namespace stereo_fusion::test;
namespace fs = std::filesystem;

namespace {

struct Messages {
  stereo_msgs::DisparityImage disparity;
  sensor_msgs::Image image;
  sensor_msgs::CameraInfo info;
};

Messages messagesOf(const StereoFrame& f) {
  Messages m;
  std_msgs::Header header;
  header.stamp = ros::Time(5.0);
  header.frame_id = "left_optical";
  toMessages(f, header, 128.0f, &m.disparity, &m.image, &m.info);
  return m;
}

}  // namespace

// A stamp far ahead of the clock is a bad timestamp, however far: 4e9 s against a clock at
// 1.7e9 s is 2.3e9 s ahead, past ros::Duration's ±2³¹ s, where subtracting ros::Times threw
// "Duration is out of dual 32-bit range" and the frame was counted as an error while fusing.
TEST(BadInput, StampsFarAheadOfTheClockAreCaughtWithoutThrowing) {
  const ros::Time now(1700000000u, 0), far(4000000000u, 0);
  EXPECT_THROW((void)(far - now), std::runtime_error) << "why the check works in doubles";
  bool ahead = false;
  EXPECT_NO_THROW(ahead = stampAheadOfClock(far, now, 10.0));
  EXPECT_TRUE(ahead);
  EXPECT_TRUE(stampAheadOfClock(ros::Time(1700000011u, 0), now, 10.0));
  EXPECT_FALSE(stampAheadOfClock(ros::Time(1700000009u, 0), now, 10.0));
  EXPECT_FALSE(stampAheadOfClock(far, now, 0.0)) << "0: the check is off";
  EXPECT_FALSE(stampAheadOfClock(far, ros::Time(), 10.0)) << "no clock yet";
}

TEST(BadInput, CameraInfoAndDisparityCalibrationAreChecked) {
  const Messages good = messagesOf(floorAndSphereFrame(0, 1.0));
  StereoFrame out;
  std::string error;
  ASSERT_TRUE(toStereoFrame(good.disparity, good.image, good.info, Eigen::Isometry3d::Identity(),
                            &out, &error))
      << error;
  struct Case {
    const char* name;
    std::function<void(Messages*)> corrupt;
    const char* message;
  };
  const std::vector<Case> cases = {
      {"CameraInfo fx = 0 (P and K)",
       [](Messages* m) {
         m->info.P[0] = 0;
         m->info.K[0] = 0;
       },
       "disagrees with DisparityImage f"},
      {"CameraInfo fx < 0", [](Messages* m) { m->info.P[0] = -262.5; },
       "disagrees with DisparityImage f"},
      {"CameraInfo fx NaN", [](Messages* m) { m->info.P[0] = NAN; },
       "focal lengths must be finite and > 0"},
      {"CameraInfo fy = 0", [](Messages* m) { m->info.P[5] = 0; },
       "focal lengths must be finite and > 0"},
      {"CameraInfo fy NaN", [](Messages* m) { m->info.P[5] = NAN; },
       "focal lengths must be finite and > 0"},
      {"CameraInfo cx inf", [](Messages* m) { m->info.P[2] = INFINITY; },
       "principal point must be finite"},
      {"DisparityImage T = 0", [](Messages* m) { m->disparity.T = 0; }, "needs f > 0 and T > 0"},
      {"DisparityImage T < 0", [](Messages* m) { m->disparity.T = -0.1f; },
       "needs f > 0 and T > 0"},
      {"DisparityImage f = 0", [](Messages* m) { m->disparity.f = 0; }, "needs f > 0 and T > 0"},
      {"DisparityImage f NaN", [](Messages* m) { m->disparity.f = NAN; }, "needs f > 0 and T > 0"},
      {"empty disparity image",
       [](Messages* m) {
         m->disparity.image.width = 0;
         m->disparity.image.height = 0;
         m->disparity.image.data.clear();
       },
       "disparity image is empty"},
      {"empty colour image",
       [](Messages* m) {
         m->image.width = 0;
         m->image.height = 0;
         m->image.data.clear();
       },
       "image is 0x0 but the disparity is 320x240"},
      {"colour data shorter than step × height", [](Messages* m) { m->image.data.resize(100); },
       "image data is shorter than step × height"},
      {"unsupported encoding bayer", [](Messages* m) { m->image.encoding = "bayer_rggb8"; },
       "unsupported image encoding"},
      {"disparity 16UC1", [](Messages* m) { m->disparity.image.encoding = "16UC1"; },
       "must be 32FC1"},
      {"disparity step not a multiple of 4",
       [](Messages* m) {
         m->disparity.image.step += 2;
         m->disparity.image.data.resize(size_t{m->disparity.image.step} *
                                        m->disparity.image.height);
       },
       "disparity step 1282 is not a multiple of 4 bytes"},
      {"CameraInfo size differs", [](Messages* m) { m->info.width = 640; },
       "CameraInfo is 640x240"},
      {"CameraInfo fy = 1e-3",
       [](Messages* m) {
         m->info.P[5] = 1e-3;
         m->info.K[4] = 1e-3;
       },
       "px are implausible for a 320x240 image"},
      {"CameraInfo principal point 1e9 (K and P)",
       [](Messages* m) {
         m->info.P[2] = 1e9;
         m->info.K[2] = 1e9;
       },
       "is implausible for a 320x240 image"},
      {"DisparityImage min_disparity NaN", [](Messages* m) { m->disparity.min_disparity = NAN; },
       "is not a range"},
      {"DisparityImage max_disparity inf",
       [](Messages* m) { m->disparity.max_disparity = INFINITY; }, "is not a range"},
      {"DisparityImage max < min",
       [](Messages* m) {
         m->disparity.min_disparity = 50;
         m->disparity.max_disparity = 10;
       },
       "is not a range"},
  };
  for (const Case& c : cases) {
    Messages m = good;
    c.corrupt(&m);
    error.clear();
    EXPECT_FALSE(
        toStereoFrame(m.disparity, m.image, m.info, Eigen::Isometry3d::Identity(), &out, &error))
        << c.name;
    EXPECT_NE(error.find(c.message), std::string::npos) << c.name << ": " << error;
  }
}

// A DisparityImage says which disparities are valid (min_disparity … max_disparity): values
// outside are not measurements and must not be fused.
TEST(BadInput, DisparitiesOutsideTheMessagesRangeAreNotMeasurements) {
  Messages m = messagesOf(floorAndSphereFrame(0, 1.0));
  StereoFrame all, clipped;
  std::string error;
  m.disparity.max_disparity = 0;  // no upper bound given
  ASSERT_TRUE(
      toStereoFrame(m.disparity, m.image, m.info, Eigen::Isometry3d::Identity(), &all, &error))
      << error;
  std::vector<float> valid;
  for (int v = 0; v < all.disparity_px.rows; ++v)
    for (int u = 0; u < all.disparity_px.cols; ++u)
      if (all.disparity_px.at<float>(v, u) > 0) valid.push_back(all.disparity_px.at<float>(v, u));
  ASSERT_GT(valid.size(), 1000u);
  std::nth_element(valid.begin(), valid.begin() + valid.size() / 2, valid.end());
  const float median = valid[valid.size() / 2];
  m.disparity.max_disparity = median;
  ASSERT_TRUE(
      toStereoFrame(m.disparity, m.image, m.info, Eigen::Isometry3d::Identity(), &clipped, &error))
      << error;
  size_t dropped = 0;
  for (int v = 0; v < all.disparity_px.rows; ++v)
    for (int u = 0; u < all.disparity_px.cols; ++u) {
      const float d = all.disparity_px.at<float>(v, u), kept = clipped.disparity_px.at<float>(v, u);
      if (d > median) {
        EXPECT_EQ(kept, 0.0f);
        ++dropped;
      } else {
        EXPECT_EQ(kept, d);
      }
    }
  EXPECT_GT(dropped, valid.size() / 4);
}

TEST(BadInput, TruncatedBagsFailCleanlyInTheOfflinePath) {
  const std::string path =
      testing::TempDir() + "stereo_fusion_truncated_" + std::to_string(::getpid()) + ".bag";
  std::string error;
  {
    auto writer = StereoBagWriter::open(path, BagTopics{}, "left_optical", 1.0, &error);
    ASSERT_TRUE(writer) << error;
    for (int i = 0; i < 3; ++i)
      ASSERT_TRUE(writer->write(floorAndSphereFrame(i, 0.1 * i), 128.0f, &error)) << error;
    writer->close();
  }
  const auto full_size = fs::file_size(path);
  const std::string out_dir = path + ".out";
  // Cut the bag at several points: every run either refuses the bag with one message or
  // skips and counts the frames it cannot read; none crashes, none fuses garbage.
  for (double share : {0.0, 0.01, 0.3, 0.6, 0.95}) {
    const std::string cut = path + ".cut.bag";
    fs::copy_file(path, cut, fs::copy_options::overwrite_existing);
    fs::resize_file(cut, static_cast<uintmax_t>(full_size * share));
    FuseOptions options;
    ASSERT_TRUE(parseFuseArguments({cut, out_dir, "--quiet"}, &options, &error)) << error;
    FuseReport report;
    const bool ran = runOfflineFusion(options, &report, &error);
    if (!ran) {
      EXPECT_NE(error.find(cut), std::string::npos)
          << share << ": the message names the bag: " << error;
    } else {
      size_t skipped = 0;
      for (const auto& [reason, n] : report.skipped) skipped += n;
      EXPECT_EQ(report.frames_used + skipped, report.frames_total) << share;
      EXPECT_LE(report.frames_used, 3u);
    }
    fs::remove(cut);
  }
  fs::remove(path);
  fs::remove_all(out_dir);
}

// A DisparityImage from a big-endian producer (is_bigendian = 1, bytes of each float reversed)
// reads as the same disparities: misread bytes would be garbage depths.
TEST(BadInput, BigEndianDisparitiesReadAsTheSameValues) {
  Messages m = messagesOf(floorAndSphereFrame(0, 1.0));
  StereoFrame little, big;
  std::string error;
  ASSERT_TRUE(
      toStereoFrame(m.disparity, m.image, m.info, Eigen::Isometry3d::Identity(), &little, &error))
      << error;
  sensor_msgs::Image& d = m.disparity.image;
  for (size_t k = 0; k + 4 <= d.data.size(); k += 4)
    std::reverse(d.data.begin() + k, d.data.begin() + k + 4);
  d.is_bigendian = 1;
  ASSERT_TRUE(
      toStereoFrame(m.disparity, m.image, m.info, Eigen::Isometry3d::Identity(), &big, &error))
      << error;
  ASSERT_EQ(big.disparity_px.size(), little.disparity_px.size());
  EXPECT_EQ(cv::norm(big.disparity_px, little.disparity_px, cv::NORM_INF), 0.0);
}

// DisparityImage.delta_d travels with the frame: it sets a floor under the disparity noise that
// picks the levels (LevelSelection.*), and a value that is no resolution refuses the frame there.
TEST(BadInput, TheDisparityStepTravelsWithTheFrame) {
  Messages m = messagesOf(floorAndSphereFrame(0, 1.0));
  StereoFrame frame;
  std::string error;
  m.disparity.delta_d = 1.0f;
  ASSERT_TRUE(
      toStereoFrame(m.disparity, m.image, m.info, Eigen::Isometry3d::Identity(), &frame, &error))
      << error;
  EXPECT_EQ(frame.disparity_step_px, 1.0);
  EXPECT_EQ(validateFrame(frame, 0.16), "");
  m.disparity.delta_d = NAN;
  ASSERT_TRUE(
      toStereoFrame(m.disparity, m.image, m.info, Eigen::Isometry3d::Identity(), &frame, &error))
      << error;
  EXPECT_NE(validateFrame(frame, 0.16).find("is not a resolution in [0, 4] px"), std::string::npos);
}
