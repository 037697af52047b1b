#pragma once
// Many nearest-surface queries at once, in parallel and in a cache-friendly order.

#include <Eigen/Core>
#include <vector>

#include "evaluator/TriangleBvh.h"
#include "stereo_fusion/util/ThreadPool.h"

namespace stereo_fusion::eval {

/// Distance (metres) from every point to `surface`, in the order of `points_m`; +inf for an
/// empty surface. Queries run in Morton (Z-curve) order so neighbouring queries walk the same
/// BVH nodes while they are in cache: about twice as fast as random sample order. The result
/// does not depend on the order or the thread count.
std::vector<double> distancesToSurface(const TriangleBvh& surface,
                                       const std::vector<Eigen::Vector3d>& points_m,
                                       ThreadPool* pool);

/// Indices of `points_m` sorted along a Z-order curve over their bounding box (21 bits per axis).
std::vector<uint32_t> mortonOrder(const std::vector<Eigen::Vector3d>& points_m);

}  // namespace stereo_fusion::eval
