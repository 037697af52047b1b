#include "stereo_fusion/ros/MapServices.h"

#include "stereo_fusion/io/MeshExport.h"

namespace stereo_fusion {

MapServices::MapServices(ros::NodeHandle& nh, MappingSession* session, MeshPublisher* publisher)
    : session_(session), publisher_(publisher) {
  servers_.push_back(nh.advertiseService("save_mesh", &MapServices::saveMesh, this));
  servers_.push_back(nh.advertiseService("get_full_mesh", &MapServices::getFullMesh, this));
  servers_.push_back(nh.advertiseService("reset", &MapServices::reset, this));
  servers_.push_back(nh.advertiseService("save_map", &MapServices::saveMap, this));
  servers_.push_back(nh.advertiseService("load_map", &MapServices::loadMap, this));
  servers_.push_back(nh.advertiseService("clear_box", &MapServices::clearBox, this));
  servers_.push_back(nh.advertiseService("clear_sphere", &MapServices::clearSphere, this));
}

bool MapServices::saveMesh(SaveMesh::Request& req, SaveMesh::Response& res) {
  // Only the copy of the mesh holds the map; the file is written while frames are fused (a slow
  // disk, or a target that blocks, must not stop fusion).
  std::unordered_map<BlockKey, SubMesh, BlockKeyHash> submeshes;
  std::unordered_map<BlockKey, TexturePatch, BlockKeyHash> patches;
  const bool got = session_->tryWithMap([&](MapAccess& map) {
    publisher_->catchUpLocked(map);                        // the mesh of every frame fused so far
    Mapper::PagedMeshParts whole = map.map().wholeMesh();  // paged-out blocks' too
    submeshes = std::move(whole.submeshes);
    patches = std::move(whole.patches);
  });
  if (!got) {
    res.success = false;
    res.message = session_->busyMessage();
    ROS_WARN("stereo_fusion: save_mesh: %s", res.message.c_str());
    return true;
  }
  res.success = exportMesh(req.path, submeshes, patches, &res.message);
  if (res.success)
    ROS_INFO("stereo_fusion: save_mesh: %s", res.message.c_str());
  else
    ROS_ERROR("stereo_fusion: save_mesh: %s", res.message.c_str());
  return true;
}

bool MapServices::getFullMesh(GetFullMesh::Request&, GetFullMesh::Response& res) {
  std::optional<MeshUpdate> mesh = publisher_->tryFullMesh();
  if (!mesh) {  // the response has no success field: the call fails, the caller retries
    ROS_WARN("stereo_fusion: get_full_mesh: %s", session_->busyMessage().c_str());
    return false;
  }
  res.mesh = std::move(*mesh);
  return true;
}

bool MapServices::reset(std_srvs::Empty::Request&, std_srvs::Empty::Response&) {
  if (!session_->reset()) {  // std_srvs/Empty has no message: the call fails, the caller retries
    ROS_WARN("stereo_fusion: reset: %s", session_->busyMessage().c_str());
    return false;
  }
  ROS_INFO("stereo_fusion: map reset");  // the publisher sent the empty map (MapReplaced)
  return true;
}

bool MapServices::saveMap(SaveMap::Request& req, SaveMap::Response& res) {
  const ros::WallTime start = ros::WallTime::now();
  if (req.path.empty()) {
    // The map store: only what changed since its last checkpoint.
    res.success = session_->checkpoint(&res.message);
    res.blocks = session_->read([](const Mapper& m) { return m.tsdf().blockCount(); });
    if (res.success)
      ROS_INFO("stereo_fusion: save_map: %s", res.message.c_str());
    else
      ROS_ERROR("stereo_fusion: save_map: %s", res.message.c_str());
    return true;
  }
  std::vector<uint8_t> bytes;
  double locked_ms = 0.0;
  // Only the copy of the blocks holds the map (at memory speed, 0.3–7 KB per block); the
  // checksums, the write and the fsync run while frames are fused.
  const bool got = session_->tryWithMap([&](MapAccess& access) {
    const ros::WallTime locked = ros::WallTime::now();
    const Mapper& map = access.map();
    bytes = map.encodeMap();
    res.blocks = map.tsdf().blockCount();
    locked_ms = (ros::WallTime::now() - locked).toSec() * 1e3;
  });
  if (!got) {
    res.success = false;
    res.message = session_->busyMessage();
    ROS_WARN("stereo_fusion: save_map: %s", res.message.c_str());
    return true;
  }
  std::string error;
  res.success = writeMapFileBytes(req.path, &bytes, &error);
  const double total_ms = (ros::WallTime::now() - start).toSec() * 1e3;
  res.message = res.success
                    ? "saved " + std::to_string(res.blocks) + " blocks to " + req.path +
                          " (map held " + std::to_string(static_cast<long>(locked_ms)) + " ms, " +
                          std::to_string(static_cast<long>(total_ms)) + " ms in all)"
                    : error;
  if (res.success)
    ROS_INFO("stereo_fusion: save_map: %s", res.message.c_str());
  else
    ROS_ERROR("stereo_fusion: save_map: %s", res.message.c_str());
  return true;
}

bool MapServices::loadMap(LoadMap::Request& req, LoadMap::Response& res) {
  const MappingSession::LoadOutcome out = session_->load(req.path);
  res.success = out.success;
  res.blocks = out.blocks;
  res.message = out.message;
  if (res.success)
    ROS_INFO("stereo_fusion: load_map: %s", res.message.c_str());
  else
    ROS_ERROR("stereo_fusion: load_map: %s", res.message.c_str());
  return true;
}

template <typename Response>
bool MapServices::clearRegion(const MapRegion& region, Response* res) {
  const MappingSession::ClearOutcome out = session_->clear(region, ros::Time::now().toSec());
  res->success = out.success;
  res->message = out.message;
  res->voxels_cleared = out.result.voxels_cleared;
  res->blocks_changed = out.result.blocks_changed;
  res->blocks_erased = out.result.blocks_erased;
  if (!out.success) {
    ROS_ERROR("stereo_fusion: clear: %s", out.message.c_str());
    return true;
  }
  // The mesh follows now, whatever the publish rate: the caller expects the region gone.
  publisher_->publishPending(ros::Time(0), true);
  ROS_INFO("stereo_fusion: %s", out.message.c_str());
  return true;
}

bool MapServices::clearBox(ClearBox::Request& req, ClearBox::Response& res) {
  return clearRegion(
      MapRegion::box({req.min.x, req.min.y, req.min.z}, {req.max.x, req.max.y, req.max.z}), &res);
}

bool MapServices::clearSphere(ClearSphere::Request& req, ClearSphere::Response& res) {
  return clearRegion(MapRegion::sphere({req.center.x, req.center.y, req.center.z}, req.radius),
                     &res);
}

}  // namespace stereo_fusion
