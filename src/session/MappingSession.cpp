#include "stereo_fusion/session/MappingSession.h"

#include <algorithm>
#include <cstdio>
#include <set>

#include "stereo_fusion/io/MapFile.h"
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

MappingSession::MappingSession(const MapperConfig& config, const SessionConfig& session)
    : config_(config),
      session_config_(session),
      mapper_(std::make_unique<Mapper>(config)),
      timeline_(config, session.loop_closure_max_frames) {
  mapper_->setStageMonitor(&monitor_);
  if (session_config_.background_corrections)
    correction_thread_ = std::thread([this] { correctionLoop(); });
}

MappingSession::~MappingSession() {
  {
    std::lock_guard<std::mutex> lock(trajectory_mutex_);
    stopping_ = true;
  }
  trajectory_cv_.notify_all();
  if (correction_thread_.joinable()) correction_thread_.join();
}

void MappingSession::setMapReplacedListener(std::function<void(const MapReplaced&)> listener) {
  std::lock_guard<std::mutex> lock(mutex_);
  listener_ = std::move(listener);
}

void MappingSession::setCorrectionListener(std::function<void(const CorrectionReport&)> listener) {
  std::lock_guard<std::mutex> lock(trajectory_mutex_);
  correction_listener_ = std::move(listener);
}

void MappingSession::notifyLocked(MapChange change, const std::vector<BlockKey>& removed) {
  if (listener_) listener_(MapReplaced{change, *mapper_, removed, correction_});
}

FrameTicket MappingSession::arrive() {
  std::lock_guard<std::mutex> lock(mutex_);
  return {epoch_, next_ticket_++};
}

bool MappingSession::isCurrent(const FrameTicket& ticket) const {
  return ticket.epoch == epoch_seen_.load();
}

MappingSession::FrameOutcome MappingSession::fuse(const StereoFrame& frame,
                                                  const FrameTicket& ticket, MeshTiming timing,
                                                  FrameLoader reload) {
  FrameOutcome out;
  std::lock_guard<std::mutex> lock(mutex_);
  if (ticket.epoch != epoch_) {
    out.reason = RejectReason::kSuperseded;
    out.error = "it arrived before a reset or load_map";
    drops_.count(out.reason);
    return out;
  }
  Edit edit;
  edit.kind = Edit::Kind::kFrame;
  edit.ticket = ticket.ticket;
  edit.stamp_s = frame.timestamp_s;
  EditReplay::FrameApplied applied;
  try {
    applied = live_replay_.frame(mapper_.get(), frame, edit, timing);
  } catch (const std::exception& e) {
    // A throw mid-frame (e.g. bad_alloc) can leave the fused voxels and the mesh out of step:
    // re-mesh from the map, and the listener sends it whole.
    if (config_.mesh_enabled) {
      try {
        const MeshChanges changes = mapper_->rebuildMesh();
        notifyLocked(MapChange::kRecovered, changes.removed);
      } catch (const std::exception&) {
        // Still out of memory: the next frame or meshing pass tries again.
      }
    }
    out.reason = RejectReason::kError;
    out.error = e.what();
    drops_.count(out.reason);
    return out;
  }
  out.result = std::move(applied.result);
  blocks_evicted_ += out.result.evicted_blocks.size();
  if (!out.result.accepted) {
    out.reason = out.result.reason;
    out.error = out.result.error;
    drops_.count(out.reason);
    return out;
  }
  out.recleared = applied.recleared;
  if (applied.recleared) ++frames_recleared_;
  ++frames_fused_;
  if (timeline_.maxFrames() > 0) {
    edit.frame = frame;  // shares the images
    if (reload) {
      edit.frame.disparity_px.release();
      edit.frame.color.release();
      edit.reload = std::move(reload);
    }
    timeline_.append(std::move(edit));
  }
  return out;
}

