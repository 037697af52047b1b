#pragma once
// Frames held in memory, for tests and for callers that already have their frames.

#include <string>
#include <vector>

#include "stereo_fusion/io/FrameSource.h"

namespace stereo_fusion::eval {

/// A FrameSource over a vector of frames (cv::Mat copies share pixels, so load() is cheap).
class InMemoryFrameSource : public FrameSource {
 public:
  explicit InMemoryFrameSource(std::vector<StereoFrame> frames) : frames_(std::move(frames)) {}
  size_t size() const override { return frames_.size(); }
  bool load(size_t i, StereoFrame* frame, std::string* error) const override {
    if (i >= frames_.size()) {
      *error = "frame " + std::to_string(i) + " does not exist";
      return false;
    }
    *frame = frames_[i];
    return true;
  }

 private:
  std::vector<StereoFrame> frames_;
};

}  // namespace stereo_fusion::eval
