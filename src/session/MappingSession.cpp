#include "stereo_fusion/session/MappingSession.h"

#include <algorithm>
#include <cstdio>
#include <set>

#include "stereo_fusion/io/MapFile.h"

namespace stereo_fusion {

MappingSession::MappingSession(const MapperConfig& config, const SessionConfig& session)
    : config_(config),
      session_config_(session),
      mapper_(std::make_unique<Mapper>(config)),
      timeline_(config, session.loop_closure_max_frames),
      corrections_(CorrectionTarget{&config_, &mutex_, &timeline_, &admission_,
                                    [this](const PoseCorrection& correction,
                                           std::unique_ptr<Mapper> rebuilt, EditReplay* replay) {
                                      adoptCorrectionLocked(correction, std::move(rebuilt), replay);
                                    }},
                   session.background_corrections) {
  mapper_->setStageMonitor(&monitor_);
}

MappingSession::~MappingSession() { corrections_.stop(); }

void MappingSession::setMapReplacedListener(std::function<void(const MapReplaced&)> listener) {
  std::lock_guard<std::mutex> lock(mutex_);
  listener_ = std::move(listener);
}

void MappingSession::notifyLocked(MapChange change, const std::vector<BlockKey>& removed) {
  MapAccess access = accessLocked();
  if (listener_) listener_(MapReplaced{change, access, removed, correction_});
}

MeshSubscription MappingSession::subscribeToMeshChanges(const std::string& name) {
  std::lock_guard<std::mutex> lock(mutex_);
  mesh_subscribers_.push_back(name);
  mesh_consumers_.push_back(mapper_->subscribeToMeshChanges(name));
  return static_cast<MeshSubscription>(mesh_consumers_.size() - 1);
}

void MappingSession::updatePlanning(
    const std::function<void(const PlanningMap&, const PlanningPass&)>& then) {
  std::unique_lock<std::mutex> pass_lock(planning_pass_mutex_, std::defer_lock);
  Mapper* mapper = nullptr;
  std::optional<PlanningMap::PendingUpdate> pending;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    mapper = mapper_.get();
    pending = mapper->beginPlanningUpdate();
    if (!pending) return;
    pass_lock.lock();  // before the map lock is released: replacements wait for it
  }
  mapper->finishPlanningUpdate(std::move(*pending),
                               [&](const PlanningPass& pass) { then(*mapper->planning(), pass); });
}

FrameTicket MappingSession::arrive() {
  std::lock_guard<std::mutex> lock(mutex_);
  return admission_.arrive();
}

MappingSession::FrameOutcome MappingSession::fuse(const StereoFrame& frame,
                                                  const FrameTicket& ticket, MeshTiming timing,
                                                  FrameLoader reload) {
  FrameOutcome out;
  std::lock_guard<std::mutex> lock(mutex_);
  if (!admission_.isCurrent(ticket)) {
    out.reason = RejectReason::kSuperseded;
    out.error = "it arrived before a reset or load_map";
    admission_.countDrop(out.reason);
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
    admission_.countDrop(out.reason);
    return out;
  }
  out.result = std::move(applied.result);
  admission_.countEvicted(out.result.evicted_blocks.size());
  if (!out.result.accepted) {
    out.reason = out.result.reason;
    out.error = out.result.error;
    admission_.countDrop(out.reason);
    return out;
  }
  out.recleared = applied.recleared;
  admission_.countFused(out.result, applied.recleared);
  checkpointIfDueLocked();
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
  edit.ticket = admission_.clearTicket();
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
  admission_.newEpoch();
  live_replay_ = EditReplay();
  correction_ = PoseCorrection();
  std::string why;
  if (!timeline_.clear(base_bytes, &why))
    std::fprintf(stderr, "stereo_fusion: the loop-closure base of the loaded map: %s\n",
                 why.c_str());
  corrections_.dropWaiting();
}

bool MappingSession::reset() {
  std::unique_lock<std::mutex> lock(mutex_, std::defer_lock);
  if (!lockWithin(&lock, requestWait())) return false;
  const std::vector<BlockKey> removed = mapper_->submeshKeys();
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
  out.blocks = mapper_->tsdf().blockCount();
  out.message = "loaded " + std::to_string(out.blocks) + " blocks from " + path;
  notifyLocked(MapChange::kLoaded, changes.removed);
  return out;
}

