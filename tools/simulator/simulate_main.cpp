// stereo_fusion_simulate: renders a stereo sequence of an analytic scene and writes it as a
// dataset folder (doc/dataset_format.md), with exact, noisy or SGBM disparity and the ground-truth
// mesh. Exit codes: 0 success, 1 failure while generating or writing, 2 bad command line.

#include <unistd.h>

#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <fstream>
#include <iomanip>
#include <future>
#include <iostream>
#include <map>
#include <string>

#include "simulator/DatasetWriter.h"
#include "simulator/SceneLibrary.h"
#include "simulator/StereoRenderer.h"
#include "simulator/Trajectory.h"
#include "stereo_fusion/mesh/SubMesh.h"
#include "stereo_fusion/ros/StereoBagWriter.h"

using namespace stereo_fusion;
using namespace stereo_fusion::sim;

namespace {

/// Every command-line setting with its default.
struct Options {
  std::string preset = "room";
  std::string trajectory = "walkthrough";
  int frames = 100;
  bool frames_given = false;  ///< --frames was passed (else the building's walkthrough: one tour)
  int width_px = 640;
  int height_px = 480;
  double fx_px = 525.0;
  double fy_px = -1.0;  ///< < 0: same as fx
  double baseline_m = 0.1;
  std::string disparity = "sgbm";
  double noise_px = 0.3;
  double outlier_fraction = 0.01;
  double matcher_noise_px = 0.0;
  double mismatch_fraction = 0.0;
  int mismatch_views = 5;
  uint32_t seed = 0;
  double rate_hz = 10.0;
  std::string bag;  ///< also write the frames as a rosbag here (empty: no bag)
  /// disparity (matched) | pair (left/right raw images only) | rectified-pair (rectified images
  /// only)
  std::string bag_content = "disparity";
  /// The bag's /tf parent frame (the nodelet's world_frame; default BagTopics', REP 105's map).
  std::string bag_world_frame = BagTopics{}.world_frame;
  double gt_max_edge_m = 0.03;
  double revolutions = 1.0;
  std::string dynamic = "none";
  double drift_yaw_deg = 0.0;  ///< --drift: odometry yaw error at the last frame
  double drift_m = 0.0;        ///< --drift: odometry position error at the last frame
  int keyframe_every = 5;
  SgbmParams sgbm;
  std::string out;
};

const char* const kUsage = R"(Usage: stereo_fusion_simulate --out DIR [options]

Renders a rectified stereo sequence of an analytic scene and writes it as a dataset folder:
calibration.yaml, poses.txt, disparity/ color/ right/ NNNNNN.png, gt_mesh.ply.

  --preset room|tabletop|hall|building
                                  scene (default room; hall: far-range, walls 3–4.5 m away;
                                  building: six furnished rooms along a corridor, a map larger
                                  than memory caps for benches of paging)
  --trajectory orbit|walkthrough  camera path (default walkthrough; building: the walkthrough is
                                  a tour through every room, ending back in the first)
  --frames N                      number of frames (default 100; building's walkthrough: one
                                  whole tour, ~1000 frames; fewer: its start only)
  --width W --height H            image size in pixels (default 640 x 480)
  --fx F                          focal length in pixels (default 525)
  --fy F                          vertical focal length (default: fx); cx, cy = image centre
  --baseline B                    stereo baseline in metres (default 0.1)
  --disparity exact|noisy|sgbm    disparity source (default sgbm)
  --noise-px S                    noisy: Gaussian sigma in pixels (default 0.3)
  --outlier-fraction P            noisy: share of outliers in [0, 1] (default 0.01)
  --matcher-noise-px S            any mode: Gaussian sigma added per pixel and frame (default 0)
  --mismatch-fraction P           any mode: share in [0, 1] of 5 cm surface patches where the
                                  matcher errs by the same 1-3 px in every view of a window of
                                  neighbouring frames (default 0); real SGBM on far walls:
                                  --matcher-noise-px 0.2 --mismatch-fraction 0.03
  --mismatch-views K              frames per window of equal mismatches (default 5; 0: every
                                  frame of the sequence errs alike)
  --sgbm-num-disparities N        sgbm: search range, a multiple of 16 (default 128)
  --sgbm-block-size N             sgbm: odd matching window size (default 5)
  --seed K                        scene, path and noise seed, 0..4294967295 (default 0)
  --revolutions R                 orbit: laps over the whole sequence (default 1)
  --dynamic none|person|moved     objects that change during the sequence (default none):
                                  person: a person (cylinder 0.5 m wide, 1.7 m tall) stands at
                                  the orbit's focus during the first half of the frames only;
                                  moved: a box stands beside the focus in the first half and
                                  on its other side in the second. gt_mesh.ply is the scene as
                                  it ends; dynamic.txt lists where objects stood that left
                                  (the evaluator reports the surface left there as ghost)
  --drift YAW_DEG,METRES          poses.txt (and the bag's /tf) drift like odometry: by the last
                                  frame YAW_DEG of yaw about the vertical through the first
                                  camera and METRES of horizontal offset, growing linearly; the
                                  images stay true. Also writes poses_true.txt and
                                  trajectory.txt, a SLAM's corrected keyframe poses (the true
                                  poses of every --keyframe-every-th frame, TUM lines); a bag
                                  gets that trajectory as nav_msgs/Path on /trajectory twice,
                                  after the middle frame (keyframes so far) and after the last
  --keyframe-every N              keyframe spacing of trajectory.txt (default 5)
  --rate-hz R                     frame rate for the timestamps (default 10)
  --gt-max-edge M                 ground-truth mesh grid step in metres (default 0.03)
  --out DIR                       output folder (created; an old dataset there is replaced)
  --bag FILE                      also write a rosbag: DisparityImage, Image, CameraInfo on
                                  the nodelet's default topics and /tf (map -> left_optical);
                                  stamps = timestamps + 1 s (ROS time 0 means "latest" to tf)
  --bag-world-frame F             the bag's tf parent frame and the trajectory's frame (default
                                  map, the nodelet's default world_frame; e.g. odom)
  --bag-content disparity|pair|rectified-pair
                                  disparity (default): what the nodelet subscribes to;
                                  pair: what a stereo camera driver publishes, for
                                  launch/stereo_pipeline.launch: /stereo/{left,right}/image_raw
                                  (rgb8, already rectified), both camera_info, /tf; no disparity;
                                  rectified-pair: the same as a rectifying driver publishes it,
                                  for stereo_pipeline.launch rectified:=true:
                                  /stereo/{left,right}/image_rect (mono8),
                                  /stereo/left/image_rect_color (rgb8), both camera_info, /tf
  --help                          this text

Exit codes: 0 done, 1 generation or write failure, 2 bad arguments.
)";

/// Thrown for a bad command line; main() prints it and exits with 2.
struct UsageError {
  std::string message;
};

/// "100000", "0.001": range bounds as a person would write them.
std::string shortNumber(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "%.10g", value);
  return buffer;
}

