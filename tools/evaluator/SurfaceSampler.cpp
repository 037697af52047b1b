#include "evaluator/SurfaceSampler.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <random>

namespace stereo_fusion::eval {
namespace {

/// Uniform double in [0, 1) from the top 53 bits of a 64-bit draw.
double uniform01(std::mt19937_64& rng) { return static_cast<double>(rng() >> 11) * 0x1.0p-53; }

}  // namespace

SurfaceSamples sampleSurface(const TriangleMesh& mesh, size_t count, uint64_t seed) {
  SurfaceSamples samples;
  const size_t vertex_count = mesh.positions.size();
  std::vector<uint32_t> triangle_of;    // valid triangles with area
  std::vector<double> cumulative_area;  // running sum, for inverse-CDF picking
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    const auto& tri = mesh.triangles[t];
    if (tri[0] >= vertex_count || tri[1] >= vertex_count || tri[2] >= vertex_count) continue;
    const Eigen::Vector3d a = mesh.positions[tri[0]].cast<double>();
    const double area = 0.5 * (mesh.positions[tri[1]].cast<double>() - a)
                                  .cross(mesh.positions[tri[2]].cast<double>() - a)
                                  .norm();
    if (!(area > 0.0) || !std::isfinite(area)) continue;
    samples.area_m2 += area;
    triangle_of.push_back(static_cast<uint32_t>(t));
    cumulative_area.push_back(samples.area_m2);
  }
  if (triangle_of.empty() || count == 0) return samples;

  std::mt19937_64 rng(seed);
  samples.points_m.resize(count);
  for (size_t i = 0; i < count; ++i) {
    const double target = uniform01(rng) * samples.area_m2;
    const size_t k =
        std::min<size_t>(std::upper_bound(cumulative_area.begin(), cumulative_area.end(), target) -
                             cumulative_area.begin(),
                         cumulative_area.size() - 1);
    const auto& tri = mesh.triangles[triangle_of[k]];
    // Uniform point in a triangle: fold the unit square's upper half onto the lower one.
    double s = uniform01(rng), t = uniform01(rng);
    if (s + t > 1.0) {
      s = 1.0 - s;
      t = 1.0 - t;
    }
    const Eigen::Vector3d a = mesh.positions[tri[0]].cast<double>();
    samples.points_m[i] = a + s * (mesh.positions[tri[1]].cast<double>() - a) +
                          t * (mesh.positions[tri[2]].cast<double>() - a);
  }
  return samples;
}

}  // namespace stereo_fusion::eval
