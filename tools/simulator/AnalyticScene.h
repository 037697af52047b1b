#pragma once
// Scenes made of analytic primitives with exact ray casting and exact signed distance:
// the ground truth for tests, the simulator and the evaluator.

#include <Eigen/Geometry>
#include <memory>
#include <opencv2/core/mat.hpp>
#include <vector>

#include "stereo_fusion/camera/StereoCamera.h"

namespace stereo_fusion {
struct TriangleMesh;
}

namespace stereo_fusion::sim {

/// A solid with an exact surface. Distances are in metres; the signed distance is negative
/// inside the solid (for a plane: on the side opposite its normal).
class Primitive {
 public:
  virtual ~Primitive() = default;
  /// Smallest t > t_min with origin + t·dir on the surface (dir normalised), or +inf.
  virtual double raycast(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir,
                         double t_min) const = 0;
  /// Euclidean signed distance to the surface (exact for plane, sphere, box, torus, cylinder).
  virtual double signedDistance(const Eigen::Vector3d& p) const = 0;
  /// Appends a triangulation of the surface to `mesh`: every vertex lies exactly on the
  /// surface (up to float rounding), normals point out of the solid, triangles are wound
  /// counter-clockwise seen from outside, colours are `base_rgb`. The grid step along each
  /// surface direction is at most `max_edge_m` (quad diagonals may be up to √2 longer) and
  /// curved surfaces use at least 24 segments around, so the chordal error is about
  /// min(max_edge_m²/(8·radius), 0.9 % of the radius) per direction of curvature. Steps below
  /// 1 mm are raised to 1 mm. Unbounded primitives (planes) append nothing: build rooms from
  /// makeRoom() or boxes when a ground-truth mesh is needed.
  virtual void tessellate(TriangleMesh* mesh, double max_edge_m) const;
  /// Base colour (RGB) modulated by the scene's procedural texture.
  Eigen::Vector3d base_rgb{200, 200, 200};
};

std::unique_ptr<Primitive> makePlane(const Eigen::Vector3d& point, const Eigen::Vector3d& normal);
std::unique_ptr<Primitive> makeSphere(const Eigen::Vector3d& centre, double radius);
/// Box with half extents `half_size` in its own frame, placed by `T_world_box`.
std::unique_ptr<Primitive> makeBox(const Eigen::Isometry3d& T_world_box,
                                   const Eigen::Vector3d& half_size);
/// The inside of a box seen from within: the solid is everything OUTSIDE the box, so the
/// signed distance is positive inside the room and raycasts from inside return the walls.
/// Tessellated normals point into the room (towards free space).
std::unique_ptr<Primitive> makeRoom(const Eigen::Isometry3d& T_world_room,
                                    const Eigen::Vector3d& half_size);
/// Capped solid cylinder around the z axis of its own frame, centred at its origin:
/// radius `radius_m`, extending ±`half_height_m` along z.
std::unique_ptr<Primitive> makeCylinder(const Eigen::Isometry3d& T_world_cylinder, double radius_m,
                                        double half_height_m);
/// Torus around the z axis of its own frame: ring radius `major_m`, tube radius `minor_m`.
std::unique_ptr<Primitive> makeTorus(const Eigen::Isometry3d& T_world_torus, double major_m,
                                     double minor_m);

/// Ray-cast hit: distance along the normalised ray and the primitive hit (-1 = none).
struct Hit {
  double t = INFINITY;
  int primitive = -1;
};

/// A set of primitives. The visible surface along a ray is the nearest hit of any primitive.
class AnalyticScene {
 public:
  void add(std::unique_ptr<Primitive> primitive, const Eigen::Vector3d& rgb = {200, 200, 200});
  Hit raycast(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir) const;
  /// Distance to the nearest surface of any primitive (unsigned: primitives may overlap).
  double distanceToSurface(const Eigen::Vector3d& p) const;
  /// Minimum of the primitives' signed distances: the clearance of `p` from every solid,
  /// positive in free space and negative inside any solid (a room's walls included).
  double clearance(const Eigen::Vector3d& p) const;
  /// Appends the triangulation of every primitive (see Primitive::tessellate) to `mesh`,
  /// with vertex colours from the procedural texture (colorAt).
  void tessellate(TriangleMesh* mesh, double max_edge_m) const;
  /// Textured colour at a surface point of primitive `index`.
  Eigen::Vector3d colorAt(const Eigen::Vector3d& p, int index) const;
  const Primitive& primitive(int index) const { return *primitives_[index]; }
  size_t size() const { return primitives_.size(); }

 private:
  std::vector<std::unique_ptr<Primitive>> primitives_;
};

/// Exact depth (CV_32FC1, metres; 0 where nothing is hit) and colour (CV_8UC3 RGB) of the
/// scene as seen by the left camera at T_world_camera. Depth is z in the camera frame.
void renderDepthAndColor(const AnalyticScene& scene, const StereoCamera& camera,
                         const Eigen::Isometry3d& T_world_camera, cv::Mat* depth_m,
                         cv::Mat* color_rgb);
/// Disparity (CV_32FC1, pixels; 0 = invalid) from a depth image: d = f·b / z.
cv::Mat disparityFromDepth(const cv::Mat& depth_m, const StereoCamera& camera);

/// Pose of a camera at `eye` looking at `target`, in the optical convention (z forward,
/// y down), with `up` giving the world's up direction.
Eigen::Isometry3d lookAt(const Eigen::Vector3d& eye, const Eigen::Vector3d& target,
                         const Eigen::Vector3d& up = Eigen::Vector3d::UnitZ());

}  // namespace stereo_fusion::sim
