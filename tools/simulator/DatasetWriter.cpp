#include "simulator/DatasetWriter.h"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <regex>

#include "stereo_fusion/io/PlyWriter.h"
#include "stereo_fusion/mesh/SubMesh.h"

namespace fs = std::filesystem;

namespace stereo_fusion::sim {

namespace {

const char* const kImageFolders[] = {"disparity", "color", "right"};

/// Fast PNG compression: the simulator writes three images per frame and size matters less.
const std::vector<int> kPngFlags = {cv::IMWRITE_PNG_COMPRESSION, 1};

bool writePng(const std::string& path, const cv::Mat& image, std::string* error) {
  try {
    if (cv::imwrite(path, image, kPngFlags)) return true;
  } catch (const cv::Exception& e) {
    *error = path + ": " + e.what();
    return false;
  }
  *error = path + ": cannot write PNG";
  return false;
}

/// Removes what an earlier run wrote into `folder` (frame images with six-digit names, poses,
/// calibration, mesh, the --drift and --dynamic files), nothing else.
bool clearOldDataset(const fs::path& folder, std::string* error) {
  static const std::regex kFrameName(R"(\d{6}\.(png|pfm|jpg|jpeg))");
  std::error_code ec;
  for (const char* name : {"poses.txt", "calibration.yaml", "gt_mesh.ply", "poses_true.txt",
                           "trajectory.txt", "dynamic.txt"})
    fs::remove(folder / name, ec);
  for (const char* sub : kImageFolders) {
    if (!fs::is_directory(folder / sub)) continue;
    for (const auto& entry : fs::directory_iterator(folder / sub, ec)) {
      if (entry.is_regular_file() && std::regex_match(entry.path().filename().string(), kFrameName))
        fs::remove(entry.path(), ec);
      if (ec) {
        *error = entry.path().string() + ": cannot remove old frame: " + ec.message();
        return false;
      }
    }
  }
  return true;
}

}  // namespace

cv::Mat encodeDisparityPng(const cv::Mat& disparity_px) {
  CV_Assert(disparity_px.type() == CV_32FC1);
  cv::Mat out(disparity_px.size(), CV_16UC1);
  for (int v = 0; v < disparity_px.rows; ++v) {
    const float* in = disparity_px.ptr<float>(v);
    uint16_t* o = out.ptr<uint16_t>(v);
    for (int u = 0; u < disparity_px.cols; ++u) {
      const double scaled = std::isfinite(in[u]) && in[u] > 0 ? std::round(in[u] * 256.0) : 0.0;
      o[u] = scaled <= 65535.0 ? static_cast<uint16_t>(scaled) : 0;
    }
  }
  return out;
}

std::string exactDecimal(double value) {
  char buffer[64];
  const auto result = std::to_chars(buffer, buffer + sizeof(buffer), value);
  return std::string(buffer, result.ptr);
}

std::string frameStem(size_t index) {
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "%06zu", index);
  return buffer;
}

