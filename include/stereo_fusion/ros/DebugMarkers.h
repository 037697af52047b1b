#pragma once
// rviz helpers beside the mesh: the current camera frustum and the bounds of the meshed blocks.

#include <visualization_msgs/Marker.h>

#include <Eigen/Geometry>
#include <unordered_map>

#include "stereo_fusion/camera/StereoCamera.h"
#include "stereo_fusion/mesh/SubMesh.h"

namespace stereo_fusion {

/// The viewing frustum of `camera` at T_world_camera as a LINE_LIST (namespace "frustum"): the
/// four edges from the optical centre to the image corners at `depth_m`, and that far rectangle.
visualization_msgs::Marker frustumMarker(const StereoCamera& camera,
                                         const Eigen::Isometry3d& T_world_camera, double depth_m,
                                         const std_msgs::Header& header);

/// The twelve edges of every block that has a submesh as one LINE_LIST (namespace "blocks"),
/// coloured by the level the block was meshed at: 0 green, 1 yellow, 2 red.
visualization_msgs::Marker blockBoundsMarker(
    const std::unordered_map<BlockKey, SubMesh, BlockKeyHash>& submeshes, double block_size_m,
    const std_msgs::Header& header);

}  // namespace stereo_fusion