bool MappingSession::lockWithin(std::unique_lock<std::mutex>* lock,
                                std::chrono::steady_clock::duration wait) {
  const auto deadline = std::chrono::steady_clock::now() + wait;
  while (!lock->try_lock()) {
    if (std::chrono::steady_clock::now() >= deadline) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  return true;
}

std::string MappingSession::busyMessage() const {
  return "busy: the map has been held for more than " +
         std::to_string(session_config_.max_request_wait_s) + " s (" + mapperStageName(stage()) +
         " for " + std::to_string(busySeconds()) + " s); nothing was done, retry";
}

MappingSession::ClearOutcome MappingSession::clear(const MapRegion& region, double stamp_s) {
  ClearOutcome out;
  std::unique_lock<std::mutex> lock(mutex_, std::defer_lock);
  if (!lockWithin(&lock, requestWait())) {
    out.message = busyMessage();
    return out;
  }
  const std::string invalid = region.validate();
  if (!invalid.empty()) {
    out.message = invalid + " (the map is unchanged)";
    return out;
  }
  if (live_replay_.pending().size() >= kMaxPendingClears ||
      timeline_.clears() >= kMaxPendingClears) {
    ++clears_refused_;
    out.message =
        std::to_string(kMaxPendingClears) +
        " clears already wait for frames that may predate them (the map is unchanged); retry after "
        "frames newer than them were fused";
    return out;
  }
  Edit edit;
  edit.kind = Edit::Kind::kClear;
  edit.ticket = next_ticket_++;
  edit.stamp_s = stamp_s;
  edit.region = region;
  out.result = live_replay_.clear(mapper_.get(), edit, MeshTiming::kDeferred);
  timeline_.append(std::move(edit));
  ++regions_cleared_;
  out.success = true;
  out.message = "cleared " + region.describe() + ": " + std::to_string(out.result.voxels_cleared) +
                " voxels, " + std::to_string(out.result.blocks_erased) + " blocks erased, " +
                std::to_string(out.result.blocks_changed) + " changed";
  return out;
}

void MappingSession::startEpochLocked(const std::vector<uint8_t>& base_bytes) {
  ++epoch_;
  epoch_seen_ = epoch_;
  live_replay_ = EditReplay();
  correction_ = PoseCorrection();
  std::string why;
  if (!timeline_.clear(base_bytes, &why))
    std::fprintf(stderr, "stereo_fusion: the loop-closure base of the loaded map: %s\n",
                 why.c_str());
  std::lock_guard<std::mutex> lock(trajectory_mutex_);
  if (pending_trajectory_) {
    trajectories_.count(TrajectoryOutcome::kDroppedByReset);
    pending_trajectory_.reset();
  }
}

bool MappingSession::reset() {
  std::unique_lock<std::mutex> lock(mutex_, std::defer_lock);
  if (!lockWithin(&lock, requestWait())) return false;
  std::vector<BlockKey> removed;
  for (const auto& [key, sub] : mapper_->mesh().submeshes()) removed.push_back(key);
  std::sort(removed.begin(), removed.end());
  const std::lock_guard<std::mutex> pass(planning_pass_mutex_);
  mapper_->reset();
  startEpochLocked({});
  notifyLocked(MapChange::kReset, removed);
  return true;
}

MappingSession::LoadOutcome MappingSession::load(const std::string& path) {
  LoadOutcome out;
  // Read and check the file while frames are still fused into the current map; only the swap
  // and the re-meshing hold it.
  BlockOctree loaded(config_.blockSizeM());
  MapFileInfo info;
  std::string error;
  if (!readMapFile(path, config_, &loaded, &info, &error)) {
    out.message = error + " (the current map is unchanged)";  // blocks loaded: 0
    return out;
  }
  std::unique_lock<std::mutex> lock(mutex_, std::defer_lock);
  if (!lockWithin(&lock, requestWait())) {
    out.message = busyMessage() + " (the current map is unchanged)";
    return out;
  }
  const std::lock_guard<std::mutex> pass(planning_pass_mutex_);
  const MeshChanges changes = mapper_->adoptMap(&loaded, info);
  std::vector<uint8_t> base;
  if (timeline_.maxFrames() > 0) {
    // The loaded map is the base a later correction re-fuses the new frames over: it holds
    // voxels, not frames, so it is not moved itself.
    base = mapper_->encodeMap();
    sealMapFile(&base);
  }
  startEpochLocked(base);
  out.success = true;
  out.blocks = mapper_->map().blockCount();
  out.message = "loaded " + std::to_string(out.blocks) + " blocks from " + path;
  notifyLocked(MapChange::kLoaded, changes.removed);
  return out;
}

std::optional<CorrectionReport> MappingSession::submitTrajectory(
    std::vector<StampedPose> poses, std::optional<double> fused_until_s) {
  auto refuse = [&](TrajectoryOutcome outcome, const std::string& why) {
    trajectories_.count(outcome);
    CorrectionReport report;
    report.outcome = outcome;
    report.message = why;
    report.trajectory_poses = poses.size();
    return report;
  };
  if (timeline_.maxFrames() == 0)
    return refuse(TrajectoryOutcome::kRejectedNothingKept,
                  "loop_closure_max_frames is 0: no frame is kept to correct");
  if (poses.empty()) return refuse(TrajectoryOutcome::kRejectedEmpty, "it holds no pose");
  sortByStamp(&poses);
  PendingTrajectory pending;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (timeline_.frames() == 0)
      return refuse(TrajectoryOutcome::kRejectedNoFrameYet, "no frame has been fused yet");
    pending.fused_until_s = fused_until_s ? *fused_until_s : timeline_.newestFrameStamp();
    pending.epoch = epoch_;
  }
  pending.poses = std::move(poses);
  if (!session_config_.background_corrections) {
    const CorrectionReport report = runCorrection(pending);
    trajectories_.count(report.outcome);
    return report;
  }
  {
    std::lock_guard<std::mutex> lock(trajectory_mutex_);
    // A newer trajectory supersedes one not started yet (a SLAM sends the whole path each time).
    if (pending_trajectory_) trajectories_.count(TrajectoryOutcome::kSuperseded);
    pending_trajectory_ = std::move(pending);
  }
  trajectory_cv_.notify_one();
  return std::nullopt;
}

