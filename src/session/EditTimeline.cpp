#include "stereo_fusion/session/EditTimeline.h"

#include <algorithm>

#include "stereo_fusion/io/MapFile.h"

namespace stereo_fusion {

namespace {
size_t imageBytes(const StereoFrame& frame) {
  return frame.disparity_px.total() * frame.disparity_px.elemSize() +
         frame.color.total() * frame.color.elemSize();
}
}  // namespace

std::unique_ptr<Mapper> mapperFromBase(const MapperConfig& config,
                                       const std::vector<uint8_t>& base_bytes, std::string* error) {
  auto mapper = std::make_unique<Mapper>(config);
  if (base_bytes.empty()) return mapper;
  BlockOctree base(config.blockSizeM());
  MapFileInfo info;
  if (!decodeMapFile(base_bytes.data(), base_bytes.size(), config, &base, &info, error))
    return nullptr;
  mapper->adoptMap(&base, info);
  return mapper;
}

EditTimeline::EditTimeline(const MapperConfig& config, size_t max_frames)
    : config_(config), max_frames_(max_frames) {
  config_.mesh_enabled = false;  // the base is never meshed: only its voxels are copied
  config_.texture = TextureMode::kOff;
}

void EditTimeline::append(Edit edit) {
  edit.position = next_position_++;
  if (max_frames_ == 0) {  // nothing is kept: no correction is possible
    front_position_ = kept_from_ = next_position_;
    return;
  }
  if (edit.isFrame()) {
    ++frames_kept_;
    bytes_ += imageBytes(edit.frame);
  } else {
    ++clears_kept_;
  }
  edits_.push_back(std::move(edit));
  while (frames_kept_ > max_frames_) freezeOldestFrame();
  prune();
}

void EditTimeline::freezeOldestFrame() {
  if (!base_) base_ = std::make_unique<Mapper>(config_);
  while (firstKept() < edits_.size()) {
    const Edit& edit = edits_[firstKept()];
    ++kept_from_;
    if (!edit.isFrame()) {
      base_replay_.clear(base_.get(), edit, MeshTiming::kDeferred);
      --clears_kept_;
      continue;
    }
    StereoFrame original;
    std::string unused;
    // A frame that cannot be read again stays out of the base (the live map has it).
    if (edit.loadFrame(&original, &unused))
      base_replay_.frame(base_.get(), correction_.corrected(original), edit, MeshTiming::kDeferred);
    --frames_kept_;
    bytes_ -= imageBytes(edit.frame);
    ++frames_frozen_;
    return;
  }
}

void EditTimeline::prune() {
  while (!edits_.empty() && front_position_ < std::min(kept_from_, pin_)) {
    edits_.pop_front();
    ++front_position_;
  }
}

EditTimeline::Snapshot EditTimeline::snapshot() const {
  Snapshot s;
  if (base_) {
    s.base_bytes = base_->encodeMap();
    sealMapFile(&s.base_bytes);
  }
  s.base_pending = base_replay_.pending();
  s.edits.assign(edits_.begin() + static_cast<std::ptrdiff_t>(firstKept()), edits_.end());
  s.end_position = next_position_;
  return s;
}

std::vector<Edit> EditTimeline::editsFrom(uint64_t position) const {
  const uint64_t from = std::max(position, front_position_);
  if (from >= next_position_ || edits_.empty()) return {};
  return std::vector<Edit>(edits_.begin() + static_cast<std::ptrdiff_t>(from - front_position_),
                           edits_.end());
}

void EditTimeline::pin(uint64_t position) { pin_ = position; }

void EditTimeline::unpin() {
  pin_ = std::numeric_limits<uint64_t>::max();
  prune();
}

bool EditTimeline::clear(const std::vector<uint8_t>& base_bytes, std::string* error) {
  edits_.clear();
  front_position_ = kept_from_ = next_position_;
  pin_ = std::numeric_limits<uint64_t>::max();
  frames_kept_ = clears_kept_ = bytes_ = 0;
  base_.reset();
  base_replay_ = EditReplay();
  frames_frozen_ = 0;
  correction_ = PoseCorrection();
  if (base_bytes.empty() || max_frames_ == 0) return true;
  std::string why;
  base_ = mapperFromBase(config_, base_bytes, &why);
  if (!base_ && error) *error = why;
  return base_ != nullptr;
}

std::vector<StampedPose> EditTimeline::originalPoses() const {
  std::vector<StampedPose> poses;
  for (size_t k = firstKept(); k < edits_.size(); ++k)
    if (edits_[k].isFrame())
      poses.push_back({edits_[k].frame.timestamp_s, edits_[k].frame.T_world_camera});
  sortByStamp(&poses);
  return poses;
}

double EditTimeline::newestFrameStamp() const {
  for (auto it = edits_.rbegin(); it != edits_.rend(); ++it)
    if (it->isFrame()) return it->frame.timestamp_s;
  return 0.0;
}

}  // namespace stereo_fusion
