// The nodelet's inputs besides raw disparity + image (rostest, the real nodelet under a real
// master): the colour image through image_transport's `compressed` transport
// (compressed_input.test) fuses exactly as the raw image does; a depth camera's registered depth
// image (depth_input.test, input: depth), 16UC1 in mm and 32FC1 in m, puts an analytic plane
// where it is, raw and through the compressedDepth transport (depth_compressed_input.test), and a
// depth image of a wrong encoding is dropped, counted and changes nothing; an image that arrives
// compressed and does not decode drops its frame as `undecodable image`; in depth mode the
// diagnostics name depth images, not disparities.
#include <nodelet/loader.h>
#include <rosgraph_msgs/Log.h>
#include <sensor_msgs/CompressedImage.h>
#include <stereo_fusion/GetFullMesh.h>
#include <tf2_ros/transform_broadcaster.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <mutex>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "../unit/TestSupport.h"
#include "RosTestSupport.h"
#include "stereo_fusion/Mapper.h"
#include "stereo_fusion/ros/FusionNodelet.h"
#include "stereo_fusion/ros/MeshMessages.h"
#include "stereo_fusion/ros/RosParameters.h"

using namespace stereo_fusion;

namespace {

StereoCamera qvga() { return *StereoCamera::create(320, 240, 262.5, 262.5, 159.5, 119.5, 0.1); }

/// The frame's colour image as image_transport_plugins' publisher sends an rgb8 image: BGR bytes
/// into PNG. Empty data when the encoding fails.
sensor_msgs::CompressedImage compressedPng(const StereoFrame& frame,
                                           const std_msgs::Header& header) {
  sensor_msgs::CompressedImage compressed;
  compressed.header = header;
  compressed.format = "rgb8; png compressed bgr8";
  cv::Mat bgr;
  cv::cvtColor(frame.color, bgr, cv::COLOR_RGB2BGR);
  if (!cv::imencode(".png", bgr, compressed.data)) compressed.data.clear();
  return compressed;
}

using SubmeshMap = std::unordered_map<BlockKey, SubMesh, BlockKeyHash>;

bool fullMesh(SubmeshMap* mesh) {
  GetFullMesh full;
  if (!ros::service::call("/stereo_fusion/get_full_mesh", full)) return false;
  mesh->clear();
  return applyMeshUpdate(full.response.mesh, mesh);
}

// ---------------------------------------------------------------------------------------------
// compressed_input.test: image_transport: compressed.

TEST(CompressedImages, FuseExactlyAsTheRawImagesWould) {
  ros::NodeHandle nh;
  ros::Publisher disparity_pub = nh.advertise<stereo_msgs::DisparityImage>("/stereo/disparity", 10);
  ros::Publisher raw_pub = nh.advertise<sensor_msgs::Image>("/stereo/left/image_rect_color", 10);
  ros::Publisher compressed_pub =
      nh.advertise<sensor_msgs::CompressedImage>("/stereo/left/image_rect_color/compressed", 10);
  ros::Publisher info_pub = nh.advertise<sensor_msgs::CameraInfo>("/stereo/left/camera_info", 10);
  tf2_ros::TransformBroadcaster tf;
  test::DiagnosticsWatcher diagnostics;
  ASSERT_TRUE(test::waitFor(
      [&] {
        return disparity_pub.getNumSubscribers() > 0 && compressed_pub.getNumSubscribers() > 0 &&
               info_pub.getNumSubscribers() > 0;
      },
      30.0))
      << "the nodelet did not subscribe to the compressed image";
  ASSERT_TRUE(test::waitForTfSubscriber(30.0));
  ASSERT_TRUE(diagnostics.waitForNextReport(30.0));
  // Through the transport only: nothing listens to the raw topic.
  EXPECT_EQ(raw_pub.getNumSubscribers(), 0u);

  sim::AnalyticScene scene;
  scene.add(sim::makePlane({0, 0.3, 0}, {0, -1, 0}), {180, 160, 120});
  scene.add(sim::makeSphere({0.05, 0.1, 1.2}, 0.2), {200, 60, 60});
  std::vector<StereoFrame> reference;  // each frame as the raw messages would have given it
  constexpr int kFrames = 4;
  for (int f = 0; f < kFrames; ++f) {
    const auto pose =
        sim::lookAt({-0.15 + 0.1 * f, -0.2, 0.0}, {0.05, 0.1, 1.2}, -Eigen::Vector3d::UnitY());
    StereoFrame frame = test::renderFrame(scene, qvga(), pose);
    // Texture the colour so that a channel swap or a shifted row would show in the vertices.
    for (int v = 0; v < frame.color.rows; ++v)
      for (int u = 0; u < frame.color.cols; ++u)
        frame.color.at<cv::Vec3b>(v, u) += cv::Vec3b(u % 7 * 5, v % 5 * 9, (u + v) % 11 * 3);
    test::FrameMessages m = test::frameMessages(frame, &tf);
    ASSERT_EQ(m.image.encoding, "rgb8");
    StereoFrame as_raw;
    std::string error;
    ASSERT_TRUE(toStereoFrame(m.disparity, m.image, m.info, frame.T_world_camera, &as_raw, &error))
        << error;
    reference.push_back(as_raw);
    sensor_msgs::CompressedImage compressed = compressedPng(frame, m.header);
    ASSERT_FALSE(compressed.data.empty());
    ros::WallDuration(0.05).sleep();  // tf first
    disparity_pub.publish(m.disparity);
    compressed_pub.publish(compressed);
    info_pub.publish(m.info);
  }
  ASSERT_TRUE(test::waitFor([&] { return diagnostics.value("frames fused") >= kFrames; }, 60.0))
      << "fused " << diagnostics.value("frames fused") << " of " << kFrames;
  EXPECT_EQ(diagnostics.droppedTotal(), 0);

  MapperConfig config;
  NodeConfig node;
  std::string error;
  ASSERT_TRUE(loadParameters(ros::NodeHandle("/stereo_fusion"), &config, &node, &error)) << error;
  ASSERT_EQ(node.image_transport, "compressed");
  Mapper raw(config);
  for (const StereoFrame& f : reference) ASSERT_TRUE(raw.integrate(f).accepted);
  SubmeshMap live;
  ASSERT_TRUE(fullMesh(&live));
  ASSERT_GT(raw.mesh().submeshes().size(), 10u);
  // Same geometry and, PNG being lossless, the same vertex colours.
  test::expectSameSubmeshes(live, raw.mesh().submeshes(), test::kWithColors);
}

/// Collects what the nodes log on /rosout at `level` or above.
class RosoutWatcher {
 public:
  explicit RosoutWatcher(uint8_t level) : level_(level) {
    sub_ = ros::NodeHandle().subscribe("/rosout", 100, &RosoutWatcher::onLog, this);
  }
  ~RosoutWatcher() { sub_.shutdown(); }
  /// The first message logged so far that contains `part` ("" if none).
  std::string find(const std::string& part) {
    std::lock_guard<std::mutex> lock(mutex_);
    for (const std::string& m : messages_)
      if (m.find(part) != std::string::npos) return m;
    return "";
  }

