#pragma once
// Building and serialising large messages off the frame worker and the map lock: the jobs
// handed over (copies of what they send) run on a thread of their own, one at a time, in the
// order handed over, so a subscriber sees them in that order.
#include <condition_variable>
#include <deque>
#include <functional>
#include <mutex>
#include <string>
#include <thread>

namespace stereo_fusion {

class SendThread {
 public:
  /// `what` names the output in the error a failing job logs (the next job still runs).
  explicit SendThread(std::string what);
  /// Stops after the job in hand; jobs still queued are dropped (the node is going).
  ~SendThread();
  SendThread(const SendThread&) = delete;
  SendThread& operator=(const SendThread&) = delete;

  void post(std::function<void()> job);
  /// Nothing queued or running.
  bool idle() const;
  /// Returns when every job posted so far has run.
  void flush();

 private:
  void run();

  const std::string what_;
  mutable std::mutex mutex_;
  std::condition_variable wake_, done_;
  std::deque<std::function<void()>> queue_;  // guarded by mutex_
  bool running_job_ = false;                 // guarded by mutex_
  bool stopping_ = false;                    // guarded by mutex_
  std::thread thread_;                       // last: started once the members above exist
};

}  // namespace stereo_fusion