void MappingSession::correctionLoop() {
  while (true) {
    PendingTrajectory trajectory;
    std::function<void(const CorrectionReport&)> listener;
    {
      std::unique_lock<std::mutex> lock(trajectory_mutex_);
      trajectory_cv_.wait(lock, [this] { return stopping_ || pending_trajectory_.has_value(); });
      if (stopping_) return;
      trajectory = std::move(*pending_trajectory_);
      pending_trajectory_.reset();
      listener = correction_listener_;
    }
    const CorrectionReport report = runCorrection(trajectory);
    trajectories_.count(report.outcome);
    if (listener) listener(report);
  }
}

CorrectionReport MappingSession::runCorrection(const PendingTrajectory& trajectory) {
  Timer timer;
  CorrectionReport report;
  report.trajectory_poses = trajectory.poses.size();
  auto finish = [&](TrajectoryOutcome outcome, const std::string& message) {
    report.outcome = outcome;
    report.message = message;
    report.ms = timer.elapsedMs();
    return report;
  };
  EditTimeline::Snapshot snapshot;
  PoseCorrection correction;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (trajectory.epoch != epoch_)
      return finish(TrajectoryOutcome::kDroppedByReset, "a reset or load_map came first");
    const std::vector<StampedPose> originals = timeline_.originalPoses();
    correction = PoseCorrection(originals, trajectory.poses, trajectory.fused_until_s);
    report.matched_poses = correction.corrections().size();
    correctionMagnitude(originals, correction, &report.max_shift_m, &report.max_rotation_deg);
    if (correction.empty())
      return finish(TrajectoryOutcome::kRejectedNoMatch,
                    "none of its " + std::to_string(trajectory.poses.size()) +
                        " stamps lies within 0.5 s of a fused frame still kept (stamps must match "
                        "the frames')");
    if (report.max_shift_m < kMinCorrectionM && report.max_rotation_deg < kMinCorrectionDeg) {
      // Nothing kept moves visibly: frames leaving the window still take this correction.
      timeline_.setCorrection(correction);
      correction_ = correction;
      return finish(TrajectoryOutcome::kAppliedWithoutRefusion, "it moves no kept frame visibly");
    }
    snapshot = timeline_.snapshot();
    timeline_.pin(snapshot.end_position);
  }
  correcting_ = true;
  auto unpin = [&] {
    std::lock_guard<std::mutex> lock(mutex_);
    if (trajectory.epoch == epoch_)
      timeline_.unpin();  // a new epoch cleared the timeline and its pin
    correcting_ = false;
  };
  auto cancelled = [&] {
    std::lock_guard<std::mutex> lock(trajectory_mutex_);
    return stopping_ || pending_trajectory_.has_value() || epoch_seen_.load() != trajectory.epoch;
  };
  auto stopped = [&](RefusionStatus status, const std::string& error) {
    unpin();
    if (status == RefusionStatus::kCancelled)
      return epoch_seen_.load() != trajectory.epoch
                 ? finish(TrajectoryOutcome::kDroppedByReset,
                          "a reset or load_map came while it was fused again")
                 : finish(TrajectoryOutcome::kSuperseded,
                          "a newer trajectory came while it was fused again");
    return finish(TrajectoryOutcome::kFailed, std::string(refusionStatusName(status)) + ": " +
                                                  error + " (the map is unchanged)");
  };

  std::string error;
  std::unique_ptr<Mapper> rebuilt = mapperFromBase(config_, snapshot.base_bytes, &error);
  if (!rebuilt) return stopped(RefusionStatus::kUnreadableBase, error);
  EditReplay replay(std::move(snapshot.base_pending));
  RefusionProgress progress;
  RefusionStatus status =
      replayEdits(snapshot.edits, correction, rebuilt.get(), &replay, cancelled, &progress, &error);
  if (status != RefusionStatus::kDone) return stopped(status, error);
  rebuilt->updateMesh();
  rebuilt->updatePlanning();

  // Catch up with the edits the live map received meanwhile, in their order.
  uint64_t next = snapshot.end_position;
  for (int round = 1;; ++round) {
    std::vector<Edit> newer;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (trajectory.epoch != epoch_) {
        correcting_ = false;
        return finish(TrajectoryOutcome::kDroppedByReset,
                      "a reset or load_map came while it was fused again");
      }
      newer = timeline_.editsFrom(next);
      if (frameCount(newer) <= kCatchUpFramesUnderLock || round >= kMaxCatchUpRounds) {
        status = replayEdits(newer, correction, rebuilt.get(), &replay, nullptr, &progress, &error);
        if (status != RefusionStatus::kDone) {
          timeline_.unpin();
          correcting_ = false;
          return finish(TrajectoryOutcome::kFailed,
                        std::string(refusionStatusName(status)) + ": " + error);
        }
        rebuilt->updateMesh();
        rebuilt->updatePlanning();
        timeline_.unpin();
        report.frames_refused = progress.frames;
        report.frames_rejected = progress.rejected;
        adoptCorrectedLocked(std::move(rebuilt), std::move(replay), correction);
        correcting_ = false;
        finish(TrajectoryOutcome::kApplied,
               "fused " + std::to_string(progress.frames) + " frames again in " +
                   std::to_string(static_cast<long>(timer.elapsedMs())) + " ms");
        last_correction_ = report;
        return report;
      }
      next = timeline_.endPosition();
      timeline_.pin(next);
    }
    status = replayEdits(newer, correction, rebuilt.get(), &replay, cancelled, &progress, &error);
    if (status != RefusionStatus::kDone) return stopped(status, error);
  }
}

