#pragma once
// The node's services on the map: ~save_mesh, ~get_full_mesh, ~reset, ~save_map, ~load_map,
// ~clear_box, ~clear_sphere. They run on the manager's multi-threaded queue: writing a large
// map or mesh (seconds on a robot's flash) must not stop frames from arriving.
#include <ros/ros.h>
#include <std_srvs/Empty.h>
#include <stereo_fusion/ClearBox.h>
#include <stereo_fusion/ClearSphere.h>
#include <stereo_fusion/GetFullMesh.h>
#include <stereo_fusion/LoadMap.h>
#include <stereo_fusion/SaveMap.h>
#include <stereo_fusion/SaveMesh.h>

#include "stereo_fusion/ros/MeshPublisher.h"
#include "stereo_fusion/session/MappingSession.h"

namespace stereo_fusion {

class MapServices {
 public:
  /// Advertises on `service_nh` (the nodelet's multi-threaded private handle).
  MapServices(ros::NodeHandle& service_nh, MappingSession* session, MeshPublisher* publisher);

 private:
  bool saveMesh(SaveMesh::Request& req, SaveMesh::Response& res);
  bool getFullMesh(GetFullMesh::Request& req, GetFullMesh::Response& res);
  bool reset(std_srvs::Empty::Request& req, std_srvs::Empty::Response& res);
  bool saveMap(SaveMap::Request& req, SaveMap::Response& res);
  bool loadMap(LoadMap::Request& req, LoadMap::Response& res);
  bool clearBox(ClearBox::Request& req, ClearBox::Response& res);
  bool clearSphere(ClearSphere::Request& req, ClearSphere::Response& res);
  template <typename Response>
  bool clearRegion(const MapRegion& region, Response* res);

  MappingSession* session_;
  MeshPublisher* publisher_;
  std::vector<ros::ServiceServer> servers_;
};

}  // namespace stereo_fusion
