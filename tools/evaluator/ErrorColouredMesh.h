#pragma once
// The reconstruction coloured by each vertex's distance to the ground truth, to see where the
// error is (stereo_fusion_evaluate --error-ply), and the ground-truth samples coloured by their
// distance to the reconstruction, to see where it is incomplete (--missing-ply).

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "evaluator/TriangleBvh.h"
#include "stereo_fusion/mesh/SubMesh.h"
#include "stereo_fusion/util/ThreadPool.h"

namespace stereo_fusion::eval {

/// RGB of a vertex `distance_m` from the ground truth: blue (0, 0, 255) at 0, green (0, 255, 0)
/// at tolerance/2, yellow (255, 255, 0) at the tolerance, red (255, 0, 0) at 2 × tolerance and
/// beyond (also for +inf and NaN), linear in between, each channel rounded to the nearest integer.
std::array<uint8_t, 3> errorColour(double distance_m, double tolerance_m);

/// `reconstruction` (same positions, triangles and normals) with every vertex coloured by
/// errorColour() of its point-to-triangle distance to `ground_truth`. The distances run in
/// parallel on `pool`. A mesh read without normals gets area-weighted face normals, as the PLY
/// writer stores one per vertex.
TriangleMesh errorColouredMesh(const TriangleMesh& reconstruction, const TriangleBvh& ground_truth,
                               double tolerance_m, ThreadPool* pool);

/// Writes errorColouredMesh() to `path` as binary little-endian PLY (io/PlyWriter), whole or
/// not at all (io/WriteTarget). False with a message naming the file on failure.
bool writeErrorColouredPly(const std::string& path, const TriangleMesh& reconstruction,
                           const TriangleMesh& ground_truth, double tolerance_m, int num_threads,
                           std::string* error);

/// The points of `points_m` whose `mask` entry is non-zero (all when `mask` is empty) as a point
/// cloud (no faces, zero normals), each coloured by errorColour() of its distance to the
/// reconstruction, `distances_m[i]` (GroundTruthResult::gt_sample_distances_m): blue where the
/// surface covers it, red where it is 2 × tolerance or more away. False when the sizes differ.
bool errorColouredPoints(const std::vector<Eigen::Vector3d>& points_m,
                         const std::vector<uint8_t>& mask, const std::vector<double>& distances_m,
                         double tolerance_m, TriangleMesh* cloud);

/// Writes errorColouredPoints() of the ground-truth samples to `path` as binary PLY, whole or
/// not at all. False with a message naming the file (or the size mismatch) on failure.
bool writeMissingPly(const std::string& path, const std::vector<Eigen::Vector3d>& gt_samples_m,
                     const std::vector<uint8_t>& gt_visible, const std::vector<double>& distances_m,
                     double tolerance_m, std::string* error);

}  // namespace stereo_fusion::eval
