#include "stereo_fusion/map/MapRegion.h"

#include <cmath>
#include <cstdio>

namespace stereo_fusion {

MapRegion MapRegion::box(const Eigen::Vector3d& min_m, const Eigen::Vector3d& max_m) {
  MapRegion region;
  region.shape = Shape::kBox;
  region.box_m = Eigen::AlignedBox3d(min_m, max_m);
  return region;
}

MapRegion MapRegion::sphere(const Eigen::Vector3d& centre_m, double radius_m) {
  MapRegion region;
  region.shape = Shape::kSphere;
  region.centre_m = centre_m;
  region.radius_m = radius_m;
  return region;
}

std::string MapRegion::validate() const {
  if (shape == Shape::kBox) {
    if (!box_m.min().allFinite() || !box_m.max().allFinite())
      return "the box's corners must be finite numbers";
    if ((box_m.min().array() > box_m.max().array()).any())
      return "the box's min must not exceed its max on any axis (" + describe() + ")";
    return "";
  }
  if (!centre_m.allFinite() || !std::isfinite(radius_m))
    return "the sphere's centre and radius must be finite numbers";
  if (radius_m <= 0.0) return "the sphere's radius must be positive (" + describe() + ")";
  return "";
}

bool MapRegion::contains(const Eigen::Vector3d& point_m) const {
  if (shape == Shape::kBox) return box_m.contains(point_m);
  return (point_m - centre_m).squaredNorm() <= radius_m * radius_m;
}

bool MapRegion::intersects(const Eigen::AlignedBox3d& other_m) const {
  if (shape == Shape::kBox) return !box_m.intersection(other_m).isEmpty();
  // The box's point nearest the centre.
  return other_m.squaredExteriorDistance(centre_m) <= radius_m * radius_m;
}

bool MapRegion::containsBox(const Eigen::AlignedBox3d& other_m) const {
  if (shape == Shape::kBox) return box_m.contains(other_m);
  // The box's corner farthest from the centre.
  const Eigen::Vector3d far =
      (other_m.min() - centre_m).cwiseAbs().cwiseMax((other_m.max() - centre_m).cwiseAbs());
  return far.squaredNorm() <= radius_m * radius_m;
}

std::string MapRegion::describe() const {
  char text[160];
  if (shape == Shape::kBox)
    std::snprintf(text, sizeof(text), "box [%g %g %g]-[%g %g %g] m", box_m.min().x(),
                  box_m.min().y(), box_m.min().z(), box_m.max().x(), box_m.max().y(),
                  box_m.max().z());
  else
    std::snprintf(text, sizeof(text), "sphere centre [%g %g %g] m, radius %g m", centre_m.x(),
                  centre_m.y(), centre_m.z(), radius_m);
  return text;
}

}  // namespace stereo_fusion
