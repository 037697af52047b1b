#pragma once
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "stereo_fusion/Mapper.h"
#include "stereo_fusion/map/MapRegion.h"
#include "stereo_fusion/trajectory/PoseCorrection.h"

namespace stereo_fusion {

/// A region an operator cleared (Mapper::clearRegion) at a time: frames stamped before it do not
/// refill it.
struct TimedRegion {
  double stamp_s = 0.0;
  MapRegion region;
};

/// What a loop closure can still move: the newest `max_frames` fused frames, kept whole (the
/// disparity and colour images share the frame's buffers), and the *base*, a map of the older
/// frames fused once more as they leave the window, at the best pose known then (the latest
/// correction applied). A correction re-fuses the window over a copy of the base
/// (refuseWindow()): with every frame still in the window the result is exactly the map of the
/// frames fused at their corrected poses; frames that left it stay where the base put them.
///
/// Memory: the frames' images (bytes()), ~2.1 MB per 640×480 frame with colour, and the base
/// map, which holds only blocks that frames beyond the window touched.
class CorrectionWindow {
 public:
  /// `max_frames` = 0 keeps nothing: no correction is possible.
  CorrectionWindow(const MapperConfig& config, size_t max_frames);

  /// Keeps `frame` (as the live mapper accepted it, at its original pose); the oldest frame
  /// beyond max_frames is fused into the base at correction().corrected() of its pose.
  void add(const StereoFrame& frame);
  /// The correction frames leaving the window are fused at (the latest the SLAM sent).
  void setCorrection(const PoseCorrection& correction) { correction_ = correction; }
  const PoseCorrection& correction() const { return correction_; }
  /// Forgets the kept frames, the base and the correction; a non-empty `base_bytes` (a sealed map
  /// file, e.g. a map just loaded) becomes the base. False with `error` if it cannot be read
  /// (the base is then empty).
  bool clear(const std::vector<uint8_t>& base_bytes = {}, std::string* error = nullptr);
  /// An operator cleared `region` at `stamp_s`: the base forgets it now, and a re-fusion clears it
  /// again after the window's frames stamped before it (refuseWindow()'s `clears`).
  void clearRegion(const MapRegion& region, double stamp_s);
  /// The clears a re-fusion of the window must repeat (those not older than its oldest frame).
  const std::vector<TimedRegion>& clears() const { return clears_; }

  size_t size() const { return frames_.size(); }
  size_t maxFrames() const { return max_frames_; }
  /// Frames that left the window into the base since construction or clear().
  uint64_t framesFrozen() const { return frames_frozen_; }
  /// Bytes of the kept images (disparity and colour).
  size_t bytes() const { return bytes_; }
  const std::deque<StereoFrame>& frames() const { return frames_; }
  /// The kept frames' original poses, by stamp (PoseCorrection's `fused`).
  std::vector<StampedPose> originalPoses() const;
  /// The base map as map-file bytes (sealed; empty while no frame has left the window).
  std::vector<uint8_t> baseBytes() const;

 private:
  MapperConfig config_;
  size_t max_frames_;
  std::deque<StereoFrame> frames_;
  size_t bytes_ = 0;
  std::unique_ptr<Mapper> base_;  // created when the first frame leaves
  uint64_t frames_frozen_ = 0;
  PoseCorrection correction_;
  std::vector<TimedRegion> clears_;
};

/// Fuses `frames` (in order) at the poses `correction` gives into a new mapper that starts from
/// `base_bytes` (a sealed map file, empty for an empty map), clearing each of `clears` after the
/// last frame stamped before it, meshes it and updates its planning layer, and returns it; nullptr with `error` if the base
/// cannot be read or `cancelled()` turns true between frames. `rejected` (optional) counts frames
/// the new mapper refused (its FrameGate).
std::unique_ptr<Mapper> refuseWindow(const MapperConfig& config, const std::vector<uint8_t>& base_bytes,
                                     const std::vector<StereoFrame>& frames, const PoseCorrection& correction,
                                     const std::function<bool()>& cancelled, size_t* rejected, std::string* error,
                                     const std::vector<TimedRegion>& clears = {});

}  // namespace stereo_fusion