 private:
  void onLog(const rosgraph_msgs::Log::ConstPtr& log) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (log->level >= level_) messages_.push_back(log->msg);
  }
  uint8_t level_;
  ros::Subscriber sub_;
  std::mutex mutex_;
  std::vector<std::string> messages_;
};

// An image that arrives compressed and does not decode drops its frame under that reason, not
// as "not synchronised" (its disparity is never matched), is logged with why, and the next
// frame is fused as usual.
TEST(CompressedImages, AnUndecodableImageIsCountedAsUndecodableNotUnsynchronised) {
  ros::NodeHandle nh;
  ros::Publisher disparity_pub = nh.advertise<stereo_msgs::DisparityImage>("/stereo/disparity", 10);
  ros::Publisher compressed_pub =
      nh.advertise<sensor_msgs::CompressedImage>("/stereo/left/image_rect_color/compressed", 10);
  ros::Publisher info_pub = nh.advertise<sensor_msgs::CameraInfo>("/stereo/left/camera_info", 10);
  tf2_ros::TransformBroadcaster tf;
  test::DiagnosticsWatcher diagnostics;
  RosoutWatcher rosout(rosgraph_msgs::Log::WARN);
  ASSERT_TRUE(test::waitFor(
      [&] {
        return disparity_pub.getNumSubscribers() > 0 && compressed_pub.getNumSubscribers() > 0 &&
               info_pub.getNumSubscribers() > 0;
      },
      30.0));
  ASSERT_TRUE(test::waitForTfSubscriber(30.0));
  ASSERT_TRUE(diagnostics.waitForNextReport(30.0));
  const std::string kUndecodable = "dropped: undecodable image";
  const std::string kUnsynchronised =
      "dropped: not synchronised (no matching image / camera_info yet)";
  const long fused_before = diagnostics.value("frames fused");
  const long undecodable_before = diagnostics.value(kUndecodable);
  const long unsynchronised_before = diagnostics.value(kUnsynchronised);
  const long dropped_before = diagnostics.droppedTotal();
  ASSERT_GE(fused_before, 0);
  ASSERT_EQ(undecodable_before, 0) << "the reason is reported, at 0 before any such image";
  ASSERT_GE(unsynchronised_before, 0);

  sim::AnalyticScene scene;
  scene.add(sim::makePlane({0, 0.3, 0}, {0, -1, 0}), {180, 160, 120});
  const auto publish = [&](double x, bool corrupt) {
    const auto pose = sim::lookAt({x, -0.2, 0.0}, {0.0, 0.3, 1.2}, -Eigen::Vector3d::UnitY());
    const StereoFrame frame = test::renderFrame(scene, qvga(), pose);
    test::FrameMessages m = test::frameMessages(frame, &tf);
    sensor_msgs::CompressedImage compressed = compressedPng(frame, m.header);
    ASSERT_FALSE(compressed.data.empty());
    if (corrupt) compressed.data.assign(4096, 0xab);  // not a PNG: the decoder refuses it
    ros::WallDuration(0.05).sleep();                  // tf first
    disparity_pub.publish(m.disparity);
    compressed_pub.publish(compressed);
    info_pub.publish(m.info);
    ros::WallDuration(0.2).sleep();
  };
  publish(0.0, true);
  publish(0.1, false);
  ASSERT_TRUE(test::waitFor(
      [&] {
        return diagnostics.value(kUndecodable) == 1 &&
               diagnostics.value("frames fused") == fused_before + 1;
      },
      30.0))
      << kUndecodable << " " << diagnostics.value(kUndecodable) << ", frames fused "
      << diagnostics.value("frames fused") << " (before " << fused_before << ")";
  // The disparity of the dropped frame waits for an image that never comes: counted once, under
  // the image's reason, in every report from now on.
  ASSERT_TRUE(diagnostics.waitForNextReport(5.0));
  ASSERT_TRUE(diagnostics.waitForNextReport(5.0));
  EXPECT_EQ(diagnostics.value(kUnsynchronised), unsynchronised_before);
  EXPECT_EQ(diagnostics.value(kUndecodable), 1);
  EXPECT_EQ(diagnostics.droppedTotal(), dropped_before + 1);
  // Logged: the reason, the topic and why.
  ASSERT_TRUE(test::waitFor([&] { return !rosout.find("undecodable_image").empty(); }, 10.0))
      << "no warning names the drop's reason";
  const std::string warning = rosout.find("undecodable_image");
  EXPECT_NE(warning.find("/stereo/left/image_rect_color/compressed"), std::string::npos) << warning;
  EXPECT_NE(warning.find("does not decode"), std::string::npos) << warning;
}

