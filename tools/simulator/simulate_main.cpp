// stereo_fusion_simulate: renders a stereo sequence of an analytic scene and writes it as a
// dataset folder (doc/dataset_format.md), with exact, noisy or SGBM disparity and the ground-truth
// mesh. Exit codes: 0 success, 1 failure while generating or writing, 2 bad command line.

#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iomanip>
#include <future>
#include <iostream>
#include <string>

#include "cli/CommandLine.h"
#include "simulator/DatasetWriter.h"
#include "simulator/SceneLibrary.h"
#include "simulator/SimulateArguments.h"
#include "simulator/StereoRenderer.h"
#include "simulator/Trajectory.h"
#include "stereo_fusion/mesh/SubMesh.h"
#include "stereo_fusion/ros/StereoBagWriter.h"

using namespace stereo_fusion;
using namespace stereo_fusion::sim;

namespace {

/// What --dynamic changes: the scene of the first half of the frames (nullptr: none) and the
/// regions where objects stood that left.
struct DynamicScene {
  std::unique_ptr<AnalyticScene> first_half;
  std::vector<Eigen::AlignedBox3d> ghost_regions;
};

/// Builds --dynamic `kind` around the orbit focus of preset `preset_name` (seed `seed`); adds to
/// `final_scene` what the scene holds at the end (the moved box at its second place).
DynamicScene makeDynamicScene(const std::string& kind, const std::string& preset_name,
                              uint32_t seed, AnalyticScene* final_scene) {
  DynamicScene out;
  if (kind == "none") return out;
  auto first = makePreset(preset_name, seed);  // same seed, same scene
  out.first_half = std::make_unique<AnalyticScene>(std::move(first->scene));
  const Eigen::Vector3d focus = first->focus_m;
  const double margin_m = 0.05;
  if (kind == "person") {
    const double radius_m = 0.25, half_height_m = 0.85;
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.translate(Eigen::Vector3d(focus.x(), focus.y(), half_height_m));
    out.first_half->add(makeCylinder(T, radius_m, half_height_m), {180, 90, 70});
    out.ghost_regions.emplace_back(
        Eigen::Vector3d(focus.x() - radius_m - margin_m, focus.y() - radius_m - margin_m, 0.0),
        Eigen::Vector3d(focus.x() + radius_m + margin_m, focus.y() + radius_m + margin_m,
                        2 * half_height_m + margin_m));
    return out;
  }
  // moved: a 0.4 × 0.4 × 0.6 m box beside the focus, then on its other side.
  const Eigen::Vector3d half(0.2, 0.2, 0.3);
  const Eigen::Vector3d before(focus.x() + 0.45, focus.y(), half.z()),
      after(focus.x() - 0.45, focus.y() + 0.2, half.z());
  Eigen::Isometry3d T_before = Eigen::Isometry3d::Identity(),
                    T_after = Eigen::Isometry3d::Identity();
  T_before.translate(before);
  T_after.translate(after);
  out.first_half->add(makeBox(T_before, half), {70, 120, 180});
  final_scene->add(makeBox(T_after, half), {70, 120, 180});
  const Eigen::Vector3d m = Eigen::Vector3d::Constant(margin_m);
  out.ghost_regions.emplace_back(before - half - m, before + half + m);
  return out;
}

/// One progress line on stderr, rewritten in place on a terminal, every 10 % otherwise.
void progress(int done, int total, double elapsed_s) {
  static const bool tty = isatty(STDERR_FILENO);
  if (!tty && done != total && done % std::max(1, total / 10) != 0) return;
  const double fps = elapsed_s > 0 ? done / elapsed_s : 0.0;
  std::fprintf(stderr, "%s[simulate] frame %d/%d  %.1f fps  %.0f s left%s", tty ? "\r" : "", done,
               total, fps, fps > 0 ? (total - done) / fps : 0.0, tty ? "  " : "\n");
  if (tty && done == total) std::fputc('\n', stderr);
  std::fflush(stderr);
}

/// Renders and writes the sequence `o` describes; returns the exit code.
int simulate(SimulateOptions o) {
  std::string error;
  const auto camera =
      StereoCamera::create(o.width_px, o.height_px, o.fx_px, o.fy_px > 0 ? o.fy_px : o.fx_px,
                           (o.width_px - 1) / 2.0, (o.height_px - 1) / 2.0, o.baseline_m, &error);
  if (!camera) {
    std::cerr << "stereo_fusion_simulate: " << error << "\n";
    return cli::kExitBadArguments;
  }
  auto preset = makePreset(o.preset, o.seed);
  if (!o.frames_given && o.trajectory == "walkthrough" && !preset->route_m.empty())
    o.frames = fullTourFrames(*preset, o.rate_hz);  // one whole tour of the building
  const auto poses =
      makeTrajectory(o.trajectory, *preset, o.frames, o.rate_hz, o.seed, &error, o.revolutions);
  if (!poses) {
    std::cerr << "stereo_fusion_simulate: " << error << "\n";
    return 1;
  }
  auto writer = DatasetWriter::create(o.out, *camera, &error);
  if (!writer) {
    std::cerr << "stereo_fusion_simulate: " << error << "\n";
    return 1;
  }

  std::unique_ptr<StereoBagWriter> bag;
  if (!o.bag.empty()) {
    BagTopics topics;
    topics.world_frame = o.bag_world_frame;
    std::string camera_frame = "left_optical";
    if (!o.bag_robot.empty()) {
      if (o.bag_content != "disparity") {
        std::cerr << "stereo_fusion_simulate: --bag-robot needs --bag-content disparity\n";
        return 2;
      }
      const std::string ns = "/" + o.bag_robot;
      topics.disparity = ns + topics.disparity;
      topics.image = ns + topics.image;
      topics.camera_info = ns + topics.camera_info;
      topics.trajectory = ns + topics.trajectory;
      if (!o.bag_world_frame_given) topics.world_frame = o.bag_robot + "/map";
      camera_frame = o.bag_robot + "/" + camera_frame;
    }
    bag = StereoBagWriter::open(o.bag, topics, camera_frame, 1.0, &error);
    if (!bag) {
      std::cerr << "stereo_fusion_simulate: " << error << "\n";
      return 1;
    }
  }

  StereoRenderConfig config;
  config.mode = *parseDisparityMode(o.disparity);
  config.noise.sigma_px = o.noise_px;
  config.noise.outlier_fraction = o.outlier_fraction;
  config.noise.outlier_max_px = o.sgbm.num_disparities;
  config.matcher.sigma_px = o.matcher_noise_px;
  config.matcher.mismatch_fraction = o.mismatch_fraction;
  config.matcher.mismatch_views = o.mismatch_views;
  config.sgbm = o.sgbm;
  config.seed = o.seed;
  // With --dynamic the first half of the frames sees `first_half` (the preset + what later
  // leaves or moves), the second half and the ground truth `preset` (+ where it moved to).
  const DynamicScene dynamic = makeDynamicScene(o.dynamic, o.preset, o.seed, &preset->scene);
  StereoRenderer renderer(preset->scene, *camera, config);
  std::unique_ptr<StereoRenderer> first_half_renderer;
  if (dynamic.first_half)
    first_half_renderer = std::make_unique<StereoRenderer>(*dynamic.first_half, *camera, config);

  std::cerr << "[simulate] " << o.preset << ", " << o.trajectory << ", " << o.frames << " frames "
            << o.width_px << "x" << o.height_px << ", disparity " << o.disparity << ", seed "
            << o.seed << " -> " << o.out << "\n";
  const auto start = std::chrono::steady_clock::now();
  auto elapsed = [&] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  };
  // Frame k is written (PNG encoding is slow) on a second thread while frame k + 1 renders.
  std::future<bool> pending_write;
  std::string write_error;
  auto finishWrite = [&] {
    if (!pending_write.valid() || pending_write.get()) return true;
    std::cerr << "\nstereo_fusion_simulate: " << write_error << "\n";
    return false;
  };
  double valid_share_sum = 0;
  const bool drifting = o.drift_yaw_deg != 0.0 || o.drift_m != 0.0;
  const std::vector<TimedPose> odometry = addOdometryDrift(*poses, o.drift_yaw_deg, o.drift_m);
  std::vector<StampedPose> keyframes;  // the SLAM's corrected trajectory: true poses
  if (drifting) {
    for (int k = 0; k < o.frames; k += o.keyframe_every)
      keyframes.push_back({(*poses)[k].timestamp_s, (*poses)[k].T_world_camera});
    auto writeTum = [&](const std::string& name, const std::vector<StampedPose>& list) {
      std::ofstream out(o.out + "/" + name);
      out << std::setprecision(12);
      for (const StampedPose& p : list) {
        const Eigen::Quaterniond q(p.T_world_camera.rotation());
        const Eigen::Vector3d t = p.T_world_camera.translation();
        out << p.stamp_s << " " << t.x() << " " << t.y() << " " << t.z() << " " << q.x() << " "
            << q.y() << " " << q.z() << " " << q.w() << "\n";
      }
      return static_cast<bool>(out);
    };
    std::vector<StampedPose> truth;
    for (const TimedPose& p : *poses) truth.push_back({p.timestamp_s, p.T_world_camera});
    if (!writeTum("poses_true.txt", truth) || !writeTum("trajectory.txt", keyframes)) {
      std::cerr << "stereo_fusion_simulate: cannot write " << o.out
                << "/poses_true.txt or trajectory.txt\n";
      return 1;
    }
  }
  for (int k = 0; k < o.frames; ++k) {
    TimedPose pose = (*poses)[k];
    const Eigen::Isometry3d T_true = pose.T_world_camera;
    StereoRenderer& frame_renderer =
        first_half_renderer && k < o.frames / 2 ? *first_half_renderer : renderer;
    StereoView view = frame_renderer.render(T_true, static_cast<uint64_t>(k));
    if (drifting) pose.T_world_camera = odometry[k].T_world_camera;
    valid_share_sum +=
        cv::countNonZero(view.disparity_px) / static_cast<double>(view.disparity_px.total());
    if (!finishWrite()) return 1;
    pending_write = std::async(std::launch::async, [&, k, pose, view = std::move(view)] {
      if (!writer->writeFrame(k, pose.timestamp_s, pose.T_world_camera, view.disparity_px,
                              view.left_rgb, view.right_rgb, &write_error))
        return false;
      if (!bag) return true;
      StereoFrame frame;
      frame.timestamp_s = pose.timestamp_s;
      frame.T_world_camera = pose.T_world_camera;
      frame.camera = *camera;
      frame.disparity_px = view.disparity_px;
      frame.color = view.left_rgb;
      if (drifting && o.bag_content == "disparity") {
        // After the middle frame and after the last: the trajectory's keyframes up to this frame.
        if (!bag->write(frame, static_cast<float>(o.sgbm.num_disparities), &write_error))
          return false;
        if (k != o.frames / 2 - 1 && k != o.frames - 1) return true;
        std::vector<StampedPose> so_far;
        for (const StampedPose& key : keyframes)
          if (key.stamp_s <= pose.timestamp_s) so_far.push_back(key);
        return bag->writeTrajectory(so_far, pose.timestamp_s + 0.5 / o.rate_hz, &write_error);
      }
      if (o.bag_content == "pair")
        return bag->writePair(frame, view.right_rgb, PairTopics{}, &write_error);
      if (o.bag_content == "rectified-pair")
        return bag->writePair(frame, view.right_rgb, PairTopics::rectified(), &write_error);
      return bag->write(frame, static_cast<float>(o.sgbm.num_disparities), &write_error);
    });
    progress(k + 1, o.frames, elapsed());
  }
  if (!finishWrite()) return 1;
  if (bag) bag->close();

