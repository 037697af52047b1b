#pragma once
#include <Eigen/Geometry>
#include <string>

namespace stereo_fusion {

/// A region of the world (world frame, metres) that an operator or a planner asks the map to
/// forget: an axis-aligned box or a sphere (services ~clear_box, ~clear_sphere).
struct MapRegion {
  enum class Shape { kBox, kSphere };

  static MapRegion box(const Eigen::Vector3d& min_m, const Eigen::Vector3d& max_m);
  static MapRegion sphere(const Eigen::Vector3d& centre_m, double radius_m);

  /// Empty if the region is usable; otherwise one sentence saying what is wrong (a coordinate
  /// not finite, a box whose min exceeds its max, a radius not positive).
  std::string validate() const;
  /// The point lies inside or on the boundary.
  bool contains(const Eigen::Vector3d& point_m) const;
  /// The box and the region share a point (a conservative test is not enough: a block the
  /// region does not reach must not be visited).
  bool intersects(const Eigen::AlignedBox3d& box_m) const;
  /// Every point of the box lies in the region.
  bool containsBox(const Eigen::AlignedBox3d& box_m) const;
  /// One line for logs, e.g. "box [0 0 0]–[1 1 1] m" or "sphere centre [0 0 1] m, radius 0.5 m".
  std::string describe() const;

  Shape shape = Shape::kBox;
  Eigen::AlignedBox3d box_m;                           ///< kBox
  Eigen::Vector3d centre_m = Eigen::Vector3d::Zero();  ///< kSphere
  double radius_m = 0.0;                               ///< kSphere
};

}  // namespace stereo_fusion
