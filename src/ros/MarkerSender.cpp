#include "stereo_fusion/ros/MarkerSender.h"

#include <ros/console.h>

#include <exception>
#include <utility>

namespace stereo_fusion {

MarkerSender::MarkerSender(Publish publish)
    : publish_(std::move(publish)), thread_([this] { run(); }) {}

MarkerSender::~MarkerSender() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
  }
  wake_.notify_all();
  thread_.join();
}

bool MarkerSender::idle() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return queue_.empty() && !building_;
}

void MarkerSender::send(const std::unordered_map<BlockKey, SubMesh, BlockKeyHash>& submeshes,
                        const std::vector<BlockKey>& changed, const std::vector<BlockKey>& removed,
                        const std_msgs::Header& header) {
  Batch batch;
  for (const BlockKey& key : changed) {
    const auto it = submeshes.find(key);
    if (it != submeshes.end()) batch.submeshes.emplace(key, it->second);
  }
  batch.changed = changed;
  batch.removed = removed;
  batch.header = header;
  enqueue(std::move(batch));
}

void MarkerSender::sendClear(const std_msgs::Header& header) {
  Batch batch;
  batch.clear = true;
  batch.header = header;
  enqueue(std::move(batch));
}

void MarkerSender::enqueue(Batch&& batch) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    queue_.push_back(std::move(batch));
  }
  wake_.notify_one();
}

void MarkerSender::flush() {
  std::unique_lock<std::mutex> lock(mutex_);
  done_.wait(lock, [&] { return (queue_.empty() && !building_) || stopping_; });
}

void MarkerSender::run() {
  std::unique_lock<std::mutex> lock(mutex_);
  while (true) {
    wake_.wait(lock, [&] { return stopping_ || !queue_.empty(); });
    if (stopping_) break;
    Batch batch = std::move(queue_.front());
    queue_.pop_front();
    building_ = true;
    lock.unlock();
    try {
      publish_(batch.clear
                   ? markers_.clear(batch.header)
                   : markers_.build(batch.submeshes, batch.changed, batch.removed, batch.header));
    } catch (const std::exception& e) {  // e.g. out of memory for a huge array: the next goes on
      ROS_ERROR_THROTTLE(5.0, "stereo_fusion: ~mesh_markers not sent: %s", e.what());
    }
    batch = Batch();  // the copies are freed off the lock
    lock.lock();
    building_ = false;
    done_.notify_all();
  }
  done_.notify_all();
}

}  // namespace stereo_fusion