// A transport no plugin provides stops the nodelet at start-up, the message naming it and the
// transports that can be loaded (ours among them).
TEST(ImageTransport, AnUnknownTransportStopsTheStartAndNamesTheLoadableOnes) {
  const std::string ns = "/unknown_transport/stereo_fusion";
  ros::param::set(ns + "/image_transport", std::string("no_such_transport"));
  // The manager logs what onInit() threw: this process's own /rosout carries the FATAL line.
  std::mutex mutex;
  std::string fatal;
  ros::Subscriber rosout = ros::NodeHandle().subscribe<rosgraph_msgs::Log>(
      "/rosout", 100, [&](const rosgraph_msgs::Log::ConstPtr& log) {
        std::lock_guard<std::mutex> lock(mutex);
        if (log->level == rosgraph_msgs::Log::FATAL &&
            log->msg.find("no_such_transport") != std::string::npos)
          fatal = log->msg;
      });
  ros::WallDuration(0.5).sleep();  // the subscription connects
  const boost::function<boost::shared_ptr<nodelet::Nodelet>(const std::string&)> create =
      [](const std::string&) { return boost::make_shared<FusionNodelet>(); };
  nodelet::Loader loader(create);
  bool loaded = false;
  try {
    loaded = loader.load(ns, "stereo_fusion/FusionNodelet", {}, {});
  } catch (const std::exception&) {  // the manager reports it either way
  }
  if (loaded) loader.unload(ns);
  EXPECT_FALSE(loaded) << "the nodelet started with an image transport that does not exist";
  ASSERT_TRUE(test::waitFor(
      [&] {
        std::lock_guard<std::mutex> lock(mutex);
        return !fatal.empty();
      },
      10.0))
      << "no FATAL naming the transport";
  std::lock_guard<std::mutex> lock(mutex);
  EXPECT_NE(fatal.find("image_transport 'no_such_transport'"), std::string::npos) << fatal;
  EXPECT_NE(fatal.find("loadable here: "), std::string::npos) << fatal;
  EXPECT_NE(fatal.find("compressed"), std::string::npos) << fatal;  // ours
  EXPECT_NE(fatal.find("raw"), std::string::npos) << fatal;
  rosout.shutdown();
  ros::param::del("/unknown_transport");
}

