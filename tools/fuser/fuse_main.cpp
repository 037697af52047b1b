// stereo_fusion_fuse: offline reconstruction without a ROS master (scripts/fuse.sh).
#include <cstdio>

#include "cli/CommandLine.h"
#include "fuser/FuseArguments.h"

int main(int argc, char** argv) {
  stereo_fusion::FuseOptions options;
  CLI::App app(
      "Fuses a dataset folder (see doc/dataset_format.md) or a rosbag (DisparityImage, Image,\n"
      "CameraInfo, /tf) and writes <out-dir>/mesh.ply and <out-dir>/stats.json (with --set\n"
      "texture=patches also <out-dir>/mesh.obj + mesh.mtl + mesh_atlas_K.png, textured from the\n"
      "camera images; with planning_enabled, the default, also esdf.ply, occupancy.pgm +\n"
      "occupancy.yaml and octomap.bt). `stereo_fusion_fuse <out-dir> --load-map FILE` meshes a\n"
      "saved map.",
      "stereo_fusion_fuse");
  stereo_fusion::addFuseArguments(&app, &options);
  app.footer("Exit codes: 0 done, 1 nothing could be fused or written, 2 bad arguments.");
  if (const auto exit_code = stereo_fusion::cli::parseOrExitCode(app, argc, argv))
    return *exit_code;
  if (options.progress)
    for (const std::string& note : options.notes)
      std::fprintf(stderr, "stereo_fusion_fuse: note: %s\n", note.c_str());
  std::string error;
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
