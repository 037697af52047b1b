#pragma once
#include <cstddef>
#include <string>
#include <vector>

#include "stereo_fusion/map/BlockKey.h"

namespace stereo_fusion {

/// Which blocks of a layer changed, kept for every consumer until it takes them, so that the
/// stage that writes a layer reports each change once and every stage that reads it (the mesher
/// after fusion, the texture pass and the nodelet's publisher after the mesher, later an ESDF)
/// catches up at its own rate. A new consumer is one subscribe() call: no stage that writes the
/// layer changes.
///
/// A block is reported as updated (its data changed, it may be new) or erased (it left the map).
/// take() returns where each block ended: a block erased and later updated again is updated;
/// one updated and then erased is erased.
///
/// Not thread-safe: the Mapper records between stages on its integrating thread.
class BlockChangeLog {
 public:
  using Consumer = int;

  /// What changed for one consumer since its last take(): sorted by key, each key once.
  struct Changes {
    std::vector<BlockKey> updated;
    std::vector<BlockKey> erased;
    bool empty() const { return updated.empty() && erased.empty(); }
  };

  /// Registers a consumer (named for messages); it sees the changes recorded from now on.
  Consumer subscribe(const std::string& name);
  const std::string& name(Consumer consumer) const { return consumers_[consumer].name; }

  void recordUpdated(const std::vector<BlockKey>& keys) { record(keys, false); }
  void recordErased(const std::vector<BlockKey>& keys) { record(keys, true); }

  /// The changes `consumer` has not taken yet; it starts afresh.
  Changes take(Consumer consumer);
  /// What take() would return, leaving the changes where they are (a checkpoint keeps them).
  Changes peek(Consumer consumer) const;
  /// Records `changes` for `consumer` alone (a resumed map: what it had not taken).
  void restore(Consumer consumer, const Changes& changes);
  size_t consumerCount() const { return consumers_.size(); }
  /// Changes recorded for `consumer` and not taken yet (a key recorded twice counts twice).
  size_t pending(Consumer consumer) const { return consumers_[consumer].events.size(); }
  /// Appends the keys every consumer has not taken yet (unsorted, repeated as recorded).
  void appendPending(std::vector<BlockKey>* out) const;
  /// The same for one consumer.
  void appendPending(Consumer consumer, std::vector<BlockKey>* out) const;
  /// Forgets every pending change of every consumer (after a reset or a loaded map, which
  /// consumers rebuild from scratch).
  void clear();

 private:
  struct Event {
    BlockKey key;
    bool erased;
  };
  struct ConsumerLog {
    std::string name;
    std::vector<Event> events;  // in recording order
  };
  void record(const std::vector<BlockKey>& keys, bool erased);
  /// A consumer's events as take() reports them: each key once, where it ended.
  static Changes compact(std::vector<Event> events);

  std::vector<ConsumerLog> consumers_;
};

}  // namespace stereo_fusion