// ---------------------------------------------------------------------------------------------
// depth_input.test: input: depth, depth_baseline_m 0.075.

/// A plane n·p = c in the world; the cameras look along world +z (identity rotation).
const Eigen::Vector3d kNormal = Eigen::Vector3d(0.2, -0.3, 1.0).normalized();
const double kOffset = 1.5 * kNormal.z();  // through (0, 0, 1.5)

/// The depth (m) pixel (u, v) of `camera` at `position` measures on the plane.
double planeDepth(const StereoCamera& camera, const Eigen::Vector3d& position, int u, int v) {
  const Eigen::Vector3d ray((u - camera.cx()) / camera.fx(), (v - camera.cy()) / camera.fy(), 1.0);
  return (kOffset - kNormal.dot(position)) / kNormal.dot(ray);
}

class DepthInput : public testing::Test {
 protected:
  void SetUp() override {
    ros::NodeHandle nh;
    compressed_ = ros::param::param<std::string>("/stereo_fusion/depth_image_transport", "raw") ==
                  "compressedDepth";
    const std::string depth_topic = "/camera/aligned_depth_to_color/image_raw";
    if (compressed_)
      depth_pub_ = nh.advertise<sensor_msgs::CompressedImage>(depth_topic + "/compressedDepth", 10);
    else
      depth_pub_ = nh.advertise<sensor_msgs::Image>(depth_topic, 10);
    image_compressed_ =
        ros::param::param<std::string>("/stereo_fusion/image_transport", "raw") == "compressed";
    if (image_compressed_)
      image_pub_ =
          nh.advertise<sensor_msgs::CompressedImage>("/camera/color/image_raw/compressed", 10);
    else
      image_pub_ = nh.advertise<sensor_msgs::Image>("/camera/color/image_raw", 10);
    info_pub_ = nh.advertise<sensor_msgs::CameraInfo>("/camera/color/camera_info", 10);
    ASSERT_TRUE(test::waitFor(
        [&] {
          return depth_pub_.getNumSubscribers() > 0 && image_pub_.getNumSubscribers() > 0 &&
                 info_pub_.getNumSubscribers() > 0;
        },
        30.0))
        << "the nodelet did not subscribe to the depth camera's topics";
    ASSERT_TRUE(test::waitForTfSubscriber(30.0));
    ASSERT_TRUE(diagnostics_.waitForNextReport(30.0));
  }