  if (!dynamic.ghost_regions.empty()) {
    std::ofstream regions(o.out + "/dynamic.txt");
    regions << "# where objects stood that left or moved (world, metres): x0 y0 z0 x1 y1 z1\n";
    for (const Eigen::AlignedBox3d& box : dynamic.ghost_regions)
      regions << "ghost_region " << box.min().x() << " " << box.min().y() << " " << box.min().z()
              << " " << box.max().x() << " " << box.max().y() << " " << box.max().z() << "\n";
    if (!regions) {
      std::cerr << "stereo_fusion_simulate: cannot write " << o.out << "/dynamic.txt\n";
      return 1;
    }
  }
  TriangleMesh gt_mesh;
  preset->scene.tessellate(&gt_mesh, o.gt_max_edge_m);
  if (!writer->writeGroundTruthMesh(gt_mesh, &error)) {
    std::cerr << "stereo_fusion_simulate: " << error << "\n";
    return 1;
  }
  std::fprintf(
      stderr,
      "[simulate] wrote %d frames (%.1f %% valid disparity) and gt_mesh.ply (%zu triangles) "
      "to %s in %.1f s\n",
      o.frames, 100.0 * valid_share_sum / o.frames, gt_mesh.triangles.size(), o.out.c_str(),
      elapsed());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  SimulateOptions options;
  CLI::App app("", "stereo_fusion_simulate");
  addSimulateArguments(&app, &options);
  if (const auto exit_code = cli::parseOrExitCode(app, argc, argv)) return *exit_code;
  return simulate(options);
}
