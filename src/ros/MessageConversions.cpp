#include "stereo_fusion/ros/MessageConversions.h"

#include <cv_bridge/cv_bridge.h>
#include <sensor_msgs/image_encodings.h>
#include <tf2_eigen/tf2_eigen.h>

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "stereo_fusion/trajectory/UnitQuaternion.h"

namespace stereo_fusion {

namespace enc = sensor_msgs::image_encodings;

namespace {

/// The colour image as the core takes it (RGB or grey); false with a message otherwise.
bool toColor(const sensor_msgs::Image& image, cv::Mat* color_out, std::string* error) {
  // cv_bridge trusts step and the data length: check them, or a short message is read past its end.
  const bool four_channels = image.encoding == enc::RGBA8 || image.encoding == enc::BGRA8;
  const size_t bytes_per_pixel = image.encoding == enc::MONO8 ? 1 : four_channels ? 4 : 3;
  if (size_t{image.step} < image.width * bytes_per_pixel ||
      image.data.size() < size_t{image.step} * image.height) {
    const bool known = image.encoding == enc::RGB8 || image.encoding == enc::BGR8 ||
                       four_channels || image.encoding == enc::MONO8;
    if (known) {
      *error = "image data is shorter than step × height";
      return false;
    }
  }
  cv::Mat color;
  try {
    if (image.encoding == enc::RGB8 || image.encoding == enc::BGR8 ||
        image.encoding == enc::RGBA8 || image.encoding == enc::BGRA8) {
      color = cv_bridge::toCvCopy(image, enc::RGB8)->image;
    } else if (image.encoding == enc::MONO8) {
      color = cv_bridge::toCvCopy(image, enc::MONO8)->image;
    } else {
      *error =
          "unsupported image encoding '" + image.encoding + "' (rgb8, bgr8, rgba8, bgra8, mono8)";
      return false;
    }
  } catch (const cv_bridge::Exception& e) {
    *error = std::string("image conversion failed: ") + e.what();
    return false;
  }
  *color_out = color;
  return true;
}

/// fx, fy, cx, cy of the rectified projection P (K when P is unset).
struct Intrinsics {
  double fx, fy, cx, cy;
};
Intrinsics intrinsicsOf(const sensor_msgs::CameraInfo& info) {
  const bool has_p = info.P[0] != 0.0;
  return {has_p ? info.P[0] : info.K[0], has_p ? info.P[5] : info.K[4],
          has_p ? info.P[2] : info.K[2], has_p ? info.P[6] : info.K[5]};
}

}  // namespace

bool toStereoFrame(const stereo_msgs::DisparityImage& disparity, const sensor_msgs::Image& image,
                   const sensor_msgs::CameraInfo& info, const Eigen::Isometry3d& T_world_camera,
                   StereoFrame* frame, std::string* error) {
  const sensor_msgs::Image& d = disparity.image;
  if (d.encoding != enc::TYPE_32FC1) {
    *error = "disparity encoding must be 32FC1, got '" + d.encoding + "'";
    return false;
  }
  // Rows of floats: a step that is no multiple of 4 cannot be one (OpenCV would throw on it).
  if (d.step % 4 != 0) {
    *error = "disparity step " + std::to_string(d.step) +
             " is not a multiple of 4 bytes (rows of 32-bit floats)";
    return false;
  }
  if (d.width == 0 || d.height == 0 || d.step < d.width * 4 ||
      d.data.size() < size_t{d.step} * d.height) {
    *error = "disparity image is empty or its data is shorter than step × height";
    return false;
  }
  if (!(std::isfinite(disparity.f) && disparity.f > 0) ||
      !(std::isfinite(disparity.T) && disparity.T > 0)) {
    *error = "DisparityImage needs f > 0 and T > 0 (got f = " + std::to_string(disparity.f) +
             ", T = " + std::to_string(disparity.T) + ")";
    return false;
  }
  const auto [fx, fy, cx, cy] = intrinsicsOf(info);
  if (std::abs(fx - disparity.f) > 0.01 * disparity.f) {
    *error = "CameraInfo fx = " + std::to_string(fx) +
             " disagrees with DisparityImage f = " + std::to_string(disparity.f);
    return false;
  }
  std::string why;
  auto camera = StereoCamera::create(static_cast<int>(d.width), static_cast<int>(d.height), fx, fy,
                                     cx, cy, disparity.T, &why);
  if (!camera) {
    *error = why;
    return false;
  }
  if (info.width != 0 && (info.width != d.width || info.height != d.height)) {
    *error = "CameraInfo is " + std::to_string(info.width) + "x" + std::to_string(info.height) +
             " but the disparity is " + std::to_string(d.width) + "x" + std::to_string(d.height);
    return false;
  }
  if (image.width != d.width || image.height != d.height) {
    *error = "image is " + std::to_string(image.width) + "x" + std::to_string(image.height) +
             " but the disparity is " + std::to_string(d.width) + "x" + std::to_string(d.height);
    return false;
  }
  cv::Mat color;
  if (!toColor(image, &color, error)) return false;
  // cv_bridge does not reorder bytes (a big-endian 32FC1 comes back as 8UC4): swap them here.
  constexpr bool kHostBigEndian = __BYTE_ORDER__ == __ORDER_BIG_ENDIAN__;
  sensor_msgs::Image host_order;
  const sensor_msgs::Image* disparity_image = &d;
  if (static_cast<bool>(d.is_bigendian) != kHostBigEndian) {
    host_order = d;
    host_order.is_bigendian = kHostBigEndian;
    for (size_t row = 0; row < d.height; ++row)
      for (size_t k = 0; k < size_t{d.width}; ++k) {
        uint8_t* value = host_order.data.data() + row * d.step + 4 * k;
        std::reverse(value, value + 4);
      }
    disparity_image = &host_order;
  }
  cv::Mat disparity_px;
  try {
    disparity_px = cv_bridge::toCvCopy(*disparity_image, enc::TYPE_32FC1)->image;
  } catch (const cv_bridge::Exception& e) {
    *error = std::string("disparity conversion failed: ") + e.what();
    return false;
  }
  // The message's own range of valid disparities: values outside it are not measurements. A
  // max_disparity of 0 or less means the producer gave no upper bound.
  if (!std::isfinite(disparity.min_disparity) || !std::isfinite(disparity.max_disparity) ||
      (disparity.max_disparity > 0.0f && disparity.max_disparity < disparity.min_disparity)) {
    *error = "DisparityImage min_disparity = " + std::to_string(disparity.min_disparity) +
             ", max_disparity = " + std::to_string(disparity.max_disparity) + " is not a range";
    return false;
  }
  const float min_valid = std::max(0.0f, disparity.min_disparity);
  const float max_valid = disparity.max_disparity > 0.0f ? disparity.max_disparity : INFINITY;
  for (int v = 0; v < disparity_px.rows; ++v) {
    float* row = disparity_px.ptr<float>(v);
    for (int u = 0; u < disparity_px.cols; ++u)
      if (!(row[u] > 0.0f && row[u] >= min_valid && row[u] <= max_valid))
        row[u] = 0.0f;  // NaN fails too
  }
  frame->timestamp_s = disparity.header.stamp.toSec();
  frame->camera = *camera;
  frame->disparity_step_px = disparity.delta_d;  // validateFrame() checks its range
  frame->disparity_px = disparity_px;
  frame->color = color;
  frame->T_world_camera = T_world_camera;
  return true;
}

bool depthToStereoFrame(const sensor_msgs::Image& depth, const sensor_msgs::Image& image,
                        const sensor_msgs::CameraInfo& info, const DepthToDisparity& converter,
                        const Eigen::Isometry3d& T_world_camera, StereoFrame* frame,
                        std::string* error) {
  const auto [fx, fy, cx, cy] = intrinsicsOf(info);
  std::string why;
  auto camera = StereoCamera::create(static_cast<int>(depth.width), static_cast<int>(depth.height),
                                     fx, fy, cx, cy, converter.baselineM(), &why);
  if (!camera) {
    *error = "depth camera: " + why;
    return false;
  }
  if (info.width != 0 && (info.width != depth.width || info.height != depth.height)) {
    *error = "CameraInfo is " + std::to_string(info.width) + "x" + std::to_string(info.height) +
             " but the depth image is " + std::to_string(depth.width) + "x" +
             std::to_string(depth.height);
    return false;
  }
  // The core has one camera for both images: the depth must be registered to the colour image.
  if (image.width != depth.width || image.height != depth.height) {
    *error = "image is " + std::to_string(image.width) + "x" + std::to_string(image.height) +
             " but the depth image is " + std::to_string(depth.width) + "x" +
             std::to_string(depth.height) + " (the depth must be registered to the colour image)";
    return false;
  }
  DepthImageView view;
  view.encoding = depth.encoding;
  view.width = static_cast<int>(depth.width);
  view.height = static_cast<int>(depth.height);
  view.step_bytes = depth.step;
  view.big_endian = depth.is_bigendian != 0;
  view.data = depth.data.data();
  view.size_bytes = depth.data.size();
  cv::Mat disparity_px;
  if (!converter.convert(view, fx, &disparity_px, error)) return false;
  cv::Mat color;
  if (!toColor(image, &color, error)) return false;
  frame->timestamp_s = depth.header.stamp.toSec();
  frame->camera = *camera;
  frame->disparity_step_px = 0.0;  // the depth's rounding maps to no fixed disparity step
  frame->disparity_px = disparity_px;
  frame->color = color;
  frame->T_world_camera = T_world_camera;
  return true;
}

bool toCameraPoses(const nav_msgs::Path& path, const Eigen::Isometry3d& T_trajectory_camera,
                   std::vector<StampedPose>* poses, std::string* why) {
  std::vector<StampedPose> out;
  out.reserve(path.poses.size());
  for (size_t k = 0; k < path.poses.size(); ++k) {
    const geometry_msgs::Pose& p = path.poses[k].pose;
    std::string bad_rotation;
    const std::optional<Eigen::Quaterniond> q = unitQuaternion(
        p.orientation.x, p.orientation.y, p.orientation.z, p.orientation.w, &bad_rotation);
    const Eigen::Vector3d t(p.position.x, p.position.y, p.position.z);
    const double stamp_s = path.poses[k].header.stamp.toSec();
    if (!q || !t.allFinite() || !std::isfinite(stamp_s)) {
      *why = "pose " + std::to_string(k) + " of " + std::to_string(path.poses.size()) + ": " +
             (q ? "its position is not finite" : bad_rotation) + " (the whole path is refused)";
      return false;
    }
    Eigen::Isometry3d T_world_trajectory = Eigen::Isometry3d::Identity();
    T_world_trajectory.linear() = q->toRotationMatrix();
    T_world_trajectory.translation() = t;
    out.push_back({stamp_s, T_world_trajectory * T_trajectory_camera});
  }
  *poses = std::move(out);
  return true;
}

void toMessages(const StereoFrame& frame, const std_msgs::Header& header, float max_disparity_px,
                stereo_msgs::DisparityImage* disparity, sensor_msgs::Image* image,
                sensor_msgs::CameraInfo* info) {
  const StereoCamera& cam = frame.camera;
  disparity->header = header;
  disparity->image = *cv_bridge::CvImage(header, enc::TYPE_32FC1, frame.disparity_px).toImageMsg();
  disparity->f = static_cast<float>(cam.fx());
  disparity->T = static_cast<float>(cam.baseline());
  disparity->min_disparity = 0.0f;
  disparity->max_disparity = max_disparity_px;
  disparity->delta_d = 1.0f / 16.0f;  // SGBM's sub-pixel step
  disparity->valid_window.width = cam.width();
  disparity->valid_window.height = cam.height();
  const std::string encoding = frame.color.channels() == 1 ? enc::MONO8 : enc::RGB8;
  *image = *cv_bridge::CvImage(header, encoding, frame.color).toImageMsg();
  info->header = header;
  info->width = cam.width();
  info->height = cam.height();
  info->distortion_model = "plumb_bob";
  info->D.assign(5, 0.0);  // rectified
  info->K = {cam.fx(), 0, cam.cx(), 0, cam.fy(), cam.cy(), 0, 0, 1};
  info->R = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  info->P = {cam.fx(), 0, cam.cx(), 0, 0, cam.fy(), cam.cy(), 0, 0, 0, 1, 0};
}

geometry_msgs::TransformStamped toTransform(const Eigen::Isometry3d& T_world_camera,
                                            const std::string& world_frame,
                                            const std_msgs::Header& camera_header) {
  geometry_msgs::TransformStamped t = tf2::eigenToTransform(T_world_camera);
  t.header.stamp = camera_header.stamp;
  t.header.frame_id = world_frame;
  t.child_frame_id = camera_header.frame_id;
  return t;
}

bool stampAheadOfClock(const ros::Time& stamp, const ros::Time& now, double max_ahead_s) {
  return max_ahead_s > 0.0 && !now.isZero() && stamp.toSec() - now.toSec() > max_ahead_s;
}

}  // namespace stereo_fusion
