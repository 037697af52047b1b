#include "evaluator/TriangleBvh.h"

#include <algorithm>
#include <numeric>

#include "evaluator/TriangleDistance.h"

namespace stereo_fusion::eval {
namespace {
constexpr uint32_t kLeafSize = 4;
}  // namespace

TriangleBvh::TriangleBvh(const TriangleMesh& mesh) {
  const size_t vertex_count = mesh.positions.size();
  triangles_.reserve(mesh.triangles.size());
  mesh_triangle_.reserve(mesh.triangles.size());
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    const auto& tri = mesh.triangles[t];
    if (tri[0] >= vertex_count || tri[1] >= vertex_count || tri[2] >= vertex_count) continue;
    triangles_.push_back({mesh.positions[tri[0]], mesh.positions[tri[1]], mesh.positions[tri[2]]});
    mesh_triangle_.push_back(static_cast<uint32_t>(t));
  }
  if (triangles_.empty()) return;
  std::vector<Eigen::Vector3f> centroids(triangles_.size());
  for (size_t t = 0; t < triangles_.size(); ++t) {
    centroids[t] = (triangles_[t].a + triangles_[t].b + triangles_[t].c) / 3.0f;
  }
  // A median-split tree of n triangles has < 2n/kLeafSize·2 nodes; reserving avoids regrowth.
  nodes_.reserve(4 * triangles_.size() / kLeafSize + 2);
  build(0, static_cast<uint32_t>(triangles_.size()), &centroids);
}

uint32_t TriangleBvh::build(uint32_t begin, uint32_t end, std::vector<Eigen::Vector3f>* centroids) {
  const uint32_t index = static_cast<uint32_t>(nodes_.size());
  nodes_.push_back({});
  Eigen::Vector3f box_min = Eigen::Vector3f::Constant(INFINITY);
  Eigen::Vector3f box_max = Eigen::Vector3f::Constant(-INFINITY);
  Eigen::Vector3f centre_min = box_min, centre_max = box_max;
  for (uint32_t t = begin; t < end; ++t) {
    const Triangle& tri = triangles_[t];
    box_min = box_min.cwiseMin(tri.a).cwiseMin(tri.b).cwiseMin(tri.c);
    box_max = box_max.cwiseMax(tri.a).cwiseMax(tri.b).cwiseMax(tri.c);
    centre_min = centre_min.cwiseMin((*centroids)[t]);
    centre_max = centre_max.cwiseMax((*centroids)[t]);
  }
  for (int k = 0; k < 3; ++k) {
    nodes_[index].min[k] = box_min[k];
    nodes_[index].max[k] = box_max[k];
  }
  if (end - begin <= kLeafSize) {
    nodes_[index].offset = begin;
    nodes_[index].count = end - begin;
    return index;
  }
  // Median split on the centroids' longest axis: balanced, so the depth stays ≈ log2(n / 4)
  // even for heavily clustered input (identical centroids are split by position in the array).
  int axis;
  (centre_max - centre_min).maxCoeff(&axis);
  const uint32_t middle = begin + (end - begin) / 2;
  std::vector<uint32_t> order(end - begin);
  std::iota(order.begin(), order.end(), begin);
  std::nth_element(
      order.begin(), order.begin() + (middle - begin), order.end(),
      [&](uint32_t l, uint32_t r) { return (*centroids)[l][axis] < (*centroids)[r][axis]; });
  // Apply the permutation to the triangles, their centroids and their mesh indices.
  std::vector<Triangle> triangles(order.size());
  std::vector<Eigen::Vector3f> centres(order.size());
  std::vector<uint32_t> mesh_index(order.size());
  for (size_t i = 0; i < order.size(); ++i) {
    triangles[i] = triangles_[order[i]];
    centres[i] = (*centroids)[order[i]];
    mesh_index[i] = mesh_triangle_[order[i]];
  }
  std::copy(triangles.begin(), triangles.end(), triangles_.begin() + begin);
  std::copy(centres.begin(), centres.end(), centroids->begin() + begin);
  std::copy(mesh_index.begin(), mesh_index.end(), mesh_triangle_.begin() + begin);
  std::vector<Triangle>().swap(triangles);  // free before recursing: peak memory stays O(n)

  build(begin, middle, centroids);
  const uint32_t right = build(middle, end, centroids);
  nodes_[index].offset = right;
  nodes_[index].count = 0;
  return index;
}

double TriangleBvh::boxDistance2(const Node& node, const Eigen::Vector3d& p) const {
  double d2 = 0.0;
  for (int k = 0; k < 3; ++k) {
    const double below = node.min[k] - p[k];
    const double above = p[k] - node.max[k];
    const double d = std::max({below, above, 0.0});
    d2 += d * d;
  }
  return d2;
}

bool TriangleBvh::nearest(const Eigen::Vector3d& p, NearestSurfacePoint* nearest,
                          double max_distance_m) const {
  if (nodes_.empty()) return false;
  double best2 = max_distance_m * max_distance_m;
  uint32_t best_triangle = UINT32_MAX;
  Eigen::Vector3d best_point = Eigen::Vector3d::Zero();

  // Depth-first, nearer child first; the balanced tree is < 40 levels deep for 2^32 triangles,
  // and each level pushes at most one deferred sibling.
  struct Entry {
    uint32_t node;
    double distance2;
  };
  Entry stack[96];
  int top = 0;
  stack[top++] = {0, boxDistance2(nodes_[0], p)};
  while (top > 0) {
    const Entry entry = stack[--top];
    if (entry.distance2 >= best2) continue;
    const Node& node = nodes_[entry.node];
    if (node.count > 0) {
      for (uint32_t t = node.offset; t < node.offset + node.count; ++t) {
        const Triangle& tri = triangles_[t];
        const Eigen::Vector3d q = closestPointOnTriangle(
            p, tri.a.cast<double>(), tri.b.cast<double>(), tri.c.cast<double>());
        const double d2 = (q - p).squaredNorm();
        if (d2 < best2) {
          best2 = d2;
          best_triangle = t;
          best_point = q;
        }
      }
      continue;
    }
    const uint32_t left = entry.node + 1, right = node.offset;
    const double left2 = boxDistance2(nodes_[left], p), right2 = boxDistance2(nodes_[right], p);
    // Push the farther child first so the nearer one is searched first and tightens best2.
    if (left2 < right2) {
      if (right2 < best2) stack[top++] = {right, right2};
      if (left2 < best2) stack[top++] = {left, left2};
    } else {
      if (left2 < best2) stack[top++] = {left, left2};
      if (right2 < best2) stack[top++] = {right, right2};
    }
  }
  if (best_triangle == UINT32_MAX) return false;
  nearest->point_m = best_point;
  nearest->distance_m = std::sqrt(best2);
  nearest->triangle = mesh_triangle_[best_triangle];
  return true;
}

double TriangleBvh::distance(const Eigen::Vector3d& p) const {
  NearestSurfacePoint hit;
  return nearest(p, &hit) ? hit.distance_m : INFINITY;
}

}  // namespace stereo_fusion::eval
