#pragma once
#include <atomic>
#include <condition_variable>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "stereo_fusion/session/EditTimeline.h"
#include "stereo_fusion/session/FrameAdmission.h"
#include "stereo_fusion/session/TrajectoryOutcome.h"
#include "stereo_fusion/trajectory/PoseCorrection.h"

namespace stereo_fusion {

/// What became of one trajectory and its re-fusion.
struct CorrectionReport {
  TrajectoryOutcome outcome = TrajectoryOutcome::kApplied;
  std::string message;
  size_t trajectory_poses = 0;
  size_t matched_poses = 0;  ///< trajectory poses within 0.5 s of a kept frame
  double max_shift_m = 0.0, max_rotation_deg = 0.0;
  size_t frames_refused = 0;  ///< frames fused again (catch-up included)
  size_t frames_rejected =
      0;  ///< of those, refused by the new map's FrameGate at the corrected pose
  double ms = 0.0;
};

/// What a correction reads and writes of the live session: the map lock, the timeline and the
/// epoch it guards, and the session's adoption of a correction (map lock held): with a rebuilt
/// map it swaps it in with its EditReplay; without (nullptr), the correction is only taken for
/// the frames still to leave the timeline (nothing kept moved visibly).
struct CorrectionTarget {
  const MapperConfig* config = nullptr;
  std::mutex* map_lock = nullptr;
  EditTimeline* timeline = nullptr;
  const FrameAdmission* admission = nullptr;
  std::function<void(const PoseCorrection&, std::unique_ptr<Mapper> rebuilt, EditReplay* replay)>
      adopt;
};

/// The session's loop-closure worker: one trajectory waiting at a time (a newer one supersedes
/// it, counted), re-fused on a thread of its own (`background`) or before submit() returns, with
/// the one re-fusion routine (replayEdits()) over a snapshot of the timeline, the catch-up with
/// the edits appended meanwhile, in their order, and the swap under the map lock. Every
/// trajectory's outcome is counted once (TrajectoryCounters).
///
/// Lock order: the map lock, then the worker's queue lock.
class CorrectionWorker {
 public:
  CorrectionWorker(CorrectionTarget target, bool background);
  ~CorrectionWorker() { stop(); }
  CorrectionWorker(const CorrectionWorker&) = delete;
  CorrectionWorker& operator=(const CorrectionWorker&) = delete;
  /// Stops the thread (the correction in progress is cancelled between frames).
  void stop();

  /// Called (no lock held) with the report of every trajectory the thread finished.
  void setListener(std::function<void(const CorrectionReport&)> listener);
  /// See MappingSession::submitTrajectory(). Takes the map lock.
  std::optional<CorrectionReport> submit(std::vector<StampedPose> poses,
                                         std::optional<double> fused_until_s);
  /// A new epoch (map lock held): a trajectory still waiting is dropped, counted.
  void dropWaiting();
  /// Counts a trajectory an input refused before submit().
  void count(TrajectoryOutcome outcome) { outcomes_.count(outcome); }
  const TrajectoryCounters& outcomes() const { return outcomes_; }
  /// The latest applied correction's report (map lock held).
  const CorrectionReport& lastAppliedLocked() const { return last_applied_; }
  /// True while a correction re-fuses.
  bool correcting() const { return correcting_.load(); }

 private:
  struct Pending {
    std::vector<StampedPose> poses;
    double fused_until_s = 0.0;
    uint64_t epoch = 0;
  };
  void loop();
  /// Re-fuses the kept edits at `trajectory`'s poses, catches up, swaps; its report.
  CorrectionReport run(const Pending& trajectory);
  /// True once the re-fusion of `trajectory` is pointless: stopping, a newer one, a new epoch.
  bool cancelled(const Pending& trajectory);

  const CorrectionTarget target_;
  const bool background_;  // a thread of its own; else submit() runs the correction
  std::mutex mutex_;       // the queue's: guards the three below
  std::condition_variable cv_;
  std::optional<Pending> pending_;
  bool stopping_ = false;
  std::function<void(const CorrectionReport&)> listener_;
  std::atomic<bool> correcting_{false};
  CorrectionReport last_applied_;  // map lock
  TrajectoryCounters outcomes_;
  std::thread thread_;  // last: started once the members above exist
};

}  // namespace stereo_fusion
