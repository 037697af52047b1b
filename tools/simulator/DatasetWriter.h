#pragma once
// Writes a sequence in the dataset folder format that DatasetReader reads (doc/dataset_format.md):
//   calibration.yaml, poses.txt, disparity/NNNNNN.png, color/NNNNNN.png, right/NNNNNN.png,
//   gt_mesh.ply.

#include <Eigen/Geometry>
#include <fstream>
#include <memory>
#include <opencv2/core/mat.hpp>
#include <string>

#include "stereo_fusion/camera/StereoCamera.h"

namespace stereo_fusion {
struct TriangleMesh;
}

namespace stereo_fusion::sim {

/// Disparity (CV_32FC1, pixels) → KITTI uint16 (CV_16UC1): round(d·256); 0 where the
/// disparity is invalid (not finite, <= 0) or too large to encode (round(d·256) > 65535).
cv::Mat encodeDisparityPng(const cv::Mat& disparity_px);

/// Shortest decimal text that parses back to exactly `value` ("0.1", not "0.10000000000000001").
std::string exactDecimal(double value);

/// Six-digit zero-padded frame file stem: 7 → "000007".
std::string frameStem(size_t index);

/// Writes one dataset folder. Frames must be added in index order 0, 1, 2, ...; each frame's
/// pose line is flushed as soon as its images are written, so an interrupted run still leaves
/// a readable sequence of the frames written so far.
class DatasetWriter {
 public:
  /// Creates `folder` (and its subfolders) and writes calibration.yaml. A folder that already
  /// holds a dataset (calibration.yaml present) is reused: its frame images, poses and mesh
  /// are removed first, so no stale frame outlives a shorter new run. A non-empty folder that
  /// is not a dataset is refused, to never delete anyone's files. nullptr + reason on failure.
  static std::unique_ptr<DatasetWriter> create(const std::string& folder,
                                               const StereoCamera& camera, std::string* error);

  /// Writes frame `index` (must be the next one): disparity (CV_32FC1 pixels, 0 invalid),
  /// left and right colour images (CV_8UC3 RGB; right may be empty to skip it), and appends
  /// "timestamp tx ty tz qx qy qz qw" (T_world_camera) to poses.txt.
  bool writeFrame(size_t index, double timestamp_s, const Eigen::Isometry3d& T_world_camera,
                  const cv::Mat& disparity_px, const cv::Mat& left_rgb, const cv::Mat& right_rgb,
                  std::string* error);

  /// Writes gt_mesh.ply.
  bool writeGroundTruthMesh(const TriangleMesh& mesh, std::string* error);

  /// The dataset folder being written.
  const std::string& folder() const { return folder_; }
  /// Number of frames written so far (the index the next frame must have).
  size_t framesWritten() const { return frames_written_; }

 private:
  DatasetWriter() = default;
  std::string folder_;
  StereoCamera camera_;
  std::ofstream poses_;
  size_t frames_written_ = 0;
};

}  // namespace stereo_fusion::sim
