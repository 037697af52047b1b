#pragma once
// Area-uniform random points on a triangle mesh's surface.

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "stereo_fusion/mesh/SubMesh.h"

namespace stereo_fusion::eval {

/// Points drawn uniformly by area from a mesh's surface.
struct SurfaceSamples {
  std::vector<Eigen::Vector3d> points_m;
  double area_m2 = 0.0;  ///< total area of the valid triangles
};

/// Draws `count` points uniformly by area (a triangle is picked with probability proportional
/// to its area, then a uniform point inside it). The same mesh, count and seed give the same
/// points on every platform (own uniform mapping, not std::uniform_real_distribution).
/// Triangles with an index out of range are ignored; a mesh without area gives no points.
/// Sampling by area, not taking the vertices, makes scores independent of tessellation: a
/// finely meshed corner would otherwise count more than a coarse wall.
SurfaceSamples sampleSurface(const TriangleMesh& mesh, size_t count, uint64_t seed);

}  // namespace stereo_fusion::eval
