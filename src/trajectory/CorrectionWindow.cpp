#include "stereo_fusion/trajectory/CorrectionWindow.h"

#include <algorithm>
#include <cmath>

#include "stereo_fusion/io/MapFile.h"

namespace stereo_fusion {

namespace {
size_t imageBytes(const StereoFrame& frame) {
  return frame.disparity_px.total() * frame.disparity_px.elemSize() + frame.color.total() * frame.color.elemSize();
}
}  // namespace

CorrectionWindow::CorrectionWindow(const MapperConfig& config, size_t max_frames)
    : config_(config), max_frames_(max_frames) {
  config_.mesh_enabled = false;  // the base is never meshed: only its voxels are copied
  config_.texture = TextureMode::kOff;
}

void CorrectionWindow::add(const StereoFrame& frame) {
  if (max_frames_ == 0) return;
  frames_.push_back(frame);
  bytes_ += imageBytes(frame);
  while (frames_.size() > max_frames_) {
    StereoFrame oldest = frames_.front();
    frames_.pop_front();
    bytes_ -= imageBytes(oldest);
    if (!base_) base_ = std::make_unique<Mapper>(config_);
    oldest.T_world_camera = correction_.corrected(oldest.timestamp_s, oldest.T_world_camera);
    base_->integrate(oldest, MeshTiming::kDeferred);
    ++frames_frozen_;
  }
}

void CorrectionWindow::clear() {
  frames_.clear();
  bytes_ = 0;
  base_.reset();
  frames_frozen_ = 0;
  correction_ = PoseCorrection();
}

std::vector<StampedPose> CorrectionWindow::originalPoses() const {
  std::vector<StampedPose> poses;
  for (const StereoFrame& f : frames_) poses.push_back({f.timestamp_s, f.T_world_camera});
  std::sort(poses.begin(), poses.end(), [](const StampedPose& a, const StampedPose& b) { return a.stamp_s < b.stamp_s; });
  return poses;
}

std::vector<uint8_t> CorrectionWindow::baseBytes() const {
  if (!base_) return {};
  std::vector<uint8_t> bytes = base_->encodeMap();
  sealMapFile(&bytes);
  return bytes;
}

std::unique_ptr<Mapper> refuseWindow(const MapperConfig& config, const std::vector<uint8_t>& base_bytes,
                                     const std::vector<StereoFrame>& frames, const PoseCorrection& correction,
                                     const std::function<bool()>& cancelled, size_t* rejected, std::string* error) {
  auto mapper = std::make_unique<Mapper>(config);
  if (!base_bytes.empty()) {
    BlockOctree base(config.blockSizeM());
    MapFileInfo info;
    if (!decodeMapFile(base_bytes.data(), base_bytes.size(), config, &base, &info, error)) return nullptr;
    // The base's frame count is kept: later frames count on from it (the eviction order).
    mapper->adoptMap(&base, info);
  }
  if (rejected) *rejected = 0;
  for (const StereoFrame& original : frames) {
    if (cancelled && cancelled()) {
      *error = "cancelled";
      return nullptr;
    }
    StereoFrame frame = original;
    frame.T_world_camera = correction.corrected(original.timestamp_s, original.T_world_camera);
    if (!mapper->integrate(frame, MeshTiming::kDeferred).accepted && rejected) ++*rejected;
  }
  mapper->updateMesh();
  return mapper;
}

void correctionMagnitude(const std::vector<StereoFrame>& frames, const PoseCorrection& correction, double* shift_m,
                         double* rotation_deg) {
  *shift_m = 0.0;
  *rotation_deg = 0.0;
  for (const StereoFrame& f : frames) {
    const Eigen::Isometry3d moved = correction.corrected(f.timestamp_s, f.T_world_camera);
    *shift_m = std::max(*shift_m, (moved.translation() - f.T_world_camera.translation()).norm());
    const Eigen::AngleAxisd turn((moved.linear() * f.T_world_camera.linear().transpose()).eval());
    *rotation_deg = std::max(*rotation_deg, std::abs(turn.angle()) * 180.0 / M_PI);
  }
}

}  // namespace stereo_fusion