  /// Publishes one frame at `position`: depth of `encoding` (16UC1 mm or 32FC1 m) with the
  /// 12 left columns unmeasured (0 / NaN), a grey rgb8 image and the camera's CameraInfo.
  void publish(const Eigen::Vector3d& position, const std::string& encoding) {
    const StereoCamera camera = qvga();
    std_msgs::Header header;
    header.stamp = ros::Time::now();
    header.frame_id = "depth_optical";
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.translation() = position;
    tf_.sendTransform(toTransform(pose, "map", header));
    sensor_msgs::Image depth;
    depth.header = header;
    depth.width = camera.width();
    depth.height = camera.height();
    depth.encoding = encoding;
    depth.is_bigendian = false;
    const bool mm = encoding == "16UC1";
    depth.step = depth.width * (mm ? 2 : 4);
    depth.data.resize(size_t{depth.step} * depth.height);
    for (int v = 0; v < camera.height(); ++v)
      for (int u = 0; u < camera.width(); ++u) {
        const double z = planeDepth(camera, position, u, v);
        uint8_t* at = depth.data.data() + v * depth.step + u * (mm ? 2 : 4);
        if (mm) {
          const uint16_t value = u < 12 ? 0 : static_cast<uint16_t>(std::lround(z * 1000.0));
          std::memcpy(at, &value, 2);
        } else {
          const float value =
              u < 12 ? std::numeric_limits<float>::quiet_NaN() : static_cast<float>(z);
          std::memcpy(at, &value, 4);
        }
      }
    sensor_msgs::Image image;
    image.header = header;
    image.width = depth.width;
    image.height = depth.height;
    image.encoding = "rgb8";
    image.step = image.width * 3;
    image.data.assign(size_t{image.step} * image.height, 128);
    sensor_msgs::CameraInfo info;
    info.header = header;
    info.width = depth.width;
    info.height = depth.height;
    info.K = {camera.fx(), 0, camera.cx(), 0, camera.fy(), camera.cy(), 0, 0, 1};
    info.P = {camera.fx(), 0, camera.cx(), 0, 0, camera.fy(), camera.cy(), 0, 0, 0, 1, 0};
    ros::WallDuration(0.05).sleep();  // tf first
    if (compressed_ && cut_depth_png_) {
      sensor_msgs::CompressedImage cut = compressedDepth(depth);
      cut.data.resize(12 + 40);  // the header and the PNG's first bytes only
      depth_pub_.publish(cut);
    } else if (compressed_) {
      depth_pub_.publish(compressedDepth(depth));
    } else {
      depth_pub_.publish(depth);
    }
    if (image_compressed_) {
      sensor_msgs::CompressedImage jpeg;
      jpeg.header = header;
      jpeg.format = "rgb8; jpeg compressed bgr8";
      EXPECT_TRUE(cv::imencode(
          ".jpg", cv::Mat(image.height, image.width, CV_8UC3, image.data.data()), jpeg.data));
      image_pub_.publish(jpeg);
    } else {
      image_pub_.publish(image);
    }
    info_pub_.publish(info);
  }

