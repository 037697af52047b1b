#include "stereo_fusion/ros/MeshFollower.h"

#include "stereo_fusion/ros/MeshMessages.h"

namespace stereo_fusion {

MeshFollower::Outcome MeshFollower::update(const MeshUpdate& update) {
  if (fetching_) {
    queued_.push_back(update);
    if (queued_.size() > kMaxQueued) {
      queued_.pop_front();
      ++queue_dropped_;
    }
    return Outcome::kQueued;
  }
  return apply(update);
}

MeshFollower::Outcome MeshFollower::apply(const MeshUpdate& update) {
  const bool same_session = have_session_ && update.session == session_;
  if (update.full) {
    // A late reply or message of the same run older than the copy would undo newer updates.
    if (synced_ && same_session && update.sequence < last_sequence_) {
      ++ignored_old_;
      return Outcome::kIgnoredOld;
    }
    if (!applyAndMark(update)) return Outcome::kMalformed;
    synced_ = true;
    have_session_ = true;
    session_ = update.session;
    last_sequence_ = update.sequence;
    return Outcome::kApplied;
  }
  if (have_session_ && !same_session) {
    // The robot restarted: what is held is the old run's map, and the new run's sequence
    // numbers say nothing about it. Drop it; the new run's blocks are drawn as they come.
    ++restarts_;
    for (const auto& [key, submesh] : mesh_) dirty_.insert(key);
    mesh_.clear();
    synced_ = false;
  } else if (have_session_ && update.sequence <= last_sequence_) {
    ++ignored_old_;
    return Outcome::kIgnoredOld;
  } else if (synced_ && update.sequence != last_sequence_ + 1) {
    gaps_ += update.sequence - last_sequence_ - 1;
    synced_ = false;
  }
  if (!applyAndMark(update)) return Outcome::kMalformed;
  have_session_ = true;
  session_ = update.session;
  last_sequence_ = update.sequence;
  return synced_ ? Outcome::kApplied : Outcome::kBestEffort;
}

bool MeshFollower::applyAndMark(const MeshUpdate& update) {
  if (update.full)
    for (const auto& [key, submesh] : mesh_) dirty_.insert(key);
  if (!applyMeshUpdate(update, &mesh_)) {
    ++malformed_;
    synced_ = false;  // the robot's copy moved on without us: repair from a full mesh
    return false;
  }
  for (size_t i = 0; i + 2 < update.removed_keys.size(); i += 3)
    dirty_.insert({update.removed_keys[i], update.removed_keys[i + 1], update.removed_keys[i + 2]});
  for (const MeshBlock& b : update.blocks) {
    const BlockKey key{b.key[0], b.key[1], b.key[2]};
    dirty_.insert(key);
    auto it = mesh_.find(key);
    if (it != mesh_.end() && it->second.triangles.empty()) mesh_.erase(it);
  }
  return true;
}

MeshFollower::Outcome MeshFollower::fullMeshArrived(const MeshUpdate& full) {
  fetching_ = false;
  MeshUpdate whole = full;
  whole.full = true;
  const Outcome outcome = apply(whole);
  drainQueue();
  return outcome;
}

void MeshFollower::fetchFailed() {
  fetching_ = false;
  drainQueue();
}

void MeshFollower::drainQueue() {
  while (!queued_.empty() && !fetching_) {
    const MeshUpdate next = std::move(queued_.front());
    queued_.pop_front();
    apply(next);
  }
}

void MeshFollower::reset() {
  for (const auto& [key, submesh] : mesh_) dirty_.insert(key);
  mesh_.clear();
  queued_.clear();
  synced_ = fetching_ = have_session_ = false;
  session_ = last_sequence_ = 0;
}

std::vector<BlockKey> MeshFollower::takeDirty() {
  std::vector<BlockKey> keys(dirty_.begin(), dirty_.end());
  dirty_.clear();
  return keys;
}

}  // namespace stereo_fusion
