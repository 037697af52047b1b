#include "stereo_fusion/ros/CallbackQueueHold.h"

namespace stereo_fusion {

void CallbackQueueHold::hold(std::initializer_list<ros::CallbackQueueInterface*> queues) {
  for (ros::CallbackQueueInterface* queue : queues) {
    auto* managed = dynamic_cast<nodelet::detail::CallbackQueue*>(queue);
    if (managed != nullptr) held_.push_back(managed->shared_from_this());
  }
}

}  // namespace stereo_fusion
