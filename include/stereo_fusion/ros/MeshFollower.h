#pragma once
// A subscriber's copy of the robot's mesh that never blocks on the network: the rviz display's
// bookkeeping of ~mesh_update. No ROS master, no rviz: it applies MeshUpdate messages with
// applyMeshUpdate() (the assembler's decoder), follows `session` and `sequence` as the
// MeshAssembler does, says when the whole mesh should be fetched (~get_full_mesh) and which
// blocks changed since the caller last looked, so a display redraws only those.

#include <stereo_fusion/MeshUpdate.h>

#include <cstdint>
#include <deque>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include "stereo_fusion/mesh/SubMesh.h"

namespace stereo_fusion {

class MeshFollower {
 public:
  using Mesh = std::unordered_map<BlockKey, SubMesh, BlockKeyHash>;

  /// What became of one update offered to update().
  enum class Outcome {
    kApplied,     ///< the next in sequence (or a full mesh): the copy is the robot's
    kBestEffort,  ///< applied although the copy is not the robot's (first update, a gap, a
                  ///< restart): its blocks are right, blocks it did not touch may be stale
    kIgnoredOld,  ///< already held (sequence at or below the copy's, same session), or a full
                  ///< mesh older than the copy
    kQueued,      ///< a full mesh is being fetched: applied after it (fullMeshArrived())
    kMalformed,   ///< refused by applyMeshUpdate(): nothing changed
  };

  /// Updates held while a full mesh is fetched; older ones beyond it are dropped (counted):
  /// the full mesh covers them unless the fetch fails.
  static constexpr size_t kMaxQueued = 100;

  /// Applies `update` (full: replaces everything held). A block without triangles is removed
  /// like a key in `removed_keys`. A new `session` drops the copy first (the robot restarted and
  /// rebuilt its mesh).
  Outcome update(const MeshUpdate& update);

  /// True when the copy is not known to be the robot's (nothing fetched yet, a gap, a restart,
  /// a malformed update) and no fetch is under way: the caller should fetch ~get_full_mesh and
  /// call fetchStarted() / fullMeshArrived() / fetchFailed().
  bool wantsFullMesh() const { return !synced_ && !fetching_; }
  void fetchStarted() { fetching_ = true; }
  /// Replaces the copy by `full` (its `full` flag need not be set), then applies the updates
  /// queued meanwhile that follow it. Returns the outcome of the full mesh itself.
  Outcome fullMeshArrived(const MeshUpdate& full);
  /// The fetch gave nothing (no service, a timeout): the queued updates are applied as they are.
  void fetchFailed();

  /// Forgets everything (every block held becomes dirty): the next update or fetch starts over.
  void reset();

  const Mesh& mesh() const { return mesh_; }
  bool synced() const { return synced_; }
  bool fetching() const { return fetching_; }
  uint64_t session() const { return session_; }
  uint64_t lastSequence() const { return last_sequence_; }
  /// Keys whose submesh changed or disappeared since the last call; look each up in mesh()
  /// (absent: erase its drawing).
  std::vector<BlockKey> takeDirty();

  // Counters: each update not applied cleanly is counted once under its reason.
  uint64_t gaps() const { return gaps_; }                   ///< updates missed (sum of gaps)
  uint64_t restarts() const { return restarts_; }           ///< new sessions of the publisher
  uint64_t malformed() const { return malformed_; }         ///< updates refused
  uint64_t ignoredOld() const { return ignored_old_; }      ///< duplicates and stale full meshes
  uint64_t queueDropped() const { return queue_dropped_; }  ///< beyond kMaxQueued while fetching

 private:
  Outcome apply(const MeshUpdate& update);
  /// Applies `update` to mesh_ and marks what it touched; false when malformed.
  bool applyAndMark(const MeshUpdate& update);
  void drainQueue();

  Mesh mesh_;
  std::unordered_set<BlockKey, BlockKeyHash> dirty_;
  std::deque<MeshUpdate> queued_;
  bool synced_ = false;
  bool fetching_ = false;
  bool have_session_ = false;
  uint64_t session_ = 0;
  uint64_t last_sequence_ = 0;
  uint64_t gaps_ = 0, restarts_ = 0, malformed_ = 0, ignored_old_ = 0, queue_dropped_ = 0;
};

}  // namespace stereo_fusion
