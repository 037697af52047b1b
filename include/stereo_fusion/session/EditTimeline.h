#pragma once
#include <cstdint>
#include <deque>
#include <functional>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "stereo_fusion/Mapper.h"
#include "stereo_fusion/map/MapRegion.h"
#include "stereo_fusion/trajectory/PoseCorrection.h"

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
  /// Fuses `posed` (edit's frame at the pose to fuse it at) into `map`, then clears again.
  FrameApplied frame(Mapper* map, const StereoFrame& posed, const Edit& edit, MeshTiming timing);
  /// Applies `clear` to `map` and keeps it while later frames may predate it.
  ClearResult clear(Mapper* map, const Edit& clear, MeshTiming timing);
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
/// order to `map` through `replay`, every frame at `correction`'s pose. `frames` / `rejected`
/// count the frames fused / refused by the map's FrameGate at the corrected pose.
struct RefusionProgress {
  size_t frames = 0;
  size_t rejected = 0;
};
RefusionStatus replayEdits(const std::vector<Edit>& edits, const PoseCorrection& correction,
                           Mapper* map, EditReplay* replay, const std::function<bool()>& cancelled,
                           RefusionProgress* progress, std::string* error);

/// A new mapper holding `base_bytes` (a sealed map file; empty: an empty map), nullptr with
/// `error` if they do not decode. The base's frame count is kept: later frames count on from it
/// (the eviction order).
std::unique_ptr<Mapper> mapperFromBase(const MapperConfig& config,
                                       const std::vector<uint8_t>& base_bytes, std::string* error);

/// The single record of what the live map received, kept for loop closures: the newest
/// `max_frames` frames and the clears among and after them, in the live order, over the *base*,
/// a map of the older edits applied once more as they leave, the frames at the best pose known
/// then (the latest correction). Re-fusing the kept edits over a copy of the base at corrected
/// poses gives exactly the map of all edits at those poses, for the frames still kept.
///
/// One pruning rule: an edit is dropped once the base has taken it and no re-fusion in
/// progress still has to read it (pin()).
class EditTimeline {
 public:
  /// `config` is the live map's (the base is never meshed); `max_frames` = 0 keeps nothing.
  EditTimeline(const MapperConfig& config, size_t max_frames);

  size_t maxFrames() const { return max_frames_; }
  /// Appends an edit the live map just received (its position is set here). The oldest frame
  /// beyond maxFrames(), and every clear before it, go into the base.
  void append(Edit edit);
  /// The next position append() gives.
  uint64_t endPosition() const { return next_position_; }

  /// What a re-fusion starts from: the base and its pending clears, and the kept edits.
  struct Snapshot {
    std::vector<uint8_t> base_bytes;  ///< sealed map file; empty for an empty base
    std::deque<Edit> base_pending;    ///< the base's EditReplay::pending()
    std::vector<Edit> edits;          ///< the kept edits, in order (images shared)
    uint64_t end_position = 0;        ///< endPosition() when taken
  };
  Snapshot snapshot() const;
  /// The edits appended at or after `position` (a re-fusion catching up).
  std::vector<Edit> editsFrom(uint64_t position) const;
  /// Keeps the edits from `position` on readable by editsFrom() even after the base took them,
  /// until unpin(): a re-fusion reads them after it.
  void pin(uint64_t position);
  void unpin();

  /// The correction frames leaving are fused into the base at (the latest the SLAM sent).
  void setCorrection(const PoseCorrection& correction) { correction_ = correction; }
  const PoseCorrection& correction() const { return correction_; }
  /// Forgets everything; a non-empty `base_bytes` (a sealed map file, e.g. a map just loaded)
  /// becomes the base. False with `error` if it cannot be read (the base is then empty).
  bool clear(const std::vector<uint8_t>& base_bytes = {}, std::string* error = nullptr);

  /// Frames kept (a correction moves them).
  size_t frames() const { return frames_kept_; }
  /// Clears kept among and after the kept frames.
  size_t clears() const { return clears_kept_; }
  /// Frames that went into the base since construction or clear().
  uint64_t framesFrozen() const { return frames_frozen_; }
  /// Bytes of the kept frames' images (disparity and colour).
  size_t bytes() const { return bytes_; }
  /// The kept frames' original poses, by stamp (PoseCorrection's `fused`).
  std::vector<StampedPose> originalPoses() const;
  /// The newest kept frame's stamp, 0 without one.
  double newestFrameStamp() const;

 private:
  /// Applies the oldest kept frame, and the clears before it, to the base.
  void freezeOldestFrame();
  /// Drops the edits the base took that no pin needs.
  void prune();
  /// Index in edits_ of the first edit the base has not taken.
  size_t firstKept() const { return static_cast<size_t>(kept_from_ - front_position_); }

  MapperConfig config_;
  size_t max_frames_;
  std::deque<Edit> edits_;  // by position; those before kept_from_ are in the base (held for a pin)
  uint64_t front_position_ = 0;  // position of edits_.front()
  uint64_t kept_from_ = 0;       // the first position the base has not taken
  uint64_t next_position_ = 0;
  uint64_t pin_ = std::numeric_limits<uint64_t>::max();
  size_t frames_kept_ = 0, clears_kept_ = 0, bytes_ = 0;
  std::unique_ptr<Mapper> base_;  // created when the first edit goes into it
  EditReplay base_replay_;
  uint64_t frames_frozen_ = 0;
  PoseCorrection correction_;
};

}  // namespace stereo_fusion