Mapper::StoreOpening MappingSession::openMapStore() {
  std::lock_guard<std::mutex> lock(mutex_);
  const std::lock_guard<std::mutex> pass(planning_pass_mutex_);
  Mapper::StoreOpening opened = mapper_->openMapStore(config_.resume);
  last_checkpoint_ = std::chrono::steady_clock::now();
  if (!opened.ok) store_error_ = opened.message;
  if (!opened.resumed) return opened;
  std::vector<uint8_t> base;
  if (timeline_.maxFrames() > 0) {
    // As after a load: the resumed map holds voxels, not frames; a later correction re-fuses
    // the new frames over it.
    base = mapper_->encodeMap();
    sealMapFile(&base);
  }
  startEpochLocked(base);
  notifyLocked(MapChange::kLoaded, opened.changes.removed);
  return opened;
}

bool MappingSession::checkpoint(std::string* message) {
  std::unique_lock<std::mutex> lock(mutex_, std::defer_lock);
  if (!lockWithin(&lock, requestWait())) {
    *message = busyMessage();
    return false;
  }
  std::string error;
  if (!mapper_->checkpoint(checkpoint_note_, &error)) {
    *message = error;
    return false;
  }
  last_checkpoint_ = std::chrono::steady_clock::now();
  // The caller is told once it is on disk (frames wait for the commit: only the blocks changed
  // since the last checkpoint).
  mapper_->flushCheckpoints();
  const CheckpointStats& stats = mapper_->checkpointStats();
  if (!stats.error.empty()) {
    *message = stats.error;
    return false;
  }
  *message = "checkpoint " + std::to_string(stats.checkpoints) + " of " + stats.file + ": " +
             std::to_string(stats.last_frames_integrated) + " frames";
  return true;
}

void MappingSession::setCheckpointNote(std::string note) {
  std::lock_guard<std::mutex> lock(mutex_);
  checkpoint_note_ = std::move(note);
}

void MappingSession::checkpointIfDueLocked() {
  if (config_.checkpoint_period_s <= 0.0 || !mapper_->hasMapStore()) return;
  const auto now = std::chrono::steady_clock::now();
  // A kill loses what came after the last committed checkpoint began: the next one begins
  // early enough that it commits, as the last one did, before the period ends — one frame and
  // the last one's commit time before it.
  const double frame_s = std::chrono::duration<double>(now - last_fused_).count();
  last_fused_ = now;
  const double margin_s = frame_s + mapper_->checkpointStats().last_commit_s;
  if (std::chrono::duration<double>(now - last_checkpoint_).count() <
      config_.checkpoint_period_s - margin_s)
    return;
  last_checkpoint_ = now;
  std::string error;
  mapper_->checkpoint(checkpoint_note_, &error);  // a refusal shows in checkpointStats()
}

void MappingSession::adoptCorrectionLocked(const PoseCorrection& correction,
                                           std::unique_ptr<Mapper> rebuilt, EditReplay* replay) {
  if (!rebuilt) {  // nothing kept moved visibly: the frames still to leave take it
    timeline_.setCorrection(correction);
    correction_ = correction;
    return;
  }
  // Both maps' submeshes, paged-out ones included: those the rebuilt map lacks are removed.
  const std::vector<BlockKey> kept = rebuilt->submeshKeys();
  std::vector<BlockKey> removed;
  const std::vector<BlockKey> before = mapper_->submeshKeys();
  std::set_difference(before.begin(), before.end(), kept.begin(), kept.end(),
                      std::back_inserter(removed));
  const std::lock_guard<std::mutex> pass(planning_pass_mutex_);
  mapper_->setStageMonitor(nullptr);
  mapper_->handOverMapStore(rebuilt.get());
  rebuilt->setStageMonitor(&monitor_);
  mapper_ = std::move(rebuilt);
  for (size_t i = 0; i < mesh_subscribers_.size(); ++i)  // the subscribers follow the swap
    mesh_consumers_[i] = mapper_->subscribeToMeshChanges(mesh_subscribers_[i]);
  live_replay_ = std::move(*replay);
  timeline_.setCorrection(correction);
  correction_ = correction;
  notifyLocked(MapChange::kCorrected, removed);
}

CorrectionReport MappingSession::lastCorrection() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return corrections_.lastAppliedLocked();
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
  s.last_correction = corrections_.lastAppliedLocked();
  s.blocks = mapper_->tsdf().blockCount();
  s.memory_bytes = mapper_->memoryBytes();
  s.awaiting_mesh = mapper_->blocksAwaitingMesh();
  s.map_memory_bytes = mapper_->mapMemoryBytes();
  s.paged_out_blocks = mapper_->pagedOutBlocks();
  s.paging = mapper_->pagingStats();
  s.checkpoint = mapper_->checkpointStats();
  if (!store_error_.empty()) s.checkpoint.error = store_error_;
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
