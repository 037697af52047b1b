#include "evaluator/ErrorColouredMesh.h"

#include <Eigen/Geometry>
#include <cmath>
#include <vector>

#include "evaluator/BatchDistance.h"
#include "stereo_fusion/io/PlyWriter.h"

namespace stereo_fusion::eval {
namespace {

uint8_t channel(double share) { return static_cast<uint8_t>(std::lround(255.0 * share)); }

}  // namespace

std::array<uint8_t, 3> errorColour(double distance_m, double tolerance_m) {
  const double t = distance_m / tolerance_m;  // in tolerances
  if (!(t < 2.0)) return {255, 0, 0};         // also +inf and NaN: no surface near
  if (t <= 0.0) return {0, 0, 255};
  if (t < 0.5) return {0, channel(2.0 * t), channel(1.0 - 2.0 * t)};  // blue → green
  if (t < 1.0) return {channel(2.0 * t - 1.0), 255, 0};               // green → yellow
  return {255, channel(2.0 - t), 0};                                  // yellow → red
}

TriangleMesh errorColouredMesh(const TriangleMesh& reconstruction, const TriangleBvh& ground_truth,
                               double tolerance_m, ThreadPool* pool) {
  TriangleMesh coloured = reconstruction;
  if (coloured.normals.size() != coloured.positions.size()) computeVertexNormals(&coloured);
  std::vector<Eigen::Vector3d> vertices_m;
  vertices_m.reserve(coloured.positions.size());
  for (const Eigen::Vector3f& p : coloured.positions) vertices_m.push_back(p.cast<double>());
  const std::vector<double> distances_m = distancesToSurface(ground_truth, vertices_m, pool);
  coloured.colors.resize(distances_m.size());
  for (size_t v = 0; v < distances_m.size(); ++v) {
    coloured.colors[v] = errorColour(distances_m[v], tolerance_m);
  }
  return coloured;
}

bool writeErrorColouredPly(const std::string& path, const TriangleMesh& reconstruction,
                           const TriangleMesh& ground_truth, double tolerance_m, int num_threads,
                           std::string* error) {
  ThreadPool pool(num_threads);
  const TriangleMesh coloured =
      errorColouredMesh(reconstruction, TriangleBvh(ground_truth), tolerance_m, &pool);
  return writePlyWhole(path, "error-coloured mesh", coloured, error);
}

bool errorColouredPoints(const std::vector<Eigen::Vector3d>& points_m,
                         const std::vector<uint8_t>& mask, const std::vector<double>& distances_m,
                         double tolerance_m, TriangleMesh* cloud) {
  if (distances_m.size() != points_m.size() || (!mask.empty() && mask.size() != points_m.size()))
    return false;
  *cloud = TriangleMesh{};
  for (size_t i = 0; i < points_m.size(); ++i) {
    if (!mask.empty() && mask[i] == 0) continue;
    cloud->positions.push_back(points_m[i].cast<float>());
    cloud->normals.emplace_back(Eigen::Vector3f::Zero());
    cloud->colors.push_back(errorColour(distances_m[i], tolerance_m));
  }
  return true;
}

bool writeMissingPly(const std::string& path, const std::vector<Eigen::Vector3d>& gt_samples_m,
                     const std::vector<uint8_t>& gt_visible, const std::vector<double>& distances_m,
                     double tolerance_m, std::string* error) {
  TriangleMesh cloud;
  if (!errorColouredPoints(gt_samples_m, gt_visible, distances_m, tolerance_m, &cloud)) {
    if (error)
      *error = path + ": " + std::to_string(gt_samples_m.size()) + " ground-truth samples, " +
               std::to_string(distances_m.size()) + " distances, " +
               std::to_string(gt_visible.size()) + " visibility flags: they must match";
    return false;
  }
  return writePlyWhole(path, "ground-truth samples", cloud, error);
}

}  // namespace stereo_fusion::eval
