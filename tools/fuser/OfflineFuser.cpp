#include "fuser/OfflineFuser.h"

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <nlohmann/json.hpp>

#include "fuser/OctomapExport.h"
#include "readers/DatasetReader.h"
#include "stereo_fusion/Mapper.h"
#include "stereo_fusion/io/ConfigFile.h"
#include "stereo_fusion/io/ObjWriter.h"
#include "stereo_fusion/io/PlanningExport.h"
#include "stereo_fusion/io/PlyWriter.h"
#include "stereo_fusion/ros/BagSequence.h"
#include "stereo_fusion/session/MappingSession.h"
#include "stereo_fusion/trajectory/PoseCorrection.h"
#include "stereo_fusion/util/Percentile.h"
#include "stereo_fusion/util/ProcessMemory.h"
#include "stereo_fusion/util/Timer.h"

namespace stereo_fusion {

namespace fs = std::filesystem;

bool parseFuseArguments(const std::vector<std::string>& args, FuseOptions* options,
                        std::string* error) {
  std::vector<std::string> positional, sets;
  std::string config_file;
  for (size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    auto value = [&](const char* flag) -> const std::string* {
      if (i + 1 >= args.size()) {
        *error = std::string(flag) + " needs a value";
        return nullptr;
      }
      return &args[++i];
    };
    if (a == "--config") {
      const std::string* v = value("--config");
      if (!v) return false;
      config_file = *v;
    } else if (a == "--set") {
      const std::string* v = value("--set");
      if (!v) return false;
      sets.push_back(*v);
    } else if (a == "--frames" || a == "--mesh-every" || a == "--esdf-every") {
      const std::string* v = value(a.c_str());
      if (!v) return false;
      const bool mesh_every = a != "--frames";  // a period: at least 1
      try {
        size_t used = 0;
        const long n = std::stol(*v, &used);
        if (used != v->size() || n < (mesh_every ? 1 : 0)) throw std::invalid_argument("");
        (a == "--mesh-every"   ? options->mesh_every
         : a == "--esdf-every" ? options->esdf_every
                               : options->max_frames) = static_cast<size_t>(n);
      } catch (...) {
        *error = a + ": '" + *v + "' is not a " + (mesh_every ? "frame count ≥ 1" : "frame count");
        return false;
      }
    } else if (a == "--disparity-topic" || a == "--image-topic" || a == "--camera-info-topic" ||
               a == "--world-frame") {
      const std::string* v = value(a.c_str());
      if (!v) return false;
      (a == "--disparity-topic"     ? options->bag_topics.disparity
       : a == "--image-topic"       ? options->bag_topics.image
       : a == "--camera-info-topic" ? options->bag_topics.camera_info
                                    : options->bag_topics.world_frame) = *v;
    } else if (a == "--load-map" || a == "--save-map" || a == "--trajectory") {
      const std::string* v = value(a.c_str());
      if (!v) return false;
      (a == "--load-map"   ? options->load_map
       : a == "--save-map" ? options->save_map
                           : options->trajectory) = *v;
    } else if (a == "--quiet") {
      options->progress = false;
    } else if (a == "--time-planning") {
      options->time_planning = true;
    } else if (!a.empty() && a[0] == '-') {
      *error = "unknown option '" + a + "'";
      return false;
    } else {
      positional.push_back(a);
    }
  }
  if (positional.size() == 1 && !options->load_map.empty()) {
    options->out_dir = positional[0];  // mesh a saved map, no frames
  } else if (positional.size() == 2) {
    options->input = positional[0];
    options->out_dir = positional[1];
  } else {
    *error = "expected <seq-folder | file.bag> <out-dir> (or <out-dir> with --load-map), got " +
             std::to_string(positional.size()) + " arguments";
    return false;
  }
  if (!options->trajectory.empty() && options->input.empty()) {
    *error = "--trajectory needs the frames it corrects (an input folder or bag)";
    return false;
  }
  if (!config_file.empty() && !loadMapperConfigFile(config_file, &options->config, error))
    return false;
  for (const std::string& s : sets) {
    const size_t eq = s.find('=');
    if (eq == std::string::npos) {
      *error = "--set expects key=value, got '" + s + "'";
      return false;
    }
    if (!setMapperParameter(&options->config, s.substr(0, eq), s.substr(eq + 1), error))
      return false;
  }
  const auto problems = validateMapperConfig(options->config);
  if (!problems.empty()) {
    *error = problems.front();
    return false;
  }
  return true;
}

namespace {

void showProgress(size_t done, size_t total, double elapsed_s, bool terminal, size_t* last_decile) {
  const double fps = elapsed_s > 0 ? done / elapsed_s : 0.0;
  const double eta = fps > 0 ? (total - done) / fps : 0.0;
  if (terminal) {
    const int width = 30;
    const int filled = total ? static_cast<int>(width * done / total) : width;
    std::fprintf(stderr, "\r[%s%s] %zu/%zu frames  %.1f fps  ETA %.0f s ",
                 std::string(filled, '=').c_str(), std::string(width - filled, ' ').c_str(), done,
                 total, fps, eta);
    if (done == total) std::fprintf(stderr, "\n");
  } else {
    const size_t decile = total ? 10 * done / total : 10;
    if (decile != *last_decile) {
      *last_decile = decile;
      std::fprintf(stderr, "%zu/%zu frames  %.1f fps  ETA %.0f s\n", done, total, fps, eta);
    }
  }
}

struct Summary {
  double mean = 0, p50 = 0, p99 = 0;
};

Summary summarize(std::vector<double> v) {
  Summary s;
  if (v.empty()) return s;
  double sum = 0;
  for (double x : v) sum += x;
  s.mean = sum / v.size();
  std::sort(v.begin(), v.end());
  s.p50 = percentileOfSorted(v, 0.50);
  s.p99 = percentileOfSorted(v, 0.99);
  return s;
}

/// The usable poses of a TUM trajectory file, by stamp.
bool readTrajectory(const std::string& path, std::vector<StampedPose>* poses, std::string* error) {
  std::vector<DatasetFrameInfo> lines;
  if (!readTumPoses(path, &lines, error)) return false;
  for (const DatasetFrameInfo& line : lines)
    if (line.pose_error.empty()) poses->push_back({line.timestamp_s, line.T_world_camera});
  sortByStamp(poses);
  if (poses->empty()) {
    *error = path + ": no usable pose";
    return false;
  }
  return true;
}

}  // namespace

namespace {
/// esdf.ply, occupancy.pgm + .yaml and octomap.bt of the planning layer, and its figures.
bool writePlanningOutputs(const std::string& out_dir, Mapper* mapper, bool time_queries,
                          FuseReport::Planning* report, std::string* error) {
  const PlanningMap* planning = mapper->planning();
  if (!planning) return true;
  report->enabled = true;
  report->cell_m = planning->grid().cell_m;
  report->max_distance_m = planning->config().max_distance_m;
  report->blocks = planning->blockCount();
  report->free_space_bytes = planning->freeSpaceBytes();
  report->esdf_bytes = planning->esdfBytes();
  Eigen::AlignedBox3d known;
  planning->forEachKnownCell([&](const CellIndex& cell, CellState state, double) {
    (state == CellState::kOccupied ? report->cells_occupied : report->cells_free) += 1;
    known.extend(planning->grid().centre(cell));
  });
  if (time_queries && !known.isEmpty()) {  // what a planner's batch query of 100 000 points costs
    std::mt19937 rng(1);
    std::vector<Eigen::Vector3d> points(100000);
    for (Eigen::Vector3d& p : points)
      for (int a = 0; a < 3; ++a)
        p[a] = std::uniform_real_distribution<double>(known.min()[a], known.max()[a])(rng);
    std::vector<EsdfSample> samples;
    Timer query;
    planning->sampleBatch(points, &samples);
    report->query_100k_ms = query.elapsedMs();
  }
  const fs::path dir(out_dir);
  if (!writeEsdfPly((dir / "esdf.ply").string(), *planning, error)) return false;
  const MapperConfig& config = mapper->config();
  const OccupancyGrid2D grid = projectOccupancy(*planning, config.grid_min_z_m, config.grid_max_z_m,
                                                mapper->occupancyGridWindow());
  if (grid.windowed)
    std::fprintf(stderr,
                 "warning: occupancy grid windowed: the known columns span %lld x %lld cells, "
                 "more than grid_max_cells (%d); occupancy.pgm holds %d x %d around the last "
                 "camera\n",
                 static_cast<long long>(grid.known_width),
                 static_cast<long long>(grid.known_height), config.grid_max_cells, grid.width,
                 grid.height);
  if (!writeOccupancyMap((dir / "occupancy.pgm").string(), (dir / "occupancy.yaml").string(), grid,
                         error))
    return false;
  if (!writeOctomap((dir / "octomap.bt").string(), *planning, &report->octomap_cells_skipped,
                    error))
    return false;
  if (time_queries) {  // what a batch rebuild costs (it recomputes the same layer: incremental ==
                       // batch)
    Timer rebuild;
    mapper->rebuildPlanning();
    report->rebuild_ms = rebuild.elapsedMs();
  }
  return true;
}
}  // namespace

bool runOfflineFusion(const FuseOptions& options, FuseReport* report, std::string* error) {
  *report = FuseReport{};
  std::unique_ptr<FrameSource> reader;
  if (options.input.empty()) {
    // No frames: only the loaded map is meshed.
  } else if (fs::path(options.input).extension() == ".bag") {
    reader = BagSequence::open(options.input, options.bag_topics, error);
    if (!reader) return false;
  } else if (auto folder = DatasetReader::open(options.input, error)) {
    reader = std::make_unique<DatasetReader>(std::move(*folder));
  } else {
    return false;
  }
  std::vector<StampedPose> trajectory;
  if (!options.trajectory.empty() && !readTrajectory(options.trajectory, &trajectory, error))
    return false;
  // The session keeps every frame's stamp and pose for --trajectory (the images are read again
  // from the input), and its one re-fusion routine applies the trajectory after the last frame.
  SessionConfig session_config;
  session_config.loop_closure_max_frames =
      trajectory.empty() ? 0 : std::numeric_limits<size_t>::max();
  session_config.background_corrections = false;
  MappingSession session(options.config, session_config);
  // Offline, one thread: the mapper is used directly between session calls (a correction
  // swaps it: take it again after).
  Mapper* mapper = session.withMapper([](Mapper& m) { return &m; });
  if (!options.load_map.empty()) {
    const MappingSession::LoadOutcome loaded = session.load(options.load_map);
    if (!loaded.success) {
      *error = loaded.message;
      return false;
    }
    report->blocks_loaded = loaded.blocks;
  }
  std::error_code ec;
  fs::create_directories(options.out_dir, ec);
  if (ec || !fs::is_directory(options.out_dir)) {
    *error = options.out_dir + ": cannot create the output directory";
    return false;
  }

  const size_t available = reader ? reader->size() : 0;
  const size_t total = options.max_frames ? std::min(options.max_frames, available) : available;
  report->frames_total = total;
  const bool terminal = isatty(STDERR_FILENO);
  size_t last_decile = 0;
  Timer wall;
  auto skip = [&](RejectReason reason, const std::string& message) {
    ++report->skipped[rejectReasonName(reason)];
    if (report->skipped_examples.size() < 5) report->skipped_examples.push_back(message);
    std::fprintf(stderr, "%sskipping frame: %s\n", terminal && options.progress ? "\n" : "",
                 message.c_str());
  };
  report->start_rss_bytes = readProcessMemory().resident_mb * 1048576.0;
  for (size_t i = 0; i < total; ++i) {
    StereoFrame frame;
    std::string why;
    bool loaded = false;
    try {
      loaded = reader->load(i, &frame, &why);
    } catch (const std::exception& e) {  // e.g. OpenCV on a pathological image
      why = "frame " + std::to_string(i) + ": " + e.what();
    }
    if (!loaded) {
      skip(RejectReason::kUnreadable, why);
    } else {
      Timer frame_timer;
      // Mesh after every mesh_every-th fused frame; the last frame's pass comes after the loop.
      const bool mesh_now = (report->frames_used + 1) % options.mesh_every == 0;
      FrameLoader reload;
      if (!trajectory.empty()) {
        FrameSource* source = reader.get();
        reload = [source, i](StereoFrame* again, std::string* why) {
          return source->load(i, again, why);
        };
      }
      const MappingSession::FrameOutcome out = session.fuse(
          frame, session.arrive(), mesh_now ? MeshTiming::kNow : MeshTiming::kDeferred, reload);
      const IntegrationResult& r = out.result;
      if (out.reason == RejectReason::kError) {
        // Out of memory mid-frame: stop cleanly with what we have rather than crash. Set
        // max_blocks to stay within memory.
        *error = "frame " + std::to_string(i) + ": " + out.error + " with " +
                 std::to_string(mapper->map().blockCount()) + " blocks; set max_blocks";
        return false;
      }
      if (out.reason != RejectReason::kNone) {
        skip(out.reason, "frame " + std::to_string(i) + ": " + out.error);
      } else {
        ++report->frames_used;
        report->pixels_rejected.speckle_pixels += r.rejected.speckle_pixels;
        report->pixels_rejected.edge_pixels += r.rejected.edge_pixels;
        report->pixels_contradicting += r.contradiction.pixels_rejected;
        if (std::isfinite(r.disparity_noise_px))
          report->disparity_noise_px.push_back(r.disparity_noise_px);
        if (r.reanchored) {
          ++report->frames_reanchored;
          std::fprintf(stderr, "%sframe %zu: %s\n", terminal && options.progress ? "\n" : "", i,
                       r.note.c_str());
        }
        StageTimings timings{r.lookup_ms,          r.fusion_ms, r.carve_ms, r.mesh.meshing_ms,
                             r.texture.texture_ms, 0.0,         mesh_now};
        timings.free_space_ms = r.free_space_ms;
        timings.contradiction_ms = r.contradiction_ms;
        timings.free_space_nodes = static_cast<double>(r.free_space.nodes_visited);
        if (mapper->planning() && report->frames_used % options.esdf_every == 0) {
          const PlanningPass pass = mapper->updatePlanning();
          timings.esdf_ms = pass.esdf_ms;
          timings.esdf_updated = true;
          timings.esdf_read_ms = pass.stats.read_ms;
          timings.esdf_propagate_ms = pass.stats.propagate_ms;
          timings.esdf_transit_ms = pass.stats.transit_ms;
          timings.esdf_transit_blocks = static_cast<double>(pass.stats.transit_allocated);
          timings.esdf_tsdf_blocks = static_cast<double>(pass.stats.tsdf_blocks);
          timings.esdf_flipped = static_cast<double>(pass.stats.esdf.cells_flipped);
          timings.esdf_raised = static_cast<double>(pass.stats.esdf.cells_raised);
          timings.esdf_lowered = static_cast<double>(pass.stats.esdf.cells_lowered);
        }
        timings.total_ms = frame_timer.elapsedMs();
        report->timings.push_back(timings);
        report->work.push_back(
            {static_cast<double>(r.lookup.valid_points),
             static_cast<double>(r.lookup.octree_searches),
             static_cast<double>(r.lookup.blocks_queued),
             static_cast<double>(r.fusion.blocks_updated),
             static_cast<double>(r.fusion.voxels_updated),
             static_cast<double>(r.mesh.blocks_meshed), static_cast<double>(r.mesh.changed.size()),
             static_cast<double>(r.fusion.blocks_created),
             static_cast<double>(r.fusion.blocks_not_created),
             static_cast<double>(r.carve.blocks_carved), static_cast<double>(r.carve.voxels_carved),
             static_cast<double>(r.lookup.box_blocks)});
      }
    }
    if (options.progress)
      showProgress(i + 1, total, wall.elapsedMs() / 1000.0, terminal, &last_decile);
  }
  if (mapper->blocksAwaitingMesh() > 0) {  // the frames since the last meshing pass
    Timer mesh_timer;
    const MeshPass pass = mapper->updateMesh();
    if (!report->timings.empty() && !report->timings.back().meshed) {
      StageTimings& last = report->timings.back();
      last.meshing_ms = pass.mesh.meshing_ms;
      last.texture_ms = pass.texture.texture_ms;
      last.total_ms += mesh_timer.elapsedMs();
      last.meshed = true;
    }
  }
  if (mapper->planning() && !report->timings.empty() && !report->timings.back().esdf_updated) {
    StageTimings& last = report->timings.back();  // the frames since the last planning update
    last.esdf_ms = mapper->updatePlanning().esdf_ms;
    last.total_ms += last.esdf_ms;
    last.esdf_updated = true;
  }
  // Once, at the end: what the data say against what was configured.
  if (const std::string warning = mapper->disparityNoiseWarning(); !warning.empty())
    std::fprintf(stderr, "warning: %s\n", warning.c_str());
  if (!trajectory.empty() && report->frames_used > 0) {
    if (options.progress)
      std::fprintf(stderr, "applying %s: fusing %zu frames again at their corrected poses\n",
                   options.trajectory.c_str(), report->frames_used);
    // Offline the trajectory comes after every frame: all of them share the drift it removes.
    const std::optional<CorrectionReport> c =
        session.submitTrajectory(trajectory, std::numeric_limits<double>::infinity());
    TrajectoryReport& t = report->correction;
    t.trajectory_poses = trajectory.size();
    if (c) {
      t.matched_poses = c->matched_poses;
      t.max_shift_m = c->max_shift_m;
      t.max_rotation_deg = c->max_rotation_deg;
      t.frames_refused = c->frames_refused;
      t.frames_rejected = c->frames_rejected;
      t.ms = c->ms;
      t.applied = c->outcome == TrajectoryOutcome::kApplied ||
                  c->outcome == TrajectoryOutcome::kAppliedWithoutRefusion;
    }
    if (!t.applied) {
      *error =
          options.trajectory + ": " + (c ? c->message : std::string("not applied")) +
          (c && c->outcome == TrajectoryOutcome::kRejectedNoMatch ? " (poses.txt's / the bag's)"
                                                                  : "");
      return false;
    }
    mapper = session.withMapper([](Mapper& m) { return &m; });
    mapper->updatePlanning();
  }
  report->wall_time_s = wall.elapsedMs() / 1000.0;

  if (!options.save_map.empty() && !mapper->saveMap(options.save_map, error)) return false;
  {
    // Welded, written and let go: the copy is not kept beside the outputs that follow.
    const TriangleMesh mesh = mapper->extractMesh();
    report->mesh_vertices = mesh.positions.size();
    report->mesh_triangles = mesh.triangles.size();
    report->mesh_output_bytes = mesh.positions.size() * sizeof(mesh.positions[0]) +
                                mesh.normals.size() * sizeof(mesh.normals[0]) +
                                mesh.colors.size() * sizeof(mesh.colors[0]) +
                                mesh.triangles.size() * sizeof(mesh.triangles[0]);
    if (!writePly((fs::path(options.out_dir) / "mesh.ply").string(), mesh, error)) return false;
  }
  report->blocks = mapper->map().blockCount();
  report->blocks_evicted = mapper->blocksEvicted();
  report->memory_bytes = mapper->map().memoryBytes();
  report->bytes_per_block = mapper->map().bytesPerBlock();
  report->memory = mapper->map().memoryUse();
  report->mesh_store_bytes = mapper->mesh().memoryBytes();
  if (!mapper->map().blocks().empty()) {
    BlockKey lo = mapper->map().blocks().front()->key, hi = lo;
    for (const VoxelBlock* b : mapper->map().blocks()) {
      lo = componentMin(lo, b->key);
      hi = componentMax(hi, b->key);
    }
    const double voxels_per_block = static_cast<double>(kFinestSide) * kFinestSide * kFinestSide;
    report->dense_grid_bytes = (hi.x - lo.x + 1.0) * (hi.y - lo.y + 1.0) * (hi.z - lo.z + 1.0) *
                               voxels_per_block * sizeof(Voxel);
  }
  const MeshStates& mesh_states =
      mapper->mesh().states();  // current: the mesh was brought up to date above
  for (const VoxelBlock* b : mapper->map().blocks()) {
    if (b->row >= mesh_states.size()) continue;
    const MeshBlockState& state = mesh_states[*b];
    ++report->blocks_per_level[state.level];
    report->seam_filled_blocks += state.seam_filled;
  }

  report->textured_blocks = mapper->textures().patches().size();
  report->texture_bytes = mapper->textures().memoryBytes();
  if (options.config.texture == TextureMode::kPatches) {
    ObjExportInfo info;
    if (!writeTexturedObj((fs::path(options.out_dir) / "mesh.obj").string(),
                          mapper->mesh().submeshes(), mapper->textures().patches(),
                          ObjExportOptions{}, &info, error))
      return false;
    report->atlas_count = info.files.size() - 2;  // besides the .obj and the .mtl
  }
  if (!writePlanningOutputs(options.out_dir, mapper, options.time_planning, &report->planning,
                            error))
    return false;
  // After every output: the peak of the whole run.
  struct rusage usage {};
  if (getrusage(RUSAGE_SELF, &usage) == 0)
    report->peak_rss_bytes = usage.ru_maxrss * 1024.0;  // KiB on Linux
  report->file_rss_bytes = readProcessMemory().file_mb * 1048576.0;
  std::ofstream stats(fs::path(options.out_dir) / "stats.json");
  stats << statsJson(*report, options.config) << "\n";
  if (!stats) {
    *error = options.out_dir + "/stats.json: write failed";
    return false;
  }
  return true;
}

std::string statsJson(const FuseReport& report, const MapperConfig& config) {
  nlohmann::ordered_json j;
  j["frames"]["total"] = report.frames_total;
  j["frames"]["used"] = report.frames_used;
  j["frames"]["reanchored"] = report.frames_reanchored;
  j["pixels_rejected"]["speckle"] = report.pixels_rejected.speckle_pixels;
  j["pixels_rejected"]["depth_edge"] = report.pixels_rejected.edge_pixels;
  j["pixels_rejected"]["behind_confident_surface"] = report.pixels_contradicting;
  j["disparity_noise_px"] = {{"configured", config.disparity_noise_px},
                             {"measured_p50", summarize(report.disparity_noise_px).p50},
                             {"frames_measured", report.disparity_noise_px.size()}};
  size_t skipped = 0;
  for (const auto& [reason, n] : report.skipped) skipped += n;
  j["frames"]["skipped"] = skipped;
  j["frames"]["skipped_by_reason"] = nlohmann::ordered_json::object();
  for (const auto& [reason, n] : report.skipped) j["frames"]["skipped_by_reason"][reason] = n;
  j["frames"]["skipped_examples"] = report.skipped_examples;
  j["blocks"]["total"] = report.blocks;
  j["blocks"]["meshed_at_8"] = report.blocks_per_level[0];
  j["blocks"]["meshed_at_4"] = report.blocks_per_level[1];
  j["blocks"]["meshed_at_2"] = report.blocks_per_level[2];
  j["blocks"]["seam_filled"] = report.seam_filled_blocks;
  j["blocks"]["evicted"] = report.blocks_evicted;
  j["map"]["loaded_blocks"] = report.blocks_loaded;
  j["memory"]["bytes"] = report.memory_bytes;
  j["memory"]["megabytes"] = report.memory_bytes / 1048576.0;
  j["memory"]["bytes_per_block"] = report.bytes_per_block;
  // Bytes by part, and per level the blocks holding it and its bytes per such block.
  j["memory"]["block_fixed_bytes"] = report.memory.block_bytes;
  j["memory"]["octree_node_bytes"] = report.memory.node_bytes + report.memory.bookkeeping_bytes;
  const char* level_names[kNumLevels] = {"8", "4", "2"};
  for (int level = 0; level < kNumLevels; ++level) {
    auto& l = j["memory"]["levels"][level_names[level]];
    l["blocks"] = report.memory.level_blocks[level];
    l["bytes"] = report.memory.level_bytes[level];
    l["bytes_per_block"] = levelVoxelCount(level) * sizeof(Voxel);
  }
  j["memory"]["peak_rss_megabytes"] = report.peak_rss_bytes / 1048576.0;
  j["memory"]["start_rss_megabytes"] = report.start_rss_bytes / 1048576.0;
  j["memory"]["file_rss_megabytes"] = report.file_rss_bytes / 1048576.0;
  j["memory"]["mesh_store_megabytes"] = report.mesh_store_bytes / 1048576.0;
  j["memory"]["mesh_output_megabytes"] = report.mesh_output_bytes / 1048576.0;
  j["memory"]["dense_grid_megabytes"] = report.dense_grid_bytes / 1048576.0;
  j["memory"]["dense_grid_ratio"] =
      report.memory_bytes > 0 ? report.dense_grid_bytes / report.memory_bytes : 0.0;
  j["mesh"]["vertices"] = report.mesh_vertices;
  j["mesh"]["triangles"] = report.mesh_triangles;
  j["texture"]["textured_blocks"] = report.textured_blocks;
  j["texture"]["bytes"] = report.texture_bytes;
  j["texture"]["megabytes"] = report.texture_bytes / 1048576.0;
  j["texture"]["atlases"] = report.atlas_count;
  // Lookup, fusion and total over every fused frame; meshing and texture over the meshing
  // passes only (one per frame with --mesh-every 1).
  auto stage = [&](double StageTimings::*field, bool mesh_calls_only) {
    std::vector<double> v;
    for (const StageTimings& t : report.timings)
      if (t.meshed || !mesh_calls_only) v.push_back(t.*field);
    const Summary s = summarize(v);
    return nlohmann::ordered_json{{"mean", s.mean},
                                  {"p50", s.p50},
                                  {"p99", s.p99},
                                  {"per", mesh_calls_only ? "mesh call" : "frame"}};
  };
  j["timings_ms"]["lookup"] = stage(&StageTimings::lookup_ms, false);
  j["timings_ms"]["fusion"] = stage(&StageTimings::fusion_ms, false);
  j["timings_ms"]["carve"] = stage(&StageTimings::carve_ms, false);
  j["timings_ms"]["contradiction"] = stage(&StageTimings::contradiction_ms, false);
  j["timings_ms"]["meshing"] = stage(&StageTimings::meshing_ms, true);
  j["timings_ms"]["texture"] = stage(&StageTimings::texture_ms, true);
  j["timings_ms"]["free_space"] = stage(&StageTimings::free_space_ms, false);
  {
    // Over the frames after which the planning layer was updated.
    auto overUpdates = [&](double StageTimings::*field) {
      std::vector<double> v;
      for (const StageTimings& t : report.timings)
        if (t.esdf_updated) v.push_back(t.*field);
      return summarize(v);
    };
    const Summary s = overUpdates(&StageTimings::esdf_ms);
    j["timings_ms"]["esdf"] = {
        {"mean", s.mean}, {"p50", s.p50}, {"p99", s.p99}, {"per", "planning update"}};
    j["planning_work_p50"]["read_ms"] = overUpdates(&StageTimings::esdf_read_ms).p50;
    j["planning_work_p50"]["propagate_ms"] = overUpdates(&StageTimings::esdf_propagate_ms).p50;
    j["planning_work_p50"]["transit_ms"] = overUpdates(&StageTimings::esdf_transit_ms).p50;
    j["planning_work_p50"]["transit_blocks"] = overUpdates(&StageTimings::esdf_transit_blocks).p50;
    j["planning_work_p50"]["tsdf_blocks"] = overUpdates(&StageTimings::esdf_tsdf_blocks).p50;
    j["planning_work_p50"]["cells_flipped"] = overUpdates(&StageTimings::esdf_flipped).p50;
    j["planning_work_p50"]["cells_raised"] = overUpdates(&StageTimings::esdf_raised).p50;
    j["planning_work_p50"]["cells_lowered"] = overUpdates(&StageTimings::esdf_lowered).p50;
    j["planning_work_p50"]["free_space_nodes"] =
        stage(&StageTimings::free_space_nodes, false)["p50"];
  }
  j["timings_ms"]["total"] = stage(&StageTimings::total_ms, false);
  size_t mesh_calls = 0;
  for (const StageTimings& t : report.timings) mesh_calls += t.meshed;
  j["timings_ms"]["mesh_calls"] = mesh_calls;
  auto work_column = [&](double StageWork::*field) {
    std::vector<double> v;
    for (const StageWork& w : report.work) v.push_back(w.*field);
    return v;
  };
  auto work = [&](double StageWork::*field) { return summarize(work_column(field)).p50; };
  j["work_per_frame_p50"]["valid_points"] = work(&StageWork::valid_points);
  j["work_per_frame_p50"]["octree_searches"] = work(&StageWork::octree_searches);
  // The lookup's work, which max_lookup_blocks_per_frame bounds.
  j["work_per_frame_p50"]["lookup_box_blocks"] = work(&StageWork::lookup_box_blocks);
  const std::vector<double> box_blocks = work_column(&StageWork::lookup_box_blocks);
  j["work_per_frame_max"]["lookup_box_blocks"] =
      box_blocks.empty() ? 0.0 : *std::max_element(box_blocks.begin(), box_blocks.end());
  j["work_per_frame_p50"]["blocks_queued"] = work(&StageWork::blocks_queued);
  j["work_per_frame_p50"]["blocks_updated"] = work(&StageWork::blocks_updated);
  j["work_per_frame_p50"]["voxels_updated"] = work(&StageWork::voxels_updated);
  j["work_per_frame_p50"]["blocks_carved"] = work(&StageWork::blocks_carved);
  j["work_per_frame_p50"]["voxels_carved"] = work(&StageWork::voxels_carved);
  j["work_per_frame_p50"]["blocks_meshed"] = work(&StageWork::blocks_meshed);
  j["work_per_frame_p50"]["submeshes_changed"] = work(&StageWork::submeshes_changed);
  // Blocks not yet in the map that the frame's bands reached: created (updated) or not allocated.
  j["work_per_frame_p50"]["blocks_created"] = work(&StageWork::blocks_created);
  j["work_per_frame_p50"]["blocks_not_created"] = work(&StageWork::blocks_not_created);
  if (report.correction.applied) {
    const TrajectoryReport& c = report.correction;
    j["trajectory"]["poses"] = c.trajectory_poses;
    j["trajectory"]["matched_poses"] = c.matched_poses;
    j["trajectory"]["frames_refused"] = c.frames_refused;
    j["trajectory"]["frames_rejected"] = c.frames_rejected;
    j["trajectory"]["max_shift_m"] = c.max_shift_m;
    j["trajectory"]["max_rotation_deg"] = c.max_rotation_deg;
    j["trajectory"]["ms"] = c.ms;
  }
  if (report.planning.enabled) {
    const FuseReport::Planning& p = report.planning;
    j["planning"]["cell_m"] = p.cell_m;
    j["planning"]["max_distance_m"] = p.max_distance_m;
    j["planning"]["blocks"] = p.blocks;
    j["planning"]["cells_free"] = p.cells_free;
    j["planning"]["cells_occupied"] = p.cells_occupied;
    if (p.rebuild_ms > 0.0) {  // --time-planning
      j["planning"]["rebuild_ms"] = p.rebuild_ms;
      j["planning"]["query_100k_ms"] = p.query_100k_ms;
    }
    j["planning"]["octomap_cells_skipped"] = p.octomap_cells_skipped;
    j["memory"]["free_space_bytes"] = p.free_space_bytes;
    j["memory"]["free_space_megabytes"] = p.free_space_bytes / 1048576.0;
    j["memory"]["esdf_bytes"] = p.esdf_bytes;
    j["memory"]["esdf_megabytes"] = p.esdf_bytes / 1048576.0;
  }
  j["wall_time_s"] = report.wall_time_s;
  for (const ParameterSpec& p : mapperParameterSpecs())
    j["config"][p.name] = getMapperParameter(config, p.name);
  return j.dump(2);
}

}  // namespace stereo_fusion
