#include "stereo_fusion/session/CorrectionWorker.h"

#include <algorithm>

#include "stereo_fusion/session/ScopeGuard.h"
#include "stereo_fusion/util/Timer.h"

namespace stereo_fusion {

namespace {
// A trajectory that moves no kept frame by more than this is taken as it is, without re-fusion.
constexpr double kMinCorrectionM = 0.002;
constexpr double kMinCorrectionDeg = 0.05;
// A re-fusion catches up with the frames fused meanwhile outside the map lock, a batch a round;
// once a batch is this small, or after this many rounds (live fusion as fast as the catch-up: it
// would never end), the last batch runs under the lock and the maps are swapped.
constexpr size_t kCatchUpFramesUnderLock = 2;
constexpr int kMaxCatchUpRounds = 4;

size_t frameCount(const std::vector<Edit>& edits) {
  return static_cast<size_t>(
      std::count_if(edits.begin(), edits.end(), [](const Edit& e) { return e.isFrame(); }));
}
}  // namespace

CorrectionWorker::CorrectionWorker(CorrectionTarget target, bool background)
    : target_(std::move(target)), background_(background) {
  if (background_) thread_ = std::thread([this] { loop(); });
}

void CorrectionWorker::stop() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
  }
  cv_.notify_all();
  if (thread_.joinable()) thread_.join();
}

void CorrectionWorker::setListener(std::function<void(const CorrectionReport&)> listener) {
  std::lock_guard<std::mutex> lock(mutex_);
  listener_ = std::move(listener);
}

std::optional<CorrectionReport> CorrectionWorker::submit(std::vector<StampedPose> poses,
                                                         std::optional<double> fused_until_s) {
  auto refuse = [&](TrajectoryOutcome outcome, const std::string& why) {
    outcomes_.count(outcome);
    CorrectionReport report;
    report.outcome = outcome;
    report.message = why;
    report.trajectory_poses = poses.size();
    return report;
  };
  EditTimeline& timeline = *target_.timeline;
  if (timeline.maxFrames() == 0)
    return refuse(TrajectoryOutcome::kRejectedNothingKept,
                  "loop_closure_max_frames is 0: no frame is kept to correct");
  if (poses.empty()) return refuse(TrajectoryOutcome::kRejectedEmpty, "it holds no pose");
  sortByStamp(&poses);
  Pending pending;
  {
    std::lock_guard<std::mutex> lock(*target_.map_lock);
    if (timeline.frames() == 0)
      return refuse(TrajectoryOutcome::kRejectedNoFrameYet, "no frame has been fused yet");
    pending.fused_until_s = fused_until_s ? *fused_until_s : timeline.newestFrameStamp();
    pending.epoch = target_.admission->epoch();
  }
  pending.poses = std::move(poses);
  if (!background_) {
    const CorrectionReport report = run(pending);
    outcomes_.count(report.outcome);
    return report;
  }
  {
    std::lock_guard<std::mutex> lock(mutex_);
    // A newer trajectory supersedes one not started yet (a SLAM sends the whole path each time).
    if (pending_) outcomes_.count(TrajectoryOutcome::kSuperseded);
    pending_ = std::move(pending);
  }
  cv_.notify_one();
  return std::nullopt;
}

void CorrectionWorker::dropWaiting() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (pending_) {
    outcomes_.count(TrajectoryOutcome::kDroppedByReset);
    pending_.reset();
  }
}

void CorrectionWorker::loop() {
  while (true) {
    Pending trajectory;
    std::function<void(const CorrectionReport&)> listener;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      cv_.wait(lock, [this] { return stopping_ || pending_.has_value(); });
      if (stopping_) return;
      trajectory = std::move(*pending_);
      pending_.reset();
      listener = listener_;
    }
    const CorrectionReport report = run(trajectory);
    outcomes_.count(report.outcome);
    if (listener) listener(report);
  }
}

bool CorrectionWorker::cancelled(const Pending& trajectory) {
  std::lock_guard<std::mutex> lock(mutex_);
  return stopping_ || pending_.has_value() || target_.admission->epoch() != trajectory.epoch;
}

