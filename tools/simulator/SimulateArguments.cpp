#include "simulator/SimulateArguments.h"

#include "cli/CommandLine.h"
#include "cli/NumberChecks.h"
#include "simulator/SceneLibrary.h"
#include "simulator/Trajectory.h"

namespace stereo_fusion::sim {
namespace {

/// What OpenCV's StereoSGBM asks of its integers (CLI11 has no such checks). A value that is no
/// integer passes here: the CLI::Range beside this refuses it.
CLI::Validator integerWhere(bool (*rule)(int), const std::string& what) {
  return CLI::Validator(
      [rule, what](std::string& value) {
        int number = 0;
        if (!CLI::detail::lexical_cast(value, number) || rule(number)) return std::string();
        return "'" + value + "' is not " + what;
      },
      what);
}
const CLI::Validator kMultipleOf16 =
    integerWhere([](int n) { return n % 16 == 0; }, "a multiple of 16");
const CLI::Validator kOdd = integerWhere([](int n) { return n % 2 != 0; }, "odd");

/// A path or a frame name: an empty one would fail later, less clearly.
const CLI::Validator kNotEmpty(
    [](std::string& value) { return value.empty() ? std::string("must not be empty") : ""; }, "");

}  // namespace

void addSimulateArguments(CLI::App* app, SimulateOptions* o) {
  app->description(
      "Renders a rectified stereo sequence of an analytic scene and writes it as a dataset\n"
      "folder: calibration.yaml, poses.txt, disparity/ color/ right/ NNNNNN.png, gt_mesh.ply.");
  app->footer("Exit codes: 0 done, 1 generation or write failure, 2 bad arguments.");
  app->get_formatter()->column_width(34);
  app->add_option("--preset", o->preset,
                  "scene (default room; hall: far-range, walls 3–4.5 m away; building: eight\n"
                  "furnished rooms along a corridor, a map larger than memory caps for benches\n"
                  "of paging; building_long: sixteen, twice the map)")
      ->check(CLI::IsMember(presetNames()));
  app->add_option("--trajectory", o->trajectory,
                  "camera path (default walkthrough; building: the walkthrough is a tour\n"
                  "through every room, ending back in the first)")
      ->check(CLI::IsMember(trajectoryNames()));
  app->add_option_function<int>(
         "--frames",
         [o](int frames) {
           o->frames = frames;
           o->frames_given = true;
         },
         "number of frames (default 100; a building's walkthrough: one whole tour, ~900\n"
         "frames, ~1800 for building_long; fewer: its start only)")
      ->check(CLI::Range(1, 1000000));
  app->add_option("--width", o->width_px, "image width in pixels (default 640)")
      ->check(CLI::Range(16, 8192));
  app->add_option("--height", o->height_px, "image height in pixels (default 480)")
      ->check(CLI::Range(16, 8192));
  app->add_option("--fx", o->fx_px, "focal length in pixels (default 525)")
      ->check(cli::positiveUpTo(1e5));
  app->add_option("--fy", o->fy_px, "vertical focal length (default: fx); cx, cy = image centre")
      ->check(cli::positiveUpTo(1e5));
  app->add_option("--baseline", o->baseline_m, "stereo baseline in metres (default 0.1)")
      ->check(cli::positiveUpTo(10));
  app->add_option("--disparity", o->disparity, "disparity source (default sgbm)")
      ->check(CLI::IsMember({"exact", "noisy", "sgbm"}));
  app->add_option("--noise-px", o->noise_px, "noisy: Gaussian sigma in pixels (default 0.3)")
      ->check(cli::numberIn(0, 100));
  app->add_option("--outlier-fraction", o->outlier_fraction,
                  "noisy: share of outliers in [0, 1] (default 0.01)")
      ->check(cli::numberIn(0, 1));
  app->add_option("--matcher-noise-px", o->matcher_noise_px,
                  "any mode: Gaussian sigma added per pixel and frame (default 0)")
      ->check(cli::numberIn(0, 100));
  app->add_option("--mismatch-fraction", o->mismatch_fraction,
                  "any mode: share in [0, 1] of 5 cm surface patches where the matcher errs by\n"
                  "the same 1-3 px in every view of a window of neighbouring frames (default 0);\n"
                  "real SGBM on far walls: --matcher-noise-px 0.2 --mismatch-fraction 0.03")
      ->check(cli::numberIn(0, 1));
  app->add_option("--mismatch-views", o->mismatch_views,
                  "frames per window of equal mismatches (default 5; 0: every frame of the\n"
                  "sequence errs alike)")
      ->check(CLI::Range(0, 1000000));
  app->add_option("--sgbm-num-disparities", o->sgbm.num_disparities,
                  "sgbm: search range, a multiple of 16 (default 128)")
      ->check(CLI::Range(16, 1024) & kMultipleOf16);
  app->add_option("--sgbm-block-size", o->sgbm.block_size,
                  "sgbm: odd matching window size (default 5)")
      ->check(CLI::Range(1, 31) & kOdd);
  app->add_option("--seed", o->seed, "scene, path and noise seed, 0..4294967295 (default 0)")
      ->check(CLI::Range(0LL, 4294967295LL));
  app->add_option("--revolutions", o->revolutions,
                  "orbit: laps over the whole sequence (default 1)")
      ->check(cli::positiveUpTo(100));
  app->add_option(
         "--dynamic", o->dynamic,
         "objects that change during the sequence (default none): person: a person\n"
         "(cylinder 0.5 m wide, 1.7 m tall) stands at the orbit's focus during the first\n"
         "half of the frames only; moved: a box stands beside the focus in the first half\n"
         "and on its other side in the second. gt_mesh.ply is the scene as it ends;\n"
         "dynamic.txt lists where objects stood that left (the evaluator reports the\n"
         "surface left there as ghost)")
      ->check(CLI::IsMember({"none", "person", "moved"}));
  app->add_option_function<std::pair<double, double>>(
         "--drift",
         [o](const std::pair<double, double>& drift) {
           o->drift_yaw_deg = drift.first;
           o->drift_m = drift.second;
         },
         "poses.txt (and the bag's /tf) drift like odometry: by the last frame YAW_DEG of yaw\n"
         "about the vertical through the first camera and METRES of horizontal offset,\n"
         "growing linearly; the images stay true. Also writes poses_true.txt and\n"
         "trajectory.txt, a SLAM's corrected keyframe poses (the true poses of every\n"
         "--keyframe-every-th frame, TUM lines); a bag gets that trajectory as nav_msgs/Path\n"
         "on /trajectory twice, after the middle frame (keyframes so far) and after the last")
      ->delimiter(',')
      ->type_name("YAW_DEG,METRES")
      ->check(cli::numberIn(-180, 180).application_index(0))
      ->check(cli::numberIn(0, 1000).application_index(1));
  app->add_option("--keyframe-every", o->keyframe_every,
                  "keyframe spacing of trajectory.txt (default 5)")
      ->check(CLI::Range(1, 1000000));
  app->add_option("--rate-hz", o->rate_hz, "frame rate for the timestamps (default 10)")
      ->check(cli::positiveUpTo(1e6));
  app->add_option("--gt-max-edge", o->gt_max_edge_m,
                  "ground-truth mesh grid step in metres (default 0.03)")
      ->check(cli::numberIn(0.001, 10));
  app->add_option("--out", o->out, "output folder (created; an old dataset there is replaced)")
      ->required()
      ->type_name("DIR")
      ->check(kNotEmpty);
  app->add_option("--bag", o->bag,
                  "also write a rosbag: DisparityImage, Image, CameraInfo on the nodelet's\n"
                  "default topics and /tf (map -> left_optical); stamps = timestamps + 1 s (ROS\n"
                  "time 0 means \"latest\" to tf)")
      ->type_name("FILE")
      ->check(kNotEmpty);
  app->add_option_function<std::string>(
         "--bag-world-frame",
         [o](const std::string& frame) {
           o->bag_world_frame = frame;
           o->bag_world_frame_given = true;
         },
         "the bag's tf parent frame and the trajectory's frame (default map, the\n"
         "nodelet's default world_frame; e.g. odom)")
      ->type_name("FRAME")
      ->check(kNotEmpty);
  app->add_option("--bag-robot", o->bag_robot,
                  "one robot of a fleet (--bag-content disparity): the bag's topics under /NAME\n"
                  "(/NAME/stereo/disparity, ...), its camera frame NAME/left_optical and its\n"
                  "world frame NAME/map (unless --bag-world-frame), so several robots' bags\n"
                  "play through one rosbag player into nodelets in namespaces NAME")
      ->type_name("NAME")
      ->check(kNotEmpty);
  app->add_option(
         "--bag-content", o->bag_content,
         "disparity (default): what the nodelet subscribes to; pair: what a stereo\n"
         "camera driver publishes, for launch/stereo_pipeline.launch:\n"
         "/stereo/{left,right}/image_raw (rgb8, already rectified), both camera_info,\n"
         "/tf; no disparity; rectified-pair: the same as a rectifying driver publishes\n"
         "it, for stereo_pipeline.launch rectified:=true: /stereo/{left,right}/image_rect\n"
         "(mono8), /stereo/left/image_rect_color (rgb8), both camera_info, /tf")
      ->check(CLI::IsMember({"disparity", "pair", "rectified-pair"}));
}

}  // namespace stereo_fusion::sim