  /// `depth` as compressed_depth_image_transport publishes it: {int32 format, float a, float b}
  /// then a 16-bit PNG; 16UC1 as it is, 32FC1 as quantised inverse depth q = a/z + b (0: none),
  /// with its defaults depth_quantization 100 and depth_max 10 m.
  static sensor_msgs::CompressedImage compressedDepth(const sensor_msgs::Image& depth) {
    sensor_msgs::CompressedImage out;
    out.header = depth.header;
    out.format = depth.encoding + "; compressedDepth png";
    const float a = 100.0f * 101.0f, b = 1.0f - a / 10.0f;
    cv::Mat png(depth.height, depth.width, CV_16UC1);
    for (int v = 0; v < png.rows; ++v)
      for (int u = 0; u < png.cols; ++u) {
        const uint8_t* at = depth.data.data() + v * depth.step;
        if (depth.encoding == "16UC1") {
          std::memcpy(&png.at<uint16_t>(v, u), at + 2 * u, 2);
        } else {
          float z;
          std::memcpy(&z, at + 4 * u, 4);
          png.at<uint16_t>(v, u) =
              std::isfinite(z) && z > 0 ? static_cast<uint16_t>(std::lround(a / z + b)) : 0;
        }
      }
    std::vector<uint8_t> bytes;
    EXPECT_TRUE(cv::imencode(".png", png, bytes));
    out.data.resize(12);
    const int32_t inverse_depth = 0;
    std::memcpy(out.data.data(), &inverse_depth, 4);
    std::memcpy(out.data.data() + 4, &a, 4);
    std::memcpy(out.data.data() + 8, &b, 4);
    out.data.insert(out.data.end(), bytes.begin(), bytes.end());
    return out;
  }

  bool compressed_ = false, image_compressed_ = false;
  bool cut_depth_png_ = false;  ///< publish() sends a compressedDepth message that does not decode
  ros::Publisher depth_pub_, image_pub_, info_pub_;
  tf2_ros::TransformBroadcaster tf_;
  test::DiagnosticsWatcher diagnostics_;
  std::vector<Eigen::Vector3d> positions_{{0, 0, 0},        {0.05, 0, 0},      {0, 0.05, 0.02},
                                          {-0.05, 0, 0.04}, {0, -0.05, -0.02}, {0.03, 0.03, 0}};

  /// Publishes the frames, 16UC1 and 32FC1 alternating, waits for them to be fused, and checks
  /// that the fused surface is the plane; the mesh goes to `mesh`.
  void fusePlane(SubmeshMap* mesh) {
    const long fused_before = diagnostics_.value("frames fused");  // SetUp saw a report
    ASSERT_GE(fused_before, 0);
    for (size_t k = 0; k < positions_.size(); ++k)
      publish(positions_[k], k % 2 == 0 ? "16UC1" : "32FC1");
    const long frames = static_cast<long>(positions_.size()) + fused_before;
    ASSERT_TRUE(test::waitFor([&] { return diagnostics_.value("frames fused") >= frames; }, 60.0))
        << "fused " << diagnostics_.value("frames fused") << " of " << frames;
    EXPECT_EQ(diagnostics_.droppedTotal(), 0);

    ASSERT_TRUE(fullMesh(mesh));
    std::vector<double> off_m;
    double min_x = INFINITY, max_x = -INFINITY;
    for (const auto& [key, sub] : *mesh)
      for (const Eigen::Vector3f& p : sub.positions) {
        off_m.push_back(std::abs(kNormal.dot(p.cast<double>()) - kOffset));
        min_x = std::min(min_x, double{p.x()});
        max_x = std::max(max_x, double{p.x()});
      }
    ASSERT_GT(off_m.size(), 2000u);
    std::sort(off_m.begin(), off_m.end());
    // The plane is where the depth says: a wrong unit (mm as m) or a baseline the core reads
    // differently from the conversion would move or scale it by centimetres or more.
    EXPECT_LT(off_m[off_m.size() / 2], 0.002) << "median distance to the plane";
    EXPECT_LT(off_m.back(), 0.01) << "largest distance to the plane";
    // The view is 1.8 m wide at 1.5 m: the fused surface spans most of it.
    EXPECT_GT(max_x - min_x, 1.2);
  }
};

TEST_F(DepthInput, APlaneInMillimetresAndMetresIsFusedWhereItIs) {
  SubmeshMap mesh;
  fusePlane(&mesh);
}

