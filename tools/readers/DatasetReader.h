#pragma once
// Reader for the dataset folder format of doc/dataset_format.md:
//   <seq>/calibration.yaml        width, height, fx, fy, cx, cy, baseline   (left rectified camera)
//   <seq>/poses.txt               per frame "timestamp tx ty tz qx qy qz qw" (T_world_camera, TUM
//   order) <seq>/disparity/NNNNNN.png    uint16, disparity = value / 256, 0 = invalid (KITTI); or
//   .pfm float32 <seq>/color/NNNNNN.png|.jpg   8-bit colour or grey rectified left image
//   <seq>/right/NNNNNN.png        optional rectified right image (disparity computed with SGBM
//                                 when disparity/ is absent)
//   <seq>/gt_mesh.ply             optional ground-truth surface (evaluation only)
// Frames pair by sorted file name with the lines of poses.txt in order.

#include <Eigen/Geometry>
#include <optional>
#include <string>
#include <vector>

#include "stereo_fusion/camera/StereoCamera.h"
#include "stereo_fusion/integration/StereoFrame.h"
#include "stereo_fusion/io/FrameSource.h"

namespace stereo_fusion {

/// Parameters of OpenCV's StereoSGBM used when a sequence has right/ images but no disparity/.
struct SgbmParams {
  int num_disparities = 128;  ///< multiple of 16
  int block_size = 5;         ///< odd
  int uniqueness_ratio = 10;
  int speckle_window_size = 100;
  int speckle_range = 2;
};

/// One frame's entry: pose and file paths (empty path = not present).
struct DatasetFrameInfo {
  size_t index = 0;
  double timestamp_s = 0.0;
  Eigen::Isometry3d T_world_camera = Eigen::Isometry3d::Identity();
  std::string disparity_path;
  std::string color_path;
  std::string right_path;
  /// Why the pose line cannot be used (not finite, not a unit quaternion), naming file and line;
  /// empty if it can. Such a frame is skipped by load(), not the whole sequence.
  std::string pose_error;
};

/// Reads a file of TUM pose lines "timestamp tx ty tz qx qy qz qw" (T_world_camera; blank lines
/// and '#' comments skipped) into `frames` (index, timestamp, pose; pose_error for a line whose
/// pose is unusable). False with "file:line: ..." on a malformed line or an unreadable file.
bool readTumPoses(const std::string& path, std::vector<DatasetFrameInfo>* frames,
                  std::string* error);

/// A validated dataset folder. open() checks calibration, poses and file lists up front and
/// fails with one message naming the file and line; load() reads one frame and fails (without
/// throwing) for a missing, unreadable or truncated image, so a caller can skip and count it.
class DatasetReader : public FrameSource {
 public:
  static std::optional<DatasetReader> open(const std::string& folder, std::string* error,
                                           const SgbmParams& sgbm = {});

  const std::string& folder() const { return folder_; }
  const StereoCamera& camera() const { return camera_; }
  size_t size() const override { return frames_.size(); }
  const DatasetFrameInfo& info(size_t i) const { return frames_[i]; }
  /// True when disparity must be computed from right/ images with SGBM.
  bool usesSgbm() const { return uses_sgbm_; }
  /// Path of gt_mesh.ply, or empty when the sequence has none.
  const std::string& groundTruthMeshPath() const { return gt_mesh_path_; }

  /// Loads frame `i`: disparity (CV_32FC1 pixels, invalid = 0), colour (RGB or grey), pose,
  /// camera. Returns false with a reason naming the file on any problem.
  bool load(size_t i, StereoFrame* frame, std::string* error) const override;

 private:
  std::string folder_;
  StereoCamera camera_;
  std::vector<DatasetFrameInfo> frames_;
  bool uses_sgbm_ = false;
  SgbmParams sgbm_;
  std::string gt_mesh_path_;
};

/// Reads a PFM image (float32, 1 channel "Pf" or 3 channels "PF", either endianness; rows are
/// stored bottom-up). Returns an empty Mat and a reason on error.
cv::Mat readPfm(const std::string& path, std::string* error);
/// Writes a single-channel float PFM (little-endian, bottom-up rows).
bool writePfm(const std::string& path, const cv::Mat& image, std::string* error);

}  // namespace stereo_fusion
