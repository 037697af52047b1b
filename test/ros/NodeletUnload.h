#pragma once
// A nodelet unloaded while one of its callbacks runs: the manager's worker thread holds the
// nodelet through that callback and destroys it afterwards, after the Loader has let go of the
// nodelet's callback queues. Shared by the tests of each nodelet of the package.

#include <gtest/gtest.h>
#include <nodelet/detail/callback_queue.h>
#include <nodelet/loader.h>

#include <boost/make_shared.hpp>
#include <boost/weak_ptr.hpp>
#include <string>
#include <vector>

namespace stereo_fusion::test {

/// Loads a `NodeletType` under `name` into a Loader of this process, unloads it while the test
/// still holds it (as a worker thread does while it runs one of its callbacks), and expects its
/// two callback queues to live exactly until the nodelet is destroyed: it unregisters its
/// subscribers, timers and services from live queues, and nothing of it is kept after.
template <class NodeletType>
void expectQueuesLiveUntilTheNodeletIsDestroyed(const std::string& name) {
  struct Probe : NodeletType {
    using nodelet::Nodelet::getMTCallbackQueue;
    using nodelet::Nodelet::getSTCallbackQueue;
  };
  boost::shared_ptr<Probe> nodelet;
  nodelet::Loader loader([&nodelet](const std::string&) {
    nodelet = boost::make_shared<Probe>();
    return nodelet;
  });
  ASSERT_TRUE(loader.load(name, "probe", {}, {}));
  std::vector<boost::weak_ptr<nodelet::detail::CallbackQueue>> queues;
  for (ros::CallbackQueueInterface* queue :
       {&nodelet->getSTCallbackQueue(), &nodelet->getMTCallbackQueue()}) {
    auto* managed = dynamic_cast<nodelet::detail::CallbackQueue*>(queue);
    ASSERT_NE(managed, nullptr) << "the Loader did not give the nodelet queues of its own";
    queues.emplace_back(managed->shared_from_this());
  }
  ASSERT_TRUE(loader.unload(name));
  for (const auto& queue : queues) {
    EXPECT_FALSE(queue.expired()) << "a queue was freed while its nodelet lives";
  }
  nodelet.reset();  // the destructor runs here, as on the worker after its last callback
  for (const auto& queue : queues) {
    EXPECT_TRUE(queue.expired()) << "a queue outlives its nodelet";
  }
}

}  // namespace stereo_fusion::test