std::unique_ptr<DatasetWriter> DatasetWriter::create(const std::string& folder,
                                                     const StereoCamera& camera,
                                                     std::string* error) {
  if (!camera.valid()) {
    *error = "invalid camera";
    return nullptr;
  }
  const fs::path root(folder);
  std::error_code ec;
  if (fs::exists(root, ec)) {
    if (!fs::is_directory(root, ec)) {
      *error = folder + ": exists and is not a folder";
      return nullptr;
    }
    if (!fs::is_empty(root, ec)) {
      if (!fs::exists(root / "calibration.yaml")) {
        *error =
            folder +
            ": not empty and not a dataset folder (no calibration.yaml); refusing to write into it";
        return nullptr;
      }
      if (!clearOldDataset(root, error)) return nullptr;
    }
  }
  for (const char* sub : kImageFolders) {
    fs::create_directories(root / sub, ec);
    if (ec) {
      *error = (root / sub).string() + ": cannot create folder: " + ec.message();
      return nullptr;
    }
  }

  std::unique_ptr<DatasetWriter> writer(new DatasetWriter());
  writer->folder_ = folder;
  writer->camera_ = camera;
  const std::string calibration_path = (root / "calibration.yaml").string();
  std::ofstream calibration(calibration_path);
  calibration << "# Left rectified camera of the simulated stereo pair (pixels, metres).\n"
              << "width: " << camera.width() << "\n"
              << "height: " << camera.height() << "\n"
              << "fx: " << exactDecimal(camera.fx()) << "\n"
              << "fy: " << exactDecimal(camera.fy()) << "\n"
              << "cx: " << exactDecimal(camera.cx()) << "\n"
              << "cy: " << exactDecimal(camera.cy()) << "\n"
              << "baseline: " << exactDecimal(camera.baseline()) << "\n";
  calibration.close();
  if (!calibration) {
    *error = calibration_path + ": cannot write";
    return nullptr;
  }
  const std::string poses_path = (root / "poses.txt").string();
  writer->poses_.open(poses_path, std::ios::trunc);
  if (!writer->poses_) {
    *error = poses_path + ": cannot open for writing";
    return nullptr;
  }
  return writer;
}

bool DatasetWriter::writeFrame(size_t index, double timestamp_s,
                               const Eigen::Isometry3d& T_world_camera, const cv::Mat& disparity_px,
                               const cv::Mat& left_rgb, const cv::Mat& right_rgb,
                               std::string* error) {
  if (index != frames_written_) {
    *error = "frame " + std::to_string(index) + " written out of order (expected " +
             std::to_string(frames_written_) + ")";
    return false;
  }
  const cv::Size size(camera_.width(), camera_.height());
  if (disparity_px.type() != CV_32FC1 || disparity_px.size() != size ||
      left_rgb.type() != CV_8UC3 || left_rgb.size() != size ||
      (!right_rgb.empty() && (right_rgb.type() != CV_8UC3 || right_rgb.size() != size))) {
    *error = "frame " + std::to_string(index) + ": image type or size does not match the camera";
    return false;
  }
  const fs::path root(folder_);
  const std::string name = frameStem(index) + ".png";
  if (!writePng((root / "disparity" / name).string(), encodeDisparityPng(disparity_px), error))
    return false;
  // cv::imwrite expects BGR channel order.
  cv::Mat bgr;
  cv::cvtColor(left_rgb, bgr, cv::COLOR_RGB2BGR);
  if (!writePng((root / "color" / name).string(), bgr, error)) return false;
  if (!right_rgb.empty()) {
    cv::cvtColor(right_rgb, bgr, cv::COLOR_RGB2BGR);
    if (!writePng((root / "right" / name).string(), bgr, error)) return false;
  }

  // One sign for the quaternion (qw >= 0) so equal rotations give equal text.
  Eigen::Quaterniond q(T_world_camera.linear());
  q.normalize();
  if (q.w() < 0) q.coeffs() *= -1.0;
  const Eigen::Vector3d& t = T_world_camera.translation();
  poses_ << exactDecimal(timestamp_s) << ' ' << exactDecimal(t.x()) << ' ' << exactDecimal(t.y())
         << ' ' << exactDecimal(t.z()) << ' ' << exactDecimal(q.x()) << ' ' << exactDecimal(q.y())
         << ' ' << exactDecimal(q.z()) << ' ' << exactDecimal(q.w()) << '\n';
  poses_.flush();
  if (!poses_) {
    *error = (root / "poses.txt").string() + ": write failed";
    return false;
  }
  ++frames_written_;
  return true;
}

bool DatasetWriter::writeGroundTruthMesh(const TriangleMesh& mesh, std::string* error) {
  return writePly((fs::path(folder_) / "gt_mesh.ply").string(), mesh, error);
}

}  // namespace stereo_fusion::sim