double parseDouble(const std::string& flag, const std::string& text, double lo, double hi,
                   bool lo_open) {
  double value = 0;
  const auto r = std::from_chars(text.data(), text.data() + text.size(), value);
  if (r.ec != std::errc() || r.ptr != text.data() + text.size() || !std::isfinite(value))
    throw UsageError{flag + ": expected a number, got '" + text + "'"};
  if ((lo_open ? value <= lo : value < lo) || value > hi)
    throw UsageError{flag + ": " + text + " is out of range " + (lo_open ? "(" : "[") +
                     shortNumber(lo) + ", " + shortNumber(hi) + "]"};
  return value;
}

long long parseInteger(const std::string& flag, const std::string& text, long long lo,
                       long long hi) {
  long long value = 0;
  const auto r = std::from_chars(text.data(), text.data() + text.size(), value);
  if (r.ec != std::errc() || r.ptr != text.data() + text.size())
    throw UsageError{flag + ": expected an integer, got '" + text + "'"};
  if (value < lo || value > hi)
    throw UsageError{flag + ": " + text + " is out of range [" + std::to_string(lo) + ", " +
                     std::to_string(hi) + "]"};
  return value;
}

std::string parseChoice(const std::string& flag, const std::string& text,
                        const std::vector<std::string>& choices) {
  std::string list;
  for (const auto& c : choices) {
    if (c == text) return text;
    list += (list.empty() ? "" : "|") + c;
  }
  throw UsageError{flag + ": expected " + list + ", got '" + text + "'"};
}