// depth_compressed_input.test only: a compressedDepth message that does not decode (a PNG cut
// short) drops its frame as an undecodable image, counted as a depth image received, not as
// unsynchronised; the map stays and the next frame is fused.
TEST_F(DepthInput, AnUndecodableCompressedDepthImageIsCountedAsUndecodable) {
  ASSERT_TRUE(compressed_)
      << "run by depth_compressed_input.test (depth_image_transport: compressedDepth)";
  SubmeshMap mesh;
  ASSERT_NO_FATAL_FAILURE(fusePlane(&mesh));
  ASSERT_TRUE(diagnostics_.waitForNextReport(5.0));
  const long fused = diagnostics_.value("frames fused");
  const long received = diagnostics_.value("depth images received");
  const long dropped = diagnostics_.droppedTotal();
  ASSERT_GE(received, static_cast<long>(positions_.size()));
  cut_depth_png_ = true;
  publish({0.01, 0.01, 0}, "16UC1");
  cut_depth_png_ = false;
  ASSERT_TRUE(
      test::waitFor([&] { return diagnostics_.value("dropped: undecodable image") == 1; }, 30.0))
      << "dropped: undecodable image " << diagnostics_.value("dropped: undecodable image");
  ASSERT_TRUE(diagnostics_.waitForNextReport(5.0));
  ASSERT_TRUE(diagnostics_.waitForNextReport(5.0));
  EXPECT_EQ(diagnostics_.value("depth images received"), received + 1);
  EXPECT_EQ(diagnostics_.value("dropped: not synchronised (no matching image / camera_info yet)"),
            0);
  EXPECT_EQ(diagnostics_.droppedTotal(), dropped + 1);
  EXPECT_EQ(diagnostics_.value("frames fused"), fused);
  SubmeshMap after;
  ASSERT_TRUE(fullMesh(&after));
  test::expectSameSubmeshes(after, mesh, test::kWithColors);
  publish({0.02, 0.0, 0.01}, "32FC1");
  EXPECT_TRUE(test::waitFor([&] { return diagnostics_.value("frames fused") == fused + 1; }, 30.0))
      << "the frame after the undecodable one was not fused";
}

// depth_input.test: the input's counters are named after what it takes, depth images; no key
// speaks of disparities the node never received.
TEST_F(DepthInput, TheDiagnosticsKeysNameDepthImages) {
  SubmeshMap mesh;
  ASSERT_NO_FATAL_FAILURE(fusePlane(&mesh));
  ASSERT_TRUE(diagnostics_.waitForNextReport(5.0));
  EXPECT_GE(diagnostics_.value("depth images received"), static_cast<long>(positions_.size()));
  EXPECT_EQ(diagnostics_.value("depth images missed upstream (header.seq gaps)"), 0);
  EXPECT_GE(diagnostics_.value("depth image rate, window (Hz)"), 0)
      << "the window's rate of depth images is not reported";
  for (const char* key : {"disparities received", "disparities missed upstream (header.seq gaps)",
                          "disparity rate, window (Hz)"})
    EXPECT_EQ(diagnostics_.value(key), -1) << "'" << key << "' is reported in depth mode";
}

// depth_input.test only (raw depth: the compressedDepth transport refuses such a message itself).
TEST_F(DepthInput, ADepthImageOfAWrongEncodingIsDroppedAsBadInputAndTheMapStays) {
  SubmeshMap mesh;
  ASSERT_NO_FATAL_FAILURE(fusePlane(&mesh));
  const long fused = diagnostics_.value("frames fused");
  const long bad_before = diagnostics_.value("dropped: bad input");
  publish({0.01, 0.01, 0}, "rgb8");
  ASSERT_TRUE(test::waitFor(
      [&] { return diagnostics_.value("dropped: bad input") == bad_before + 1; }, 30.0))
      << "dropped: bad input " << diagnostics_.value("dropped: bad input");
  EXPECT_EQ(diagnostics_.value("frames fused"), fused);
  SubmeshMap after;
  ASSERT_TRUE(fullMesh(&after));
  test::expectSameSubmeshes(after, mesh, test::kWithColors);
}

}  // namespace

int main(int argc, char** argv) {
  return test::runRosTests(argc, argv, "stereo_fusion_inputs_test");
}
