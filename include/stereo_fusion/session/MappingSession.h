#pragma once
#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "stereo_fusion/Mapper.h"
#include "stereo_fusion/session/CorrectionWorker.h"
#include "stereo_fusion/session/EditTimeline.h"
#include "stereo_fusion/session/FrameAdmission.h"
#include "stereo_fusion/session/MapAccess.h"

namespace stereo_fusion {

/// What a session keeps beside the map.
struct SessionConfig {
  /// Frames kept whole for a loop closure's correction (the node's loop_closure_max_frames);
  /// 0 keeps none, SIZE_MAX keeps all (offline, with a FrameLoader: only stamps and poses).
  size_t loop_closure_max_frames = 0;
  /// Corrections run on a thread of the session's while frames are fused (the node); false:
  /// submitTrajectory() runs one before it returns (the offline fuser).
  bool background_corrections = true;
  /// How long a request (clear, reset, load, tryRead, tryWithMap) waits for the map lock before
  /// it answers "busy" instead (a frame or a meshing pass holds it; frames themselves always wait).
  double max_request_wait_s = 2.0;
};

/// Why the session replaced the map (or its mesh) wholesale.
enum class MapChange { kReset, kLoaded, kCorrected, kRecovered };

/// Told to the listener, with the map lock held, whenever the map is replaced wholesale.
struct MapReplaced {
  MapChange change;
  MapAccess& map;                        ///< the map now (a correction swaps in a new Mapper)
  const std::vector<BlockKey>& removed;  ///< submeshes of the old map that are gone
  const PoseCorrection& correction;      ///< the latest correction applied (path display)
};

/// The ROS-free mapping session: the one owner of the Mapper, composed of its jobs — frame
/// admission by epoch and ticket with one set of counters (FrameAdmission), the single timeline
/// of edits with the rule for frames from before a clear (EditTimeline, EditReplay), and loop
/// closures with the one re-fusion routine (CorrectionWorker) — plus reset and load. The node
/// and the offline fuser are adapters over it. Every public method is thread-safe; the map lock
/// is held only inside them, and the map is lent only for the length of a call (read(),
/// withMap()): no caller keeps a reference a correction's swap could leave dangling.
///
/// Lock order: the map lock, then the planning pass's (updatePlanning()), then the correction
/// worker's queue lock; a re-fusion holds none of them while it fuses, and only the last few
/// catch-up frames run under the map lock.
class MappingSession {
 public:
  /// Throws std::invalid_argument for an invalid `config` (as Mapper).
  MappingSession(const MapperConfig& config, const SessionConfig& session);
  ~MappingSession();
  MappingSession(const MappingSession&) = delete;
  MappingSession& operator=(const MappingSession&) = delete;

  /// Called (map lock held) after every wholesale change of the map: publish it whole.
  void setMapReplacedListener(std::function<void(const MapReplaced&)> listener);
  /// Called (no lock held) with the report of every trajectory the background thread finished.
  void setCorrectionListener(std::function<void(const CorrectionReport&)> listener) {
    corrections_.setListener(std::move(listener));
  }

  // --- frames ---
  /// A frame arrived: its ticket. Take it when the frame arrives, not when it is fused, so
  /// that a clear applied while the frame waited (queue, tf) is applied again after it.
  FrameTicket arrive();
  /// False once a reset or load_map came after the ticket's arrival.
  bool isCurrent(const FrameTicket& ticket) const { return admission_.isCurrent(ticket); }
  /// The map epoch now (reset and load_map start a new one).
  uint64_t epoch() const { return admission_.epoch(); }
  /// Counts a frame an input dropped before it reached fuse().
  void countDrop(RejectReason reason) { admission_.countDrop(reason); }

  struct FrameOutcome {
    RejectReason reason = RejectReason::kNone;  ///< kNone: fused
    std::string error;                          ///< why not, one sentence
    IntegrationResult result;
    bool recleared = false;  ///< a clear it predates was applied again after it
  };
  /// Fuses `frame` (the ticket arrive() gave it). `reload` (offline) reads it again for a
  /// correction instead of keeping its images. Every outcome is counted (drops()).
  FrameOutcome fuse(const StereoFrame& frame, const FrameTicket& ticket, MeshTiming timing,
                    FrameLoader reload = {});

