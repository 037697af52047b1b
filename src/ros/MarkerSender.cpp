#include "stereo_fusion/ros/MarkerSender.h"

#include <memory>
#include <utility>

namespace stereo_fusion {

MarkerSender::MarkerSender(Publish publish)
    : publish_(std::move(publish)), thread_("~mesh_markers") {}

void MarkerSender::send(const std::unordered_map<BlockKey, SubMesh, BlockKeyHash>& submeshes,
                        const std::vector<BlockKey>& changed, const std::vector<BlockKey>& removed,
                        const std_msgs::Header& header) {
  auto copies = std::make_shared<std::unordered_map<BlockKey, SubMesh, BlockKeyHash>>();
  for (const BlockKey& key : changed) {
    const auto it = submeshes.find(key);
    if (it != submeshes.end()) copies->emplace(key, it->second);
  }
  thread_.post([this, copies, changed, removed, header] {
    publish_(markers_.build(*copies, changed, removed, header));
  });
}

void MarkerSender::sendClear(const std_msgs::Header& header) {
  thread_.post([this, header] { publish_(markers_.clear(header)); });
}

}  // namespace stereo_fusion
