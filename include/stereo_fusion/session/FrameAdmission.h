#pragma once
#include <atomic>
#include <cstdint>

#include "stereo_fusion/integration/RejectReason.h"
#include "stereo_fusion/session/FrameStats.h"

namespace stereo_fusion {

/// Handed out when a frame arrives (MappingSession::arrive()); fuse() needs it.
struct FrameTicket {
  uint64_t epoch = 0;   ///< the map epoch: reset and load_map start a new one
  uint64_t ticket = 0;  ///< arrival order, on the same counter as clears (predates())
};

/// The session's admission of frames: the map epoch (reset and load_map start a new one, and
/// frames that arrived before are superseded), the tickets frames and clears take in arrival
/// order, and every frame's outcome counted once (RejectCounters, the fused frames' totals).
/// The tickets and the epoch change under the session's map lock; the epoch and the counters
/// are read from any thread.
class FrameAdmission {
 public:
  /// A frame arrives (map lock held): its ticket.
  FrameTicket arrive() { return {epoch_.load(), next_ticket_++}; }
  /// A clear's place in the arrival order (map lock held).
  uint64_t clearTicket() { return next_ticket_++; }
  /// False once a reset or load_map came after the ticket's arrival.
  bool isCurrent(const FrameTicket& ticket) const { return ticket.epoch == epoch_.load(); }
  /// The map epoch now.
  uint64_t epoch() const { return epoch_.load(); }
  /// A reset or load_map (map lock held): tickets handed out before are superseded.
  void newEpoch() { ++epoch_; }

  /// A frame that did not reach the map, under its reason.
  void countDrop(RejectReason reason) { drops_.count(reason); }
  /// A frame fused; `recleared`: a clear it predates was applied again after it.
  void countFused(const IntegrationResult& result, bool recleared) {
    if (recleared) ++frames_recleared_;
    ++frames_fused_;
    totals_.add(result);
  }
  /// Blocks the memory bound evicted while a frame was integrated (fused or not).
  void countEvicted(uint64_t blocks) { blocks_evicted_ += blocks; }

  const RejectCounters& drops() const { return drops_; }
  const FusedFrameTotals& fusedTotals() const { return totals_; }
  uint64_t framesFused() const { return frames_fused_.load(); }
  uint64_t framesRecleared() const { return frames_recleared_.load(); }
  uint64_t blocksEvicted() const { return blocks_evicted_.load(); }

 private:
  std::atomic<uint64_t> epoch_{0};
  uint64_t next_ticket_ = 1;  // map lock
  RejectCounters drops_;
  FusedFrameTotals totals_;
  std::atomic<uint64_t> frames_fused_{0}, frames_recleared_{0}, blocks_evicted_{0};
};

}  // namespace stereo_fusion
