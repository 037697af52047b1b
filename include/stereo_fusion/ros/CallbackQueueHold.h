#pragma once
// Keeps a nodelet's two callback queues alive until the nodelet itself is destroyed.
//
// nodelet's Loader frees a nodelet's queues when it unloads it (shutdown, unload service, broken
// bond). While one of the nodelet's callbacks runs, the worker thread calling it holds the
// nodelet, so the nodelet outlives that unload and is destroyed afterwards on the worker, after
// its queues: its subscribers and timers then unregister from freed memory (TSan: "use of an
// invalid mutex" in ros::CallbackQueue::removeByID). A nodelet holding a CallbackQueueHold as its
// first member unregisters everything from live queues, whoever drops it last.

#include <nodelet/detail/callback_queue.h>
#include <ros/callback_queue_interface.h>

#include <boost/shared_ptr.hpp>
#include <initializer_list>
#include <vector>

namespace stereo_fusion {

class CallbackQueueHold {
 public:
  /// Holds those of `queues` that a nodelet manager created (a nodelet initialised on the global
  /// queue, or on a queue the caller owns, holds nothing).
  void hold(std::initializer_list<ros::CallbackQueueInterface*> queues);

 private:
  std::vector<boost::shared_ptr<nodelet::detail::CallbackQueue>> held_;
};

}  // namespace stereo_fusion