void MappingSession::adoptCorrectedLocked(std::unique_ptr<Mapper> rebuilt, EditReplay replay,
                                          const PoseCorrection& correction) {
  std::set<BlockKey> kept;
  for (const auto& [key, sub] : rebuilt->mesh().submeshes()) kept.insert(key);
  std::vector<BlockKey> removed;
  for (const auto& [key, sub] : mapper_->mesh().submeshes())
    if (!kept.count(key)) removed.push_back(key);
  std::sort(removed.begin(), removed.end());
  const std::lock_guard<std::mutex> pass(planning_pass_mutex_);
  mapper_->setStageMonitor(nullptr);
  rebuilt->setStageMonitor(&monitor_);
  mapper_ = std::move(rebuilt);
  live_replay_ = std::move(replay);
  timeline_.setCorrection(correction);
  correction_ = correction;
  notifyLocked(MapChange::kCorrected, removed);
}

CorrectionReport MappingSession::lastCorrection() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return last_correction_;
}

PoseCorrection MappingSession::correction() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return correction_;
}

MappingSession::KeptStatus MappingSession::kept() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return keptLocked();
}

std::optional<MappingSession::MapStatus> MappingSession::tryStatus(double wait_s) const {
  std::unique_lock<std::mutex> lock(mutex_, std::defer_lock);
  if (!lockWithin(&lock, std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                             std::chrono::duration<double>(wait_s))))
    return std::nullopt;
  MapStatus s;
  s.kept = keptLocked();
  s.last_correction = last_correction_;
  s.blocks = mapper_->map().blockCount();
  s.memory_bytes = mapper_->memoryBytes();
  s.awaiting_mesh = mapper_->blocksAwaitingMesh();
  if (const PlanningMap* planning = mapper_->planning()) {
    s.planning_free_space_bytes = planning->freeSpaceBytes();
    s.planning_esdf_bytes = planning->esdfBytes();
  }
  return s;
}

MappingSession::KeptStatus MappingSession::keptLocked() const {
  KeptStatus s;
  s.frames = timeline_.frames();
  s.clears = timeline_.clears();
  s.bytes = timeline_.bytes();
  s.frozen = timeline_.framesFrozen();
  s.pending_clears = live_replay_.pending().size();
  return s;
}

}  // namespace stereo_fusion