  // --- edits ---
  struct ClearOutcome {
    bool success = false;
    std::string message;
    ClearResult result;
  };
  /// Clears `region` at clock `stamp_s` (frames stamped before it, or that arrived before it,
  /// do not refill it). Refused, the map unchanged, if the region is invalid or more than
  /// kMaxPendingClears clears wait for frames that may predate them.
  ClearOutcome clear(const MapRegion& region, double stamp_s);
  static constexpr size_t kMaxPendingClears = 4096;
  /// Drops the map, the kept frames and any correction; frames that arrived before count as
  /// superseded. False (nothing done) if the map stayed busy for max_request_wait_s.
  bool reset();
  struct LoadOutcome {
    bool success = false;
    std::string message;
    size_t blocks = 0;
  };
  /// Replaces the map by the file at `path` (read and checked before the map lock is taken);
  /// on failure the map is unchanged.
  LoadOutcome load(const std::string& path);

  // --- the map store (checkpoint_period_s, resume) ---
  /// Opens map_store_path/map.sqlite as the map's durable copy (with resume, the map becomes
  /// the one it holds: the listener hears kLoaded and publishes it whole). Call once, after
  /// the listener is set. A store that cannot be opened leaves the map without one (`ok`
  /// false, `message` says why).
  Mapper::StoreOpening openMapStore();
  /// Writes a checkpoint now (~save_map with an empty path, the fuser's end); false with
  /// `message` without a map store or when the map stayed busy. `message` says what it wrote.
  bool checkpoint(std::string* message);
  /// What the map store's periodic checkpoints note for their owner (the offline fuser: where
  /// in its input the next frame is), stored with the next checkpoint.
  void setCheckpointNote(std::string note);

  // --- loop closures ---
  /// A corrected trajectory (camera poses in the map's frame, any order). With
  /// background_corrections it is queued (a newer one supersedes it, counted) and nullopt is
  /// returned; otherwise it is applied now and its report returned. `fused_until_s`: the
  /// frames the SLAM had seen (default: the newest kept frame now; offline: +infinity).
  std::optional<CorrectionReport> submitTrajectory(
      std::vector<StampedPose> poses, std::optional<double> fused_until_s = std::nullopt) {
    return corrections_.submit(std::move(poses), fused_until_s);
  }
  /// Counts a trajectory an input refused before submitTrajectory().
  void countTrajectory(TrajectoryOutcome outcome) { corrections_.count(outcome); }
  /// The latest applied correction's report.
  CorrectionReport lastCorrection() const;
  /// The latest correction applied (the identity before any).
  PoseCorrection correction() const;
  /// True while a correction re-fuses (tests, diagnostics).
  bool correcting() const { return corrections_.correcting(); }

  // --- the map, lent for one call ---
  /// Runs f(const Mapper&) with the map lock held; its result.
  template <typename F>
  auto read(F&& f) const {
    std::lock_guard<std::mutex> lock(mutex_);
    return f(static_cast<const Mapper&>(*mapper_));
  }
  /// Runs f(MapAccess&) with the map lock held: read the map, mesh it, take its changes.
  template <typename F>
  auto withMap(F&& f) {
    std::lock_guard<std::mutex> lock(mutex_);
    MapAccess access = accessLocked();
    return f(access);
  }
  /// The same for a request: false, f not run, if the map stayed busy for max_request_wait_s.
  template <typename F>
  bool tryWithMap(F&& f) {
    std::unique_lock<std::mutex> lock(mutex_, std::defer_lock);
    if (!lockWithin(&lock, requestWait())) return false;
    MapAccess access = accessLocked();
    f(access);
    return true;
  }
  /// A new subscriber of the mesh's changes (take them in withMap()); it follows the map
  /// across reset, load and corrections.
  MeshSubscription subscribeToMeshChanges(const std::string& name);
  /// Brings the planning layer up to date holding the map lock only while it reads the TSDF
  /// blocks changed since the last update; the distance field's update, then
  /// `then(layer, pass)`, run after the lock is released, while frames go on being fused (the
  /// node's planning timer). `then` reads the layer as this update left it (frames' free space
  /// waits for its end) and must not call the session: the map is not replaced (reset, load, a
  /// correction) until it returns, and those hold the map lock while they wait. Nothing runs
  /// without the planning layer.
  void updatePlanning(const std::function<void(const PlanningMap&, const PlanningPass&)>& then);

