// Reading stereo frames from a real rosbag written with the rosbag C++ API.
#include <gtest/gtest.h>
#include <unistd.h>
#include <cv_bridge/cv_bridge.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/image_encodings.h>
#include <tf2_eigen/tf2_eigen.h>
#include <tf2_msgs/TFMessage.h>

#include <std_msgs/String.h>
#include <tf2/buffer_core.h>
#include <tf2/exceptions.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <thread>

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
        tf.transforms.push_back(toTransform(T, "map", camera));
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

/// The reader BagSequence was before it streamed (2026-12-06): every DisparityImage, Image and
/// CameraInfo held in memory from open(), matched there. Kept as the reference the streaming
/// reader must equal, frame by frame and message by message.
class EagerBagSequence {
 public:
  static std::unique_ptr<EagerBagSequence> open(const std::string& path, const BagTopics& topics,
                                                std::string* error) {
    auto seq = std::make_unique<EagerBagSequence>();
    seq->topics_ = topics;
    rosbag::Bag bag;
    try {
      bag.open(path, rosbag::bagmode::Read);
      rosbag::View all(bag);
      if (all.size() == 0) {
        *error = path + ": the bag holds no messages";
        return nullptr;
      }
      const ros::Duration span = all.getEndTime() - all.getBeginTime() + ros::Duration(60.0);
      seq->tf_ = std::make_unique<tf2::BufferCore>(span);
      std::map<ros::Time, sensor_msgs::Image::ConstPtr> images;
      std::vector<sensor_msgs::CameraInfo::ConstPtr> infos;
      rosbag::View view(bag, rosbag::TopicQuery({topics.disparity, topics.image, topics.camera_info,
                                                 "/tf", "/tf_static"}));
      for (const rosbag::MessageInstance& m : view) {
        if (m.getTopic() == "/tf" || m.getTopic() == "/tf_static") {
          if (auto tf = m.instantiate<tf2_msgs::TFMessage>()) {
            const bool is_static = m.getTopic() == "/tf_static";
            for (const auto& t : tf->transforms) seq->tf_->setTransform(t, "bag", is_static);
          }
        } else if (m.getTopic() == topics.disparity) {
          if (auto d = m.instantiate<stereo_msgs::DisparityImage>()) seq->disparities_.push_back(d);
        } else if (m.getTopic() == topics.image) {
          if (auto im = m.instantiate<sensor_msgs::Image>()) images[im->header.stamp] = im;
        } else if (m.getTopic() == topics.camera_info) {
          if (auto ci = m.instantiate<sensor_msgs::CameraInfo>()) infos.push_back(ci);
        }
      }
      bag.close();
      if (seq->disparities_.empty()) {
        *error = path + ": no stereo_msgs/DisparityImage on topic " + topics.disparity;
        return nullptr;
      }
      for (const auto& d : seq->disparities_) {
        auto im = images.find(d->header.stamp);
        seq->images_.push_back(im == images.end() ? nullptr : im->second);
        sensor_msgs::CameraInfo::ConstPtr best = infos.empty() ? nullptr : infos.front();
        for (const auto& ci : infos)
          if (ci->header.stamp <= d->header.stamp) best = ci;
        seq->infos_.push_back(best);
      }
    } catch (const rosbag::BagException& e) {
      *error = path + ": cannot read the bag: " + e.what();
      return nullptr;
    }
    return seq;
  }

  size_t size() const { return disparities_.size(); }

  bool load(size_t i, StereoFrame* frame, std::string* error) const {
    if (i >= disparities_.size()) {
      *error = "frame " + std::to_string(i) + " is out of range";
      return false;
    }
    const auto& d = *disparities_[i];
    const std::string where =
        "frame " + std::to_string(i) + " (stamp " + std::to_string(d.header.stamp.toSec()) + ")";
    if (!images_[i]) {
      *error = where + ": no image on " + topics_.image + " with the same stamp";
      return false;
    }
    if (!infos_[i]) {
      *error = where + ": no CameraInfo on " + topics_.camera_info;
      return false;
    }
    Eigen::Isometry3d T_world_camera;
    try {
      T_world_camera = tf2::transformToEigen(
          tf_->lookupTransform(topics_.world_frame, d.header.frame_id, d.header.stamp));
    } catch (const tf2::TransformException& e) {
      *error = where + ": no transform " + topics_.world_frame + " <- " + d.header.frame_id + ": " +
               e.what();
      return false;
    }
    if (!toStereoFrame(d, *images_[i], *infos_[i], T_world_camera, frame, error)) {
      *error = where + ": " + *error;
      return false;
    }
    return true;
  }

