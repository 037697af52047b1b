#include "stereo_fusion/ros/UndecodableImages.h"

#include <list>
#include <mutex>

namespace stereo_fusion {

namespace {

struct Entry {
  uint64_t id;
  std::string topic;
  UndecodableImages::Listener listener;
};

struct Registry {
  // Held while a listener runs: a Listening destroyed meanwhile waits, so no listener is called
  // on an object that is gone.
  std::mutex mutex;
  std::list<Entry> entries;
  uint64_t next_id = 1;
};

Registry& registry() {
  // Never destroyed: a plugin or listener released during exit may still reach it.
  static Registry* instance = new Registry;
  return *instance;
}

}  // namespace

UndecodableImages::Listening::~Listening() {
  Registry& r = registry();
  std::lock_guard<std::mutex> lock(r.mutex);
  r.entries.remove_if([&](const Entry& e) { return e.id == id_; });
}

std::unique_ptr<UndecodableImages::Listening> UndecodableImages::listen(
    const std::string& transport_topic, Listener listener) {
  Registry& r = registry();
  std::lock_guard<std::mutex> lock(r.mutex);
  const uint64_t id = r.next_id++;
  r.entries.push_back({id, transport_topic, std::move(listener)});
  return std::make_unique<Listening>(id);
}

bool UndecodableImages::report(const std::string& transport_topic, const std_msgs::Header& header,
                               const std::string& error) {
  Registry& r = registry();
  std::lock_guard<std::mutex> lock(r.mutex);
  bool heard = false;
  for (const Entry& e : r.entries)
    if (e.topic == transport_topic) {
      e.listener(header, error);
      heard = true;
    }
  return heard;
}

}  // namespace stereo_fusion