CorrectionReport CorrectionWorker::run(const Pending& trajectory) {
  Timer timer;
  CorrectionReport report;
  report.trajectory_poses = trajectory.poses.size();
  auto finish = [&](TrajectoryOutcome outcome, const std::string& message) {
    report.outcome = outcome;
    report.message = message;
    report.ms = timer.elapsedMs();
    return report;
  };
  EditTimeline& timeline = *target_.timeline;
  auto current = [&] { return trajectory.epoch == target_.admission->epoch(); };
  // The map lock, for every part of the run that holds it; the clean-ups below run with it held.
  std::unique_lock<std::mutex> lock(*target_.map_lock);
  if (!current())
    return finish(TrajectoryOutcome::kDroppedByReset, "a reset or load_map came first");
  const std::vector<StampedPose> originals = timeline.originalPoses();
  const PoseCorrection correction(originals, trajectory.poses, trajectory.fused_until_s);
  report.matched_poses = correction.corrections().size();
  correctionMagnitude(originals, correction, &report.max_shift_m, &report.max_rotation_deg);
  if (correction.empty())
    return finish(TrajectoryOutcome::kRejectedNoMatch,
                  "none of its " + std::to_string(trajectory.poses.size()) +
                      " stamps lies within 0.5 s of a fused frame still kept (stamps must match "
                      "the frames')");
  if (report.max_shift_m < kMinCorrectionM && report.max_rotation_deg < kMinCorrectionDeg) {
    // Nothing kept moves visibly: frames leaving the window still take this correction.
    target_.adopt(correction, nullptr, nullptr);
    return finish(TrajectoryOutcome::kAppliedWithoutRefusion, "it moves no kept frame visibly");
  }
  EditTimeline::Snapshot snapshot = timeline.snapshot();
  timeline.pin(snapshot.end_position);
  correcting_ = true;
  // However the re-fusion ends: the timeline unpinned (a new epoch cleared it and its pin), then
  // the worker idle again.
  ScopeGuard idle([&] {
    if (!lock.owns_lock()) lock.lock();
    correcting_ = false;
  });
  ScopeGuard unpin([&] {
    if (!lock.owns_lock()) lock.lock();
    if (current()) timeline.unpin();
  });
  lock.unlock();
  auto stopped = [&](RefusionStatus status, const std::string& error) {
    if (status == RefusionStatus::kCancelled)
      return current() ? finish(TrajectoryOutcome::kSuperseded,
                                "a newer trajectory came while it was fused again")
                       : finish(TrajectoryOutcome::kDroppedByReset,
                                "a reset or load_map came while it was fused again");
    return finish(TrajectoryOutcome::kFailed, std::string(refusionStatusName(status)) + ": " +
                                                  error + " (the map is unchanged)");
  };
  auto isCancelled = [&] { return cancelled(trajectory); };

  std::string error;
  std::unique_ptr<Mapper> rebuilt = mapperFromBase(*target_.config, snapshot.base_bytes, &error);
  if (!rebuilt) return stopped(RefusionStatus::kUnreadableBase, error);
  EditReplay replay(std::move(snapshot.base_pending));
  RefusionProgress progress;
  RefusionStatus status = replayEdits(snapshot.edits, correction, rebuilt.get(), &replay,
                                      isCancelled, &progress, &error);
  if (status != RefusionStatus::kDone) return stopped(status, error);
  rebuilt->updateMesh();
  rebuilt->updatePlanning();

  // Catch up with the edits the live map received meanwhile, in their order.
  uint64_t next = snapshot.end_position;
  for (int round = 1;; ++round) {
    lock.lock();
    if (!current())
      return finish(TrajectoryOutcome::kDroppedByReset,
                    "a reset or load_map came while it was fused again");
    const std::vector<Edit> newer = timeline.editsFrom(next);
    if (frameCount(newer) <= kCatchUpFramesUnderLock || round >= kMaxCatchUpRounds) {
      status = replayEdits(newer, correction, rebuilt.get(), &replay, nullptr, &progress, &error);
      if (status != RefusionStatus::kDone)
        return finish(TrajectoryOutcome::kFailed,
                      std::string(refusionStatusName(status)) + ": " + error);
      rebuilt->updateMesh();
      rebuilt->updatePlanning();
      unpin.run();
      report.frames_refused = progress.frames;
      report.frames_rejected = progress.rejected;
      target_.adopt(correction, std::move(rebuilt), &replay);
      finish(TrajectoryOutcome::kApplied,
             "fused " + std::to_string(progress.frames) + " frames again in " +
                 std::to_string(static_cast<long>(timer.elapsedMs())) + " ms");
      last_applied_ = report;
      return report;
    }
    next = timeline.endPosition();
    timeline.pin(next);
    lock.unlock();
    status = replayEdits(newer, correction, rebuilt.get(), &replay, isCancelled, &progress, &error);
    if (status != RefusionStatus::kDone) return stopped(status, error);
  }
}

}  // namespace stereo_fusion
