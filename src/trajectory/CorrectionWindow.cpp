#include "stereo_fusion/trajectory/CorrectionWindow.h"

#include <algorithm>
#include <cmath>
#include <limits>

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
    const StereoFrame oldest = frames_.front();
    frames_.pop_front();
    bytes_ -= imageBytes(oldest);
    if (!base_) base_ = std::make_unique<Mapper>(config_);
    base_->integrate(correction_.corrected(oldest), MeshTiming::kDeferred);
    ++frames_frozen_;
  }
  // Clears older than every kept frame were repeated into the base already.
  const double oldest_s = frames_.empty() ? 0.0 : frames_.front().timestamp_s;
  clears_.erase(std::remove_if(clears_.begin(), clears_.end(),
                               [oldest_s](const TimedRegion& c) { return c.stamp_s <= oldest_s; }),
                clears_.end());
}

void CorrectionWindow::clearRegion(const MapRegion& region, double stamp_s) {
  if (max_frames_ == 0) return;
  if (base_) base_->clearRegion(region, MeshTiming::kDeferred);
  clears_.push_back({stamp_s, region});
}

bool CorrectionWindow::clear(const std::vector<uint8_t>& base_bytes, std::string* error) {
  frames_.clear();
  bytes_ = 0;
  base_.reset();
  frames_frozen_ = 0;
  correction_ = PoseCorrection();
  clears_.clear();
  if (base_bytes.empty() || max_frames_ == 0) return true;
  BlockOctree base(config_.blockSizeM());
  MapFileInfo info;
  std::string why;
  if (!decodeMapFile(base_bytes.data(), base_bytes.size(), config_, &base, &info, &why)) {
    if (error) *error = why;
    return false;
  }
  base_ = std::make_unique<Mapper>(config_);
  base_->adoptMap(&base, info);
  return true;
}

std::vector<StampedPose> CorrectionWindow::originalPoses() const {
  std::vector<StampedPose> poses;
  for (const StereoFrame& f : frames_) poses.push_back({f.timestamp_s, f.T_world_camera});
  sortByStamp(&poses);
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
                                     const std::function<bool()>& cancelled, size_t* rejected, std::string* error,
                                     const std::vector<TimedRegion>& clears) {
  auto mapper = std::make_unique<Mapper>(config);
  if (!base_bytes.empty()) {
    BlockOctree base(config.blockSizeM());
    MapFileInfo info;
    if (!decodeMapFile(base_bytes.data(), base_bytes.size(), config, &base, &info, error)) return nullptr;
    // The base's frame count is kept: later frames count on from it (the eviction order).
    mapper->adoptMap(&base, info);
  }
  if (rejected) *rejected = 0;
  // Clear c goes after the last frame stamped before it: before frame i when
  // stamp(i − 1) < c ≤ stamp(i), after every frame when all are older.
  auto clearBefore = [&](double after_s, double until_s) {
    for (const TimedRegion& c : clears)
      if (c.stamp_s > after_s && c.stamp_s <= until_s) mapper->clearRegion(c.region, MeshTiming::kDeferred);
  };
  double previous_s = -std::numeric_limits<double>::infinity();
  for (const StereoFrame& original : frames) {
    if (cancelled && cancelled()) {
      *error = "cancelled";
      return nullptr;
    }
    clearBefore(previous_s, original.timestamp_s);
    previous_s = original.timestamp_s;
    if (!mapper->integrate(correction.corrected(original), MeshTiming::kDeferred).accepted && rejected) ++*rejected;
  }
  clearBefore(previous_s, std::numeric_limits<double>::infinity());
  mapper->updateMesh();
  mapper->updatePlanning();  // swapped in ready: occupancy and distances of the corrected map
  return mapper;
}

}  // namespace stereo_fusion
