// stereo_fusion_fuse: offline reconstruction without a ROS master (scripts/fuse.sh).
#include <cstdio>
#include <cstring>

#include "fuser/OfflineFuser.h"

namespace {
const char* kUsage =
    "usage: stereo_fusion_fuse <seq-folder | file.bag> <out-dir> [--config FILE] [--set key=value "
    "...]\n"
    "                          [--frames N] [--mesh-every N] [--esdf-every N] [--quiet] "
    "[--load-map FILE]\n"
    "                          [--save-map FILE] [--trajectory FILE] [--time-planning]\n"
    "                          [--frame-log FILE]\n"
    "       stereo_fusion_fuse <out-dir> --load-map FILE [...]   (mesh a saved map)\n"
    "Fuses a dataset folder (see doc/dataset_format.md) or a rosbag (DisparityImage, Image, "
    "CameraInfo, /tf)\n"
    "and writes <out-dir>/mesh.ply and <out-dir>/stats.json (with --set texture=patches also\n"
    "<out-dir>/mesh.obj + mesh.mtl + mesh_atlas_K.png, textured from the camera images; with\n"
    "planning_enabled, the default, also esdf.ply, occupancy.pgm + occupancy.yaml and "
    "octomap.bt).\n"
    "  --config FILE     parameters in config/default.yaml's format (applied before --set); the\n"
    "                    nodelet's own keys are accepted too (one file for both): world_frame is\n"
    "                    a bag's frame (unless --world-frame), the others are checked and ignored\n"
    "  --set key=value   override one parameter; every key of config/default.yaml is accepted\n"
    "  --frames N        fuse only the first N frames\n"
    "  --frame-log FILE  append '<frame> <unix time s>' after every fused frame (flushed)\n"
    "  --mesh-every N    bring the mesh up to date after every N-th frame (default 1) and the "
    "last\n"
    "                    (texture patches are then cut from the frames that end a meshing pass)\n"
    "  --esdf-every N    bring the planning layer (occupancy, ESDF) up to date after every N-th "
    "frame\n"
    "                    (default 10) and the last; the free space is recorded every frame\n"
    "  --time-planning   also time a 100 000-point distance query and a batch rebuild of the\n"
    "                    planning layer (stats.json planning.query_100k_ms, planning.rebuild_ms)\n"
    "  --disparity-topic, --image-topic, --camera-info-topic, --world-frame\n"
    "                    what to read from a bag (defaults: /stereo/disparity,\n"
    "                    /stereo/left/image_rect_color, /stereo/left/camera_info, map)\n"
    "  --load-map FILE   start from a map saved with --save-map (same voxel_size_m, "
    "truncation_vox)\n"
    "  --save-map FILE   save the map after the last frame (versioned binary, checksummed)\n"
    "  --trajectory FILE a SLAM's corrected camera poses, TUM lines 'stamp tx ty tz qx qy qz qw' "
    "with\n"
    "                    stamps matching the frames' (typically keyframes): after the last frame "
    "the\n"
    "                    frames are fused again at the poses it implies (frames between two of "
    "its\n"
    "                    poses take their interpolated correction), as after a loop closure\n"
    "  --quiet           no progress output\n";
}

int main(int argc, char** argv) {
  std::vector<std::string> args(argv + 1, argv + argc);
  for (const std::string& a : args)
    if (a == "--help" || a == "-h") {
      std::fputs(kUsage, stdout);
      return 0;
    }
  stereo_fusion::FuseOptions options;
  std::string error;
  if (!stereo_fusion::parseFuseArguments(args, &options, &error)) {
    std::fprintf(stderr, "stereo_fusion_fuse: %s\n%s", error.c_str(), kUsage);
    return 2;
  }
  if (options.progress)
    for (const std::string& note : options.notes)
      std::fprintf(stderr, "stereo_fusion_fuse: note: %s\n", note.c_str());
  stereo_fusion::FuseReport report;
  if (!stereo_fusion::runOfflineFusion(options, &report, &error)) {
    std::fprintf(stderr, "stereo_fusion_fuse: %s\n", error.c_str());
    return 1;
  }
  size_t skipped = 0;
  for (const auto& [reason, n] : report.skipped) skipped += n;
  std::printf(
      "fused %zu of %zu frames (%zu skipped) in %.1f s: %zu blocks, %.1f MB, mesh %zu vertices / "
      "%zu triangles\n",
      report.frames_used, report.frames_total, skipped, report.wall_time_s, report.blocks,
      report.memory_bytes / 1048576.0, report.mesh_vertices, report.mesh_triangles);
  if (report.blocks_evicted > 0)
    std::printf("memory bound: %llu blocks evicted\n",
                static_cast<unsigned long long>(report.blocks_evicted));
  std::printf("wrote %s/mesh.ply and %s/stats.json\n", options.out_dir.c_str(),
              options.out_dir.c_str());
  if (options.config.texture == stereo_fusion::TextureMode::kPatches)
    std::printf(
        "wrote %s/mesh.obj + mesh.mtl + %zu atlas PNG(s): %zu textured blocks, texture memory %.1f "
        "MB\n",
        options.out_dir.c_str(), report.atlas_count, report.textured_blocks,
        report.texture_bytes / 1048576.0);
  if (report.correction.applied)
    std::printf(
        "trajectory %s: %zu of %zu poses matched fused frames; %zu frames fused again (%zu "
        "rejected) in %.1f s, "
        "largest correction %.3f m / %.2f deg\n",
        options.trajectory.c_str(), report.correction.matched_poses,
        report.correction.trajectory_poses, report.correction.frames_refused,
        report.correction.frames_rejected, report.correction.ms / 1000.0,
        report.correction.max_shift_m, report.correction.max_rotation_deg);
  if (!options.save_map.empty())
    std::printf("saved the map (%zu blocks) to %s\n", report.blocks + report.paged_out_blocks,
                options.save_map.c_str());
  // Meshing a loaded map alone is a success without frames.
  return report.frames_used > 0 || (!options.load_map.empty() && report.frames_total == 0) ? 0 : 1;
}
