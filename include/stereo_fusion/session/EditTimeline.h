#pragma once
#include <cstdint>
#include <deque>
#include <functional>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "stereo_fusion/Mapper.h"
#include "stereo_fusion/session/EditReplay.h"
#include "stereo_fusion/trajectory/PoseCorrection.h"

namespace stereo_fusion {

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