 private:
  BagTopics topics_;
  std::unique_ptr<tf2::BufferCore> tf_;
  std::vector<stereo_msgs::DisparityImage::ConstPtr> disparities_;
  std::vector<sensor_msgs::Image::ConstPtr> images_;
  std::vector<sensor_msgs::CameraInfo::ConstPtr> infos_;
};

/// Frame i of `a` and of `b` load alike: both or neither, with the same message, to the same
/// stamp, pose, camera and pixels.
void expectSameFrame(size_t i, bool loaded_a, const StereoFrame& a, const std::string& error_a,
                     bool loaded_b, const StereoFrame& b, const std::string& error_b) {
  SCOPED_TRACE("frame " + std::to_string(i));
  ASSERT_EQ(loaded_a, loaded_b) << error_a << " | " << error_b;
  if (!loaded_a) {
    EXPECT_EQ(error_a, error_b);
    return;
  }
  EXPECT_EQ(a.timestamp_s, b.timestamp_s);
  EXPECT_TRUE(a.T_world_camera.isApprox(b.T_world_camera, 0));
  EXPECT_EQ(a.camera.width(), b.camera.width());
  EXPECT_EQ(a.camera.height(), b.camera.height());
  EXPECT_EQ(a.camera.fx(), b.camera.fx());
  EXPECT_EQ(a.camera.fy(), b.camera.fy());
  EXPECT_EQ(a.camera.cx(), b.camera.cx());
  EXPECT_EQ(a.camera.cy(), b.camera.cy());
  EXPECT_EQ(a.camera.baseline(), b.camera.baseline());
  EXPECT_EQ(a.disparity_step_px, b.disparity_step_px);
  ASSERT_EQ(a.disparity_px.size(), b.disparity_px.size());
  ASSERT_EQ(a.color.size(), b.color.size());
  ASSERT_EQ(a.color.type(), b.color.type());
  EXPECT_EQ(cv::norm(a.disparity_px, b.disparity_px, cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::norm(a.color, b.color, cv::NORM_INF), 0.0);
}

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
  EXPECT_NE(error.find("no transform map <- left_optical"), std::string::npos) << error;
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

// The streaming reader loads what the reader that held every message loaded, on a bag with the
// cases matching must get right: record times unlike the header stamps and out of their order,
// two images of one stamp (the later one wins), an image no frame has, a frame without its image,
// camera infos that change, one recorded late with an early stamp, frames before the first
// info's stamp (they take the first one), a message of another type on the disparity topic, and
// a frame without a transform. Then the same on a bag the simulator's writer wrote.
TEST(BagSequence, StreamingLoadsWhatTheEagerReaderLoaded) {
  const std::string path =
      testing::TempDir() + "stereo_fusion_streaming_" + std::to_string(::getpid()) + ".bag";
  const sim::AnalyticScene scene = floorAndSphere();
  constexpr int kFrames = 8;
  {
    rosbag::Bag bag(path, rosbag::bagmode::Write);
    auto info_with_cx = [](sensor_msgs::CameraInfo info, double cx, double stamp_s) {
      info.K[2] = cx;
      info.P[2] = cx;
      info.header.stamp = ros::Time(stamp_s);
      return info;
    };
    for (int i = 0; i < kFrames; ++i) {
      const ros::Time stamp(200.0 + 0.1 * i);
      const Eigen::Isometry3d T =
          sim::lookAt({-0.2 + 0.05 * i, -0.2, 0.0}, {0.05, 0.1, 1.2}, -Eigen::Vector3d::UnitY());
      StereoFrame f = renderFrame(scene, qvgaCamera(), T);
      BagMessages m = toMessages(f, stamp);
      if (i != kFrames - 1) {  // the last frame has no transform
        std_msgs::Header camera = m.disparity.header;
        tf2_msgs::TFMessage tf;
        tf.transforms.push_back(toTransform(T, "map", camera));
        bag.write("/tf", stamp - ros::Duration(0.01), tf);
      }
      // Recorded up to 0.3 s after their stamps, frame 6 before frame 5 (so the sequence's order,
      // the bag's, is not the stamps'), images before their disparities for odd frames and after
      // them for even ones, none for frame 4.
      const ros::Time recorded = stamp + ros::Duration(i == 6 ? 0.0 : 0.3 - 0.03 * i);
      if (i % 2 == 1) bag.write("/stereo/left/image_rect_color", recorded, m.image);
      bag.write("/stereo/disparity", recorded + ros::Duration(0.001), m.disparity);
      if (i % 2 == 0 && i != 4)
        bag.write("/stereo/left/image_rect_color", recorded + ros::Duration(0.002), m.image);
      if (i == 2) {  // a second image of frame 2's stamp, recorded later: it wins
        sensor_msgs::Image second = m.image;
        for (auto& byte : second.data) byte = static_cast<uint8_t>(255 - byte);
        bag.write("/stereo/left/image_rect_color", recorded + ros::Duration(0.003), second);
      }
      if (i == 3) {  // an image whose stamp no disparity has
        sensor_msgs::Image stray = m.image;
        stray.header.stamp = stamp + ros::Duration(0.05);
        bag.write("/stereo/left/image_rect_color", recorded, stray);
        // Another publisher's connection (rosbag files a message without one under the topic's
        // first connection, whatever its type).
        std_msgs::String text;
        text.data = "not a disparity image";
        auto talker = boost::make_shared<ros::M_string>();
        (*talker)["type"] = ros::message_traits::datatype(text);
        (*talker)["md5sum"] = ros::message_traits::md5sum(text);
        (*talker)["message_definition"] = ros::message_traits::definition(text);
        (*talker)["callerid"] = "/talker";
        (*talker)["latching"] = "0";
        bag.write("/stereo/disparity", recorded, text, talker);
      }
      // Infos: cx 159.5 stamped as frame 2 (frames 0 and 1 take it too: it is the first), 150 as
      // frame 5, and one recorded last stamped as frame 3 (cx 170): the frames from frame 3's
      // stamp on take it, as it comes later in the bag than cx 150.
      if (i == 2)
        bag.write("/stereo/left/camera_info", recorded, info_with_cx(m.info, 159.5, stamp.toSec()));
      if (i == 5)
        bag.write("/stereo/left/camera_info", recorded, info_with_cx(m.info, 150.0, stamp.toSec()));
      if (i == kFrames - 1)
        bag.write("/stereo/left/camera_info", recorded + ros::Duration(1.0),
                  info_with_cx(m.info, 170.0, 200.3));
    }
    bag.close();
  }
  auto compare = [](const std::string& bag_path, size_t expected_frames, size_t* loaded) {
    std::string error_a, error_b;
    auto eager = EagerBagSequence::open(bag_path, BagTopics{}, &error_a);
    auto streaming = BagSequence::open(bag_path, BagTopics{}, &error_b);
    ASSERT_TRUE(eager) << error_a;
    ASSERT_TRUE(streaming) << error_b;
    ASSERT_EQ(streaming->size(), eager->size());
    ASSERT_EQ(streaming->size(), expected_frames);
    *loaded = 0;
    for (size_t i = 0; i < eager->size() + 1; ++i) {  // one past the end: both refuse it
      StereoFrame a, b;
      const bool ok_a = eager->load(i, &a, &error_a), ok_b = streaming->load(i, &b, &error_b);
      expectSameFrame(i, ok_a, a, error_a, ok_b, b, error_b);
      *loaded += ok_b;
    }
    // Loading again, in another order, gives the same frames (nothing is consumed).
    for (size_t i = eager->size(); i-- > 0;) {
      StereoFrame a, b;
      const bool ok_a = eager->load(i, &a, &error_a), ok_b = streaming->load(i, &b, &error_b);
      expectSameFrame(i, ok_a, a, error_a, ok_b, b, error_b);
    }
  };
  size_t loaded = 0;
  ASSERT_NO_FATAL_FAILURE(compare(path, kFrames, &loaded));
  EXPECT_EQ(loaded, kFrames - 2u);  // frame 4 has no image, frame 7 no transform
  // The cases happened: the order is the bag's, frame 2 has the inverted image, frame 4 none,
  // the infos' cx are as described.
  std::string error;
  auto streaming = BagSequence::open(path, BagTopics{}, &error);
  const std::vector<double> stamps = {200.0, 200.1, 200.2, 200.3, 200.4, 200.6, 200.5};
  for (size_t i = 0; i < stamps.size(); ++i) {
    StereoFrame f;
    if (i == 4) {
      EXPECT_FALSE(streaming->load(i, &f, &error));
      EXPECT_NE(error.find("no image on /stereo/left/image_rect_color with the same stamp"),
                std::string::npos)
          << error;
      continue;
    }
    ASSERT_TRUE(streaming->load(i, &f, &error)) << error;
    EXPECT_NEAR(f.timestamp_s, stamps[i], 1e-6) << i;
    EXPECT_EQ(f.camera.cx(), stamps[i] < 200.25 ? 159.5 : 170.0) << i;
    if (i == 2) {
      const StereoFrame rendered = renderFrame(
          scene, qvgaCamera(),
          sim::lookAt({-0.2 + 0.05 * 2, -0.2, 0.0}, {0.05, 0.1, 1.2}, -Eigen::Vector3d::UnitY()));
      cv::Mat inverted;
      cv::subtract(cv::Scalar::all(255), rendered.color, inverted);
      EXPECT_EQ(cv::norm(f.color, inverted, cv::NORM_INF), 0.0);
    }
  }
  fs::remove(path);

  // A sequence as the simulator writes it.
  const std::string written =
      testing::TempDir() + "stereo_fusion_streaming_written_" + std::to_string(::getpid()) + ".bag";
  {
    auto writer = StereoBagWriter::open(written, BagTopics{}, "left_optical", 1.0, &error);
    ASSERT_TRUE(writer) << error;
    for (int i = 0; i < 5; ++i)
      ASSERT_TRUE(writer->write(floorAndSphereFrame(i, 0.1 * i), 128.0f, &error)) << error;
    writer->close();
  }
  ASSERT_NO_FATAL_FAILURE(compare(written, 5, &loaded));
  EXPECT_EQ(loaded, 5u);
  fs::remove(written);
}

// load() reads the bag from several threads at once (a re-fusion reloads frames while the
// caller may read others): every thread gets the frames a single reader gets.
TEST(BagSequence, LoadsFromSeveralThreadsAtOnce) {
  const std::string path =
      testing::TempDir() + "stereo_fusion_threads_" + std::to_string(::getpid()) + ".bag";
  std::string error;
  {
    auto writer = StereoBagWriter::open(path, BagTopics{}, "left_optical", 1.0, &error);
    ASSERT_TRUE(writer) << error;
    for (int i = 0; i < 6; ++i)
      ASSERT_TRUE(writer->write(floorAndSphereFrame(i, 0.1 * i), 128.0f, &error)) << error;
    writer->close();
  }
  auto seq = BagSequence::open(path, BagTopics{}, &error);
  ASSERT_TRUE(seq) << error;
  std::vector<StereoFrame> alone(seq->size());
  for (size_t i = 0; i < seq->size(); ++i) ASSERT_TRUE(seq->load(i, &alone[i], &error)) << error;
  std::vector<int> mismatches(4, 0);
  std::vector<std::thread> threads;
  for (int t = 0; t < 4; ++t)
    threads.emplace_back([&, t] {
      for (int round = 0; round < 5; ++round)
        for (size_t k = 0; k < alone.size(); ++k) {
          const size_t i = (k + t) % alone.size();
          StereoFrame f;
          std::string why;
          if (!seq->load(i, &f, &why) ||
              cv::norm(f.disparity_px, alone[i].disparity_px, cv::NORM_INF) != 0.0 ||
              cv::norm(f.color, alone[i].color, cv::NORM_INF) != 0.0 ||
              f.timestamp_s != alone[i].timestamp_s)
            ++mismatches[t];
        }
    });
  for (auto& thread : threads) thread.join();
  EXPECT_EQ(mismatches, std::vector<int>(4, 0));
  fs::remove(path);
}
