#include "stereo_fusion/ros/SendThread.h"

#include <ros/console.h>

#include <exception>
#include <utility>

namespace stereo_fusion {

SendThread::SendThread(std::string what) : what_(std::move(what)), thread_([this] { run(); }) {}

SendThread::~SendThread() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
  }
  wake_.notify_all();
  thread_.join();
}

void SendThread::post(std::function<void()> job) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    queue_.push_back(std::move(job));
  }
  wake_.notify_one();
}

bool SendThread::idle() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return queue_.empty() && !running_job_;
}

void SendThread::flush() {
  std::unique_lock<std::mutex> lock(mutex_);
  done_.wait(lock, [&] { return (queue_.empty() && !running_job_) || stopping_; });
}

void SendThread::run() {
  std::unique_lock<std::mutex> lock(mutex_);
  while (true) {
    wake_.wait(lock, [&] { return stopping_ || !queue_.empty(); });
    if (stopping_) break;
    std::function<void()> job = std::move(queue_.front());
    queue_.pop_front();
    running_job_ = true;
    lock.unlock();
    try {
      job();
    } catch (const std::exception& e) {  // e.g. out of memory for a huge message
      ROS_ERROR_THROTTLE(5.0, "stereo_fusion: %s not sent: %s", what_.c_str(), e.what());
    }
    job = nullptr;  // what it copied is freed off the lock
    lock.lock();
    running_job_ = false;
    done_.notify_all();
  }
  done_.notify_all();
}

}  // namespace stereo_fusion