  /// The answer of a request that found the map busy.
  std::string busyMessage() const;
  /// Seconds the live map's current operation has run (0 while idle) and its stage: read
  /// without the map lock (a watchdog).
  double busySeconds() const { return monitor_.busySeconds(); }
  MapperStage stage() const { return monitor_.stage.load(); }
  const MapperConfig& config() const { return config_; }
  const RejectCounters& drops() const { return admission_.drops(); }
  /// Pixel counts and re-anchored frames summed over the fused frames.
  const FusedFrameTotals& fusedTotals() const { return admission_.fusedTotals(); }
  const TrajectoryCounters& trajectories() const { return corrections_.outcomes(); }
  uint64_t framesFused() const { return admission_.framesFused(); }
  uint64_t framesRecleared() const { return admission_.framesRecleared(); }
  uint64_t regionsCleared() const { return regions_cleared_.load(); }
  uint64_t clearsRefused() const { return clears_refused_.load(); }
  uint64_t blocksEvicted() const { return admission_.blocksEvicted(); }

  struct KeptStatus {
    size_t frames = 0, clears = 0, bytes = 0, pending_clears = 0;
    uint64_t frozen = 0;
  };
  KeptStatus kept() const;
  /// What /diagnostics reports of the map, or nullopt if it stayed busy for `wait_s`.
  struct MapStatus {
    KeptStatus kept;
    CorrectionReport last_correction;
    size_t blocks = 0, memory_bytes = 0, awaiting_mesh = 0;
    /// The planning layer's bytes (PlanningMap::freeSpaceBytes(), esdfBytes()); 0 without it.
    size_t planning_free_space_bytes = 0, planning_esdf_bytes = 0;
    /// Paging (max_map_memory_mb): every layer's bytes in memory, the blocks in the store.
    size_t map_memory_bytes = 0, paged_out_blocks = 0;
    PagingStats paging;
    CheckpointStats checkpoint;  ///< the map store's (file empty: none)
  };
  std::optional<MapStatus> tryStatus(double wait_s) const;

 private:
  MapAccess accessLocked() { return MapAccess(mapper_.get(), &mesh_consumers_); }
  /// Takes a correction (map lock held): with `rebuilt`, swaps it in and tells the listener.
  void adoptCorrectionLocked(const PoseCorrection& correction, std::unique_ptr<Mapper> rebuilt,
                             EditReplay* replay);
  /// A new epoch (reset, load): drops the kept edits and any correction (map lock held).
  void startEpochLocked(const std::vector<uint8_t>& base_bytes);
  void notifyLocked(MapChange change, const std::vector<BlockKey>& removed);
  /// After a fused frame: a checkpoint when checkpoint_period_s has passed since the last.
  void checkpointIfDueLocked();
  KeptStatus keptLocked() const;
  /// Takes `lock`'s mutex within `wait`, polling every millisecond (libstdc++'s timed mutex
  /// locks through pthread_mutex_clocklock, which ThreadSanitizer does not see).
  static bool lockWithin(std::unique_lock<std::mutex>* lock,
                         std::chrono::steady_clock::duration wait);
  std::chrono::steady_clock::duration requestWait() const {
    return std::chrono::duration_cast<std::chrono::steady_clock::duration>(
        std::chrono::duration<double>(session_config_.max_request_wait_s));
  }

  const MapperConfig config_;
  const SessionConfig session_config_;

  mutable std::mutex mutex_;  // the map lock: guards everything below but the counters
  // Held by updatePlanning() from its reading to its end; taken after the map lock by whatever
  // replaces the map, which then waits for it (the update runs without the map lock).
  std::mutex planning_pass_mutex_;
  StageMonitor monitor_;  // the live mapper's (a correction's rebuilt one gets it at the swap)
  std::unique_ptr<Mapper> mapper_;
  std::vector<std::string> mesh_subscribers_;             // by MeshSubscription
  std::vector<BlockChangeLog::Consumer> mesh_consumers_;  // theirs in mapper_'s mesh log
  EditReplay live_replay_;
  EditTimeline timeline_;
  PoseCorrection correction_;
  std::function<void(const MapReplaced&)> listener_;
  FrameAdmission admission_;
  std::atomic<uint64_t> regions_cleared_{0}, clears_refused_{0};
  std::chrono::steady_clock::time_point last_checkpoint_ = std::chrono::steady_clock::now();
  std::chrono::steady_clock::time_point last_fused_ = std::chrono::steady_clock::now();
  std::string checkpoint_note_;
  std::string store_error_;       // why the map store could not be opened
  CorrectionWorker corrections_;  // last: its thread stops before the members above go
};

}  // namespace stereo_fusion
