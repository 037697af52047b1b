#pragma once
// ~mesh_markers off the frame worker: rviz's triangle lists cost ~84 B a triangle to build and
// as much to serialise (at 1 cm, 16-30 ms every half second on the worker, which frames queued
// behind). The mesh publisher hands over copies of the changed submeshes under the map lock;
// a SendThread builds and publishes them, in the order handed over.
#include <visualization_msgs/MarkerArray.h>

#include <functional>
#include <unordered_map>
#include <vector>

#include "stereo_fusion/ros/MeshMessages.h"
#include "stereo_fusion/ros/SendThread.h"

namespace stereo_fusion {

class MarkerSender {
 public:
  using Publish = std::function<void(const visualization_msgs::MarkerArray&)>;
  /// `publish` is called on the sender's thread, one array at a time.
  explicit MarkerSender(Publish publish);

  /// Nothing queued or being built: the mesh publisher keeps merging its backlog until then,
  /// so a slow subscriber's markers fall behind in time, not in memory.
  bool idle() const { return thread_.idle(); }
  /// Queues the markers of `changed` (their submeshes copied from `submeshes` now; a key
  /// without one is skipped) and a DELETE for each of `removed`.
  void send(const std::unordered_map<BlockKey, SubMesh, BlockKeyHash>& submeshes,
            const std::vector<BlockKey>& changed, const std::vector<BlockKey>& removed,
            const std_msgs::Header& header);
  /// Queues a DELETEALL (a reset), after what is queued already.
  void sendClear(const std_msgs::Header& header);
  /// Returns when everything queued so far has been published.
  void flush() { thread_.flush(); }

 private:
  Publish publish_;
  MeshMarkers markers_;  // its ids: touched by the sender's thread only
  SendThread thread_;    // last: stopped before the members its jobs use go
};

}  // namespace stereo_fusion
