#include "stereo_fusion/map/BlockChangeLog.h"

#include <algorithm>

namespace stereo_fusion {

BlockChangeLog::Consumer BlockChangeLog::subscribe(const std::string& name) {
  consumers_.push_back({name, {}});
  return static_cast<Consumer>(consumers_.size() - 1);
}

void BlockChangeLog::record(const std::vector<BlockKey>& keys, bool erased) {
  for (ConsumerLog& consumer : consumers_)
    for (const BlockKey& key : keys) consumer.events.push_back({key, erased});
}

BlockChangeLog::Changes BlockChangeLog::take(Consumer consumer) {
  std::vector<Event> events;
  events.swap(consumers_[consumer].events);
  return compact(std::move(events));
}

BlockChangeLog::Changes BlockChangeLog::peek(Consumer consumer) const {
  return compact(consumers_[consumer].events);
}

void BlockChangeLog::restore(Consumer consumer, const Changes& changes) {
  std::vector<Event>& events = consumers_[consumer].events;
  for (const BlockKey& key : changes.updated) events.push_back({key, false});
  for (const BlockKey& key : changes.erased) events.push_back({key, true});
}

BlockChangeLog::Changes BlockChangeLog::compact(std::vector<Event> events) {
  // Stable: among a key's events the last recorded stays last, and it decides.
  std::stable_sort(events.begin(), events.end(),
                   [](const Event& a, const Event& b) { return a.key < b.key; });
  Changes changes;
  for (size_t i = 0; i < events.size(); ++i) {
    if (i + 1 < events.size() && events[i + 1].key == events[i].key) continue;
    (events[i].erased ? changes.erased : changes.updated).push_back(events[i].key);
  }
  return changes;
}

void BlockChangeLog::appendPending(std::vector<BlockKey>* out) const {
  for (const ConsumerLog& consumer : consumers_)
    for (const Event& event : consumer.events) out->push_back(event.key);
}

void BlockChangeLog::appendPending(Consumer consumer, std::vector<BlockKey>* out) const {
  for (const Event& event : consumers_[consumer].events) out->push_back(event.key);
}

void BlockChangeLog::clear() {
  for (ConsumerLog& consumer : consumers_) consumer.events.clear();
}

}  // namespace stereo_fusion
