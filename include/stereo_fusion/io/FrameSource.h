#pragma once
#include <cstddef>
#include <string>

#include "stereo_fusion/integration/StereoFrame.h"

namespace stereo_fusion {

/// A recorded sequence of stereo frames (dataset folder or rosbag) that can be loaded one by
/// one; a frame that cannot be loaded fails alone, with a reason, and can be skipped.
class FrameSource {
 public:
  virtual ~FrameSource() = default;
  virtual size_t size() const = 0;
  /// Loads frame `i`; false with a message naming the file or message on any problem.
  virtual bool load(size_t i, StereoFrame* frame, std::string* error) const = 0;
};

}  // namespace stereo_fusion
