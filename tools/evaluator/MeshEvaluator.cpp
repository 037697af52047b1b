#include "evaluator/MeshEvaluator.h"

#include "evaluator/BatchDistance.h"
#include "evaluator/SeenTriangles.h"
#include "evaluator/SurfaceSampler.h"
#include "evaluator/TriangleBvh.h"
#include "stereo_fusion/util/ThreadPool.h"

namespace stereo_fusion::eval {

uint64_t reconstructionSeed(uint64_t seed) {
  // Any fixed bijection works; this one keeps the two streams apart for every seed.
  return seed ^ 0x9E3779B97F4A7C15ull;
}

GroundTruthResult evaluateAgainstGroundTruth(const TriangleMesh& reconstruction,
                                             const TriangleMesh& ground_truth,
                                             const GroundTruthOptions& options) {
  const SurfaceSamples gt = sampleSurface(ground_truth, options.samples, options.seed);
  return evaluateAgainstGroundTruthSamples(reconstruction, ground_truth, gt.points_m, gt.area_m2,
                                           {}, options);
}

GroundTruthResult evaluateAgainstGroundTruthSamples(
    const TriangleMesh& reconstruction, const TriangleMesh& ground_truth,
    const std::vector<Eigen::Vector3d>& gt_samples_m, double gt_area_m2,
    const std::vector<uint8_t>& gt_visible, const GroundTruthOptions& options) {
  GroundTruthResult result;
  ThreadPool pool(options.num_threads);
  const SurfaceSamples recon =
      sampleSurface(reconstruction, options.samples, reconstructionSeed(options.seed));
  result.reconstruction_samples = recon.points_m.size();
  result.reconstruction_area_m2 = recon.area_m2;
  result.ground_truth_samples = gt_samples_m.size();
  result.ground_truth_area_m2 = gt_area_m2;
  result.visibility_used = !gt_visible.empty();

  // Precision / accuracy: reconstruction → ground truth.
  {
    const TriangleBvh gt_surface(options.accuracy_triangles.empty()
                                     ? ground_truth
                                     : keepTriangles(ground_truth, options.accuracy_triangles));
    const std::vector<double> to_gt = distancesToSurface(gt_surface, recon.points_m, &pool);
    result.precision = shareWithin(to_gt, options.tolerance_m);
    if (!options.ghost_regions_m.empty() && !recon.points_m.empty()) {
      size_t ghost = 0;
      for (size_t i = 0; i < recon.points_m.size(); ++i) {
        if (!(to_gt[i] > options.tolerance_m)) continue;
        for (const Eigen::AlignedBox3d& region : options.ghost_regions_m)
          if (region.contains(recon.points_m[i])) {
            ++ghost;
            break;
          }
      }
      result.ghost_area_m2 =
          recon.area_m2 * static_cast<double>(ghost) / static_cast<double>(recon.points_m.size());
    } else if (!options.ghost_regions_m.empty()) {
      result.ghost_area_m2 = 0.0;
    }
    result.accuracy = summarizeDistances(to_gt);
  }
  // Completeness: ground truth → reconstruction, over all samples and over the visible ones.
  const TriangleBvh recon_surface(reconstruction);
  const std::vector<double> to_recon = distancesToSurface(recon_surface, gt_samples_m, &pool);
  result.completeness_all = gt_samples_m.empty() ? 0.0 : shareWithin(to_recon, options.tolerance_m);
  std::vector<double> evaluated;
  if (result.visibility_used) {
    for (size_t i = 0; i < to_recon.size() && i < gt_visible.size(); ++i) {
      if (gt_visible[i]) evaluated.push_back(to_recon[i]);
    }
  } else {
    evaluated = to_recon;
  }
  result.ground_truth_samples_evaluated = evaluated.size();
  result.completeness = evaluated.empty() ? 0.0 : shareWithin(evaluated, options.tolerance_m);
  result.completion = summarizeDistances(std::move(evaluated));
  result.f_score = fScore(result.precision, result.completeness);
  result.gt_sample_distances_m = std::move(to_recon);
  return result;
}

}  // namespace stereo_fusion::eval
