#pragma once
#include <Eigen/Geometry>
// Ground-truth evaluation of a reconstructed mesh: accuracy, completeness, precision, F-score.

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "evaluator/DistanceStats.h"
#include "stereo_fusion/mesh/SubMesh.h"

namespace stereo_fusion::eval {

/// Parameters of the ground-truth comparison.
struct GroundTruthOptions {
  /// A point counts as "on the other surface" when it is at most this far from it
  /// (default 2 voxels of the default 0.02 m voxel size).
  double tolerance_m = 0.04;
  /// Area-uniform samples drawn from each mesh.
  size_t samples = 1000000;
  /// Seed of the sampling; the reconstruction and the ground truth use different streams.
  uint64_t seed = 1;
  /// Threads for the distance queries, the caller included; 0 = all cores.
  int num_threads = 0;
  /// Where objects stood that have gone since (the sequence's dynamic.txt): reconstruction
  /// surface inside them that is farther than the tolerance from the truth is ghost surface.
  std::vector<Eigen::AlignedBox3d> ghost_regions_m;
  /// One entry per ground-truth triangle, or empty for all: the triangles that accuracy and
  /// precision are measured against (seenTriangles(): walls count as solid).
  std::vector<uint8_t> accuracy_triangles;
};

/// Scores of a reconstruction against a ground-truth surface. Shares are fractions in [0, 1].
struct GroundTruthResult {
  /// Distances from reconstruction samples to the ground-truth surface (how right the surface
  /// that exists is).
  DistanceSummary accuracy;
  /// Distances from the evaluated ground-truth samples to the reconstruction (how much of the
  /// truth is covered, and how far the rest is).
  DistanceSummary completion;
  /// Share of reconstruction samples within tolerance of the ground truth; NaN when the
  /// reconstruction has no surface.
  double precision = NAN;
  /// Share of evaluated ground-truth samples within tolerance of the reconstruction.
  double completeness = 0.0;
  /// Share of ALL ground-truth samples within tolerance (equals `completeness` without a
  /// visibility mask).
  double completeness_all = 0.0;
  double f_score = 0.0;  ///< 2PR/(P+R) with P = precision, R = completeness
  size_t ground_truth_samples = 0;
  size_t ground_truth_samples_evaluated = 0;  ///< the visible ones when a mask is given
  size_t reconstruction_samples = 0;
  double ground_truth_area_m2 = 0.0;
  double reconstruction_area_m2 = 0.0;
  bool visibility_used = false;
  /// Area of reconstruction surface inside GroundTruthOptions::ghost_regions_m and farther than
  /// the tolerance from the truth (NaN without regions).
  double ghost_area_m2 = NAN;
  /// Distance of every ground-truth sample (visible or not, in the order given) to the
  /// reconstruction: what `completion` summarises, kept for a per-sample picture (--missing-ply).
  std::vector<double> gt_sample_distances_m;
};

/// Draws `options.samples` points from each mesh and scores `reconstruction` against
/// `ground_truth` over the whole ground-truth surface.
GroundTruthResult evaluateAgainstGroundTruth(const TriangleMesh& reconstruction,
                                             const TriangleMesh& ground_truth,
                                             const GroundTruthOptions& options);

/// The same with given ground-truth samples and an optional mask (`gt_visible`, one entry per
/// sample, or empty for "all"): completeness and the completion distances count only the
/// samples marked visible, so a surface the sequence never saw does not count as missing.
GroundTruthResult evaluateAgainstGroundTruthSamples(
    const TriangleMesh& reconstruction, const TriangleMesh& ground_truth,
    const std::vector<Eigen::Vector3d>& gt_samples_m, double gt_area_m2,
    const std::vector<uint8_t>& gt_visible, const GroundTruthOptions& options);

/// Seed of the reconstruction's sample stream derived from `options.seed`; the ground truth
/// uses `options.seed` itself. Exposed so callers drawing samples themselves stay consistent.
uint64_t reconstructionSeed(uint64_t seed);

}  // namespace stereo_fusion::eval
