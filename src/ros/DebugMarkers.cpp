#include "stereo_fusion/ros/DebugMarkers.h"

namespace stereo_fusion {

namespace {

geometry_msgs::Point toPoint(const Eigen::Vector3d& p) {
  geometry_msgs::Point q;
  q.x = p.x();
  q.y = p.y();
  q.z = p.z();
  return q;
}

visualization_msgs::Marker lineList(const std_msgs::Header& header, const char* ns,
                                    double width_m) {
  visualization_msgs::Marker m;
  m.header = header;
  m.ns = ns;
  m.id = 0;
  m.type = visualization_msgs::Marker::LINE_LIST;
  m.action = visualization_msgs::Marker::ADD;
  m.pose.orientation.w = 1.0;
  m.scale.x = width_m;
  m.color.a = 1.0f;
  return m;
}

}  // namespace

visualization_msgs::Marker frustumMarker(const StereoCamera& camera,
                                         const Eigen::Isometry3d& T_world_camera, double depth_m,
                                         const std_msgs::Header& header) {
  visualization_msgs::Marker m = lineList(header, "frustum", 0.01);
  m.color.r = 0.1f;
  m.color.g = 0.6f;
  m.color.b = 1.0f;
  // Image corners (pixel edges, not centres) back-projected to depth_m in the camera frame.
  const double us[4] = {-0.5, camera.width() - 0.5, camera.width() - 0.5, -0.5};
  const double vs[4] = {-0.5, -0.5, camera.height() - 0.5, camera.height() - 0.5};
  Eigen::Vector3d corners[4];
  for (int k = 0; k < 4; ++k)
    corners[k] =
        T_world_camera * Eigen::Vector3d((us[k] - camera.cx()) / camera.fx() * depth_m,
                                         (vs[k] - camera.cy()) / camera.fy() * depth_m, depth_m);
  const Eigen::Vector3d centre = T_world_camera.translation();
  for (int k = 0; k < 4; ++k) {
    m.points.push_back(toPoint(centre));
    m.points.push_back(toPoint(corners[k]));
    m.points.push_back(toPoint(corners[k]));
    m.points.push_back(toPoint(corners[(k + 1) % 4]));
  }
  return m;
}

visualization_msgs::Marker blockBoundsMarker(
    const std::unordered_map<BlockKey, SubMesh, BlockKeyHash>& submeshes, double block_size_m,
    const std_msgs::Header& header) {
  visualization_msgs::Marker m = lineList(header, "blocks", 0.002);
  static const float kLevelColor[3][3] = {
      {0.2f, 0.8f, 0.2f}, {0.9f, 0.8f, 0.1f}, {0.9f, 0.2f, 0.2f}};
  for (const auto& [key, sub] : submeshes) {
    const Eigen::Vector3d o(key.x * block_size_m, key.y * block_size_m, key.z * block_size_m);
    std_msgs::ColorRGBA c;
    const int level = std::max(0, std::min(2, sub.level));
    c.r = kLevelColor[level][0];
    c.g = kLevelColor[level][1];
    c.b = kLevelColor[level][2];
    c.a = 1.0f;
    // The 12 edges: from every corner with bit a clear, along axis a.
    for (int corner = 0; corner < 8; ++corner)
      for (int a = 0; a < 3; ++a) {
        if (corner & (1 << a)) continue;
        const Eigen::Vector3d p0 =
            o + block_size_m * Eigen::Vector3d(corner & 1, (corner >> 1) & 1, (corner >> 2) & 1);
        Eigen::Vector3d p1 = p0;
        p1[a] += block_size_m;
        m.points.push_back(toPoint(p0));
        m.points.push_back(toPoint(p1));
        m.colors.push_back(c);
        m.colors.push_back(c);
      }
  }
  if (m.points.empty())
    m.action = visualization_msgs::Marker::DELETE;  // rviz rejects an empty LINE_LIST
  return m;
}

}  // namespace stereo_fusion