/// Parses argv into `o`; returns false when --help was given.
bool parseArguments(int argc, char** argv, Options* o) {
  using Setter = std::function<void(const std::string& flag, const std::string& value)>;
  const std::map<std::string, Setter> setters = {
      {"--preset", [&](auto& f, auto& v) { o->preset = parseChoice(f, v, presetNames()); }},
      {"--trajectory",
       [&](auto& f, auto& v) { o->trajectory = parseChoice(f, v, trajectoryNames()); }},
      {"--frames",
       [&](auto& f, auto& v) {
         o->frames = static_cast<int>(parseInteger(f, v, 1, 1000000));
         o->frames_given = true;
       }},
      {"--width",
       [&](auto& f, auto& v) { o->width_px = static_cast<int>(parseInteger(f, v, 16, 8192)); }},
      {"--height",
       [&](auto& f, auto& v) { o->height_px = static_cast<int>(parseInteger(f, v, 16, 8192)); }},
      {"--fx", [&](auto& f, auto& v) { o->fx_px = parseDouble(f, v, 0, 1e5, true); }},
      {"--fy", [&](auto& f, auto& v) { o->fy_px = parseDouble(f, v, 0, 1e5, true); }},
      {"--baseline", [&](auto& f, auto& v) { o->baseline_m = parseDouble(f, v, 0, 10, true); }},
      {"--disparity",
       [&](auto& f, auto& v) {
         o->disparity = parseChoice(f, v, {"exact", "noisy", "sgbm"});
       }},
      {"--noise-px", [&](auto& f, auto& v) { o->noise_px = parseDouble(f, v, 0, 100, false); }},
      {"--outlier-fraction",
       [&](auto& f, auto& v) { o->outlier_fraction = parseDouble(f, v, 0, 1, false); }},
      {"--matcher-noise-px",
       [&](auto& f, auto& v) { o->matcher_noise_px = parseDouble(f, v, 0, 100, false); }},
      {"--mismatch-fraction",
       [&](auto& f, auto& v) { o->mismatch_fraction = parseDouble(f, v, 0, 1, false); }},
      {"--mismatch-views",
       [&](auto& f, auto& v) {
         o->mismatch_views = static_cast<int>(parseInteger(f, v, 0, 1000000));
       }},
      {"--sgbm-num-disparities",
       [&](auto& f, auto& v) {
         o->sgbm.num_disparities = static_cast<int>(parseInteger(f, v, 16, 1024));
         if (o->sgbm.num_disparities % 16 != 0) throw UsageError{f + ": must be a multiple of 16"};
       }},
      {"--sgbm-block-size",
       [&](auto& f, auto& v) {
         o->sgbm.block_size = static_cast<int>(parseInteger(f, v, 1, 31));
         if (o->sgbm.block_size % 2 == 0) throw UsageError{f + ": must be odd"};
       }},
      {"--seed",
       [&](auto& f, auto& v) {
         o->seed = static_cast<uint32_t>(parseInteger(f, v, 0, 4294967295LL));
       }},
      {"--revolutions",
       [&](auto& f, auto& v) { o->revolutions = parseDouble(f, v, 0, 100, true); }},
      {"--dynamic",
       [&](auto& f, auto& v) {
         o->dynamic = parseChoice(f, v, {"none", "person", "moved"});
       }},
      {"--drift",
       [&](auto& f, auto& v) {
         const size_t comma = v.find(',');
         if (comma == std::string::npos)
           throw UsageError{f + ": expected YAW_DEG,METRES, got '" + v + "'"};
         o->drift_yaw_deg = parseDouble(f, v.substr(0, comma), -180, 180, false);
         o->drift_m = parseDouble(f, v.substr(comma + 1), 0, 1000, false);
       }},
      {"--keyframe-every",
       [&](auto& f, auto& v) {
         o->keyframe_every = static_cast<int>(parseInteger(f, v, 1, 1000000));
       }},
      {"--rate-hz", [&](auto& f, auto& v) { o->rate_hz = parseDouble(f, v, 0, 1e6, true); }},
      {"--gt-max-edge",
       [&](auto& f, auto& v) { o->gt_max_edge_m = parseDouble(f, v, 0.001, 10, false); }},
      {"--bag",
       [&](auto& f, auto& v) {
         if (v.empty()) throw UsageError{f + ": expected a file name"};
         o->bag = v;
       }},
      {"--bag-world-frame",
       [&](auto& f, auto& v) {
         if (v.empty()) throw UsageError{f + ": expected a tf frame"};
         o->bag_world_frame = v;
       }},
      {"--bag-content",
       [&](auto& f, auto& v) {
         o->bag_content = parseChoice(f, v, {"disparity", "pair", "rectified-pair"});
       }},
      {"--out",
       [&](auto& f, auto& v) {
         if (v.empty()) throw UsageError{f + ": expected a folder"};
         o->out = v;
       }},
  };
  for (int i = 1; i < argc; ++i) {
    std::string flag = argv[i], value;
    if (flag == "--help" || flag == "-h") return false;
    const size_t eq = flag.find('=');
    const bool inline_value = flag.rfind("--", 0) == 0 && eq != std::string::npos;
    if (inline_value) {  // --flag=value
      value = flag.substr(eq + 1);
      flag = flag.substr(0, eq);
    }
    const auto it = setters.find(flag);
    if (it == setters.end()) throw UsageError{"unknown argument '" + flag + "'"};
    if (!inline_value) {
      if (i + 1 >= argc) throw UsageError{flag + ": missing value"};
      value = argv[++i];
    }
    it->second(flag, value);
  }
  if (o->out.empty()) throw UsageError{"--out DIR is required"};
  return true;
}

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

}  // namespace

int main(int argc, char** argv) {
  Options o;
  try {
    if (!parseArguments(argc, argv, &o)) {
      std::cout << kUsage;
      return 0;
    }
  } catch (const UsageError& e) {
    std::cerr << "stereo_fusion_simulate: " << e.message << "\n(see --help)\n";
    return 2;
  }

  std::string error;
  const auto camera =
      StereoCamera::create(o.width_px, o.height_px, o.fx_px, o.fy_px > 0 ? o.fy_px : o.fx_px,
                           (o.width_px - 1) / 2.0, (o.height_px - 1) / 2.0, o.baseline_m, &error);
  if (!camera) {
    std::cerr << "stereo_fusion_simulate: " << error << "\n";
    return 2;
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
    bag = StereoBagWriter::open(o.bag, topics, "left_optical", 1.0, &error);
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
