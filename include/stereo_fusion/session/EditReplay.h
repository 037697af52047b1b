#pragma once
#include <cstdint>
#include <deque>
#include <functional>
#include <string>
#include <vector>

#include "stereo_fusion/Mapper.h"
#include "stereo_fusion/map/MapRegion.h"
#include "stereo_fusion/trajectory/PoseCorrection.h"

// The edits a map receives (frames, clears), the rule for frames from before a clear, and the
// one routine that applies them in order (live, to the loop-closure base, in a re-fusion).
namespace stereo_fusion {

/// Reads a kept frame again (offline: the frames' images are not held in memory).
using FrameLoader = std::function<bool(StereoFrame* frame, std::string* error)>;

/// One thing that reached the live map: a frame it fused or a region an operator cleared.
struct Edit {
  enum class Kind : uint8_t { kFrame, kClear };
  Kind kind = Kind::kFrame;
  /// Its place in the order the live map received edits (the timeline's order).
  uint64_t position = 0;
  /// Frames: the ticket taken when the frame arrived; clears: the ticket taken when applied.
  /// One counter for both (MappingSession::arrive()), so "arrived before the clear" is `<`.
  uint64_t ticket = 0;
  /// Frames: the frame's stamp; clears: the clock when the clear was applied.
  double stamp_s = 0.0;
  /// kFrame: the frame as the live map fused it, at its original pose (images shared, not
  /// copied), or only its stamp and pose when `reload` reads it again.
  StereoFrame frame;
  FrameLoader reload;
  MapRegion region;  ///< kClear

  bool isFrame() const { return kind == Kind::kFrame; }
  /// The frame, read again through `reload` when its images are not held.
  bool loadFrame(StereoFrame* out, std::string* error) const;
};

/// The rule for frames from before a clear: a frame that arrived before the clear was applied,
/// or was taken (stamped) before it, saw the region as it was; fusing it refills the region,
/// so the clear is applied again after it.
inline bool predates(const Edit& frame, const Edit& clear) {
  return frame.ticket < clear.ticket || frame.stamp_s < clear.stamp_s;
}

/// Applies edits to one map in order with the rule above: after each frame, the clears applied
/// before it that it predates are applied again. The live map, the loop-closure base and a
/// re-fusion all go through one, so all three see the same sequence of edits.
///
/// A clear is settled, and forgotten here, once a fused frame does not predate it: frames are
/// fused in arrival order and (require_increasing_timestamps) in stamp order, so no later frame
/// predates it either.
class EditReplay {
 public:
  EditReplay() = default;
  explicit EditReplay(std::deque<Edit> pending) : pending_(std::move(pending)) {}

  struct FrameApplied {
    IntegrationResult result;
    bool recleared = false;  ///< a clear was applied again after it and removed voxels
  };
  /// Fuses `posed` (edit's frame at the pose to fuse it at) into `mapper`, then clears again.
  FrameApplied frame(Mapper* mapper, const StereoFrame& posed, const Edit& edit, MeshTiming timing);
  /// Applies `clear` to `mapper` and keeps it while later frames may predate it.
  ClearResult clear(Mapper* mapper, const Edit& clear, MeshTiming timing);
  /// Clears a later frame may still predate, oldest first.
  const std::deque<Edit>& pending() const { return pending_; }

 private:
  std::deque<Edit> pending_;
};

/// Why a re-fusion stopped.
enum class RefusionStatus {
  kDone,
  kCancelled,        ///< cancelled() turned true between frames (a newer trajectory, a reset)
  kUnreadableBase,   ///< the base map's bytes did not decode
  kUnreadableFrame,  ///< a kept frame could not be read again
};
const char* refusionStatusName(RefusionStatus status);

/// The one re-fusion routine (a loop closure live, a trajectory offline): applies `edits` in
/// order to `mapper` through `replay`, every frame at `correction`'s pose. `frames` / `rejected`
/// count the frames fused / refused by the mapper's FrameGate at the corrected pose.
struct RefusionProgress {
  size_t frames = 0;
  size_t rejected = 0;
};
RefusionStatus replayEdits(const std::vector<Edit>& edits, const PoseCorrection& correction,
                           Mapper* mapper, EditReplay* replay,
                           const std::function<bool()>& cancelled, RefusionProgress* progress,
                           std::string* error);

}  // namespace stereo_fusion
