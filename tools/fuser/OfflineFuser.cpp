#include "fuser/OfflineFuser.h"

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <memory>
#include <random>

#include "fuser/OctomapExport.h"
#include "readers/DatasetReader.h"
#include "stereo_fusion/Mapper.h"
#include "stereo_fusion/io/ObjWriter.h"
#include "stereo_fusion/io/PlanningExport.h"
#include "stereo_fusion/io/PlyWriter.h"
#include "stereo_fusion/ros/BagSequence.h"
#include "stereo_fusion/session/MappingSession.h"
#include "stereo_fusion/session/OutputCadence.h"
#include "stereo_fusion/trajectory/PoseCorrection.h"
#include "stereo_fusion/util/ProcessMemory.h"
#include "stereo_fusion/util/Timer.h"

namespace stereo_fusion {

namespace fs = std::filesystem;

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
bool writePlanningOutputs(const std::string& out_dir, MapAccess& access, bool time_queries,
                          FuseReport::Planning* report, std::string* error) {
  const PlanningMap* planning = access.map().planning();
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
  const MapperConfig& config = access.map().config();
  const OccupancyGrid2D grid = projectOccupancy(*planning, config.grid_min_z_m, config.grid_max_z_m,
                                                access.map().occupancyGridWindow());
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
    access.rebuildPlanning();
    report->rebuild_ms = rebuild.elapsedMs();
  }
  return true;
}

/// The frames of `options.input` (none with only --load-map), or false with a message.
bool openInput(const FuseOptions& options, std::unique_ptr<FrameSource>* reader,
               std::string* error) {
  if (options.input.empty()) return true;  // no frames: only the loaded map is meshed
  if (fs::path(options.input).extension() == ".bag") {
    *reader = BagSequence::open(options.input, options.bag_topics, error);
    return *reader != nullptr;
  }
  auto folder = DatasetReader::open(options.input, error);
  if (folder) *reader = std::make_unique<DatasetReader>(std::move(*folder));
  return folder.has_value();
}

/// Fuses the input's frames through `session`, meshing and updating the planning layer on the
/// cadence, and records each fused frame's stats in `report`. False (with a message) only when
/// fusing threw: out of memory mid-frame.
/// The map store's note of where the fuser was: the next input frame.
std::string inputNote(const FuseOptions& options, size_t next_frame) {
  return "input=" + options.input + "\nnext_frame=" + std::to_string(next_frame);
}

/// The input frame a resumed map continues from (0: from the start, with a warning, when the
/// store was written from another input).
size_t resumedInputFrame(const FuseOptions& options, const std::string& note) {
  const std::string input = "input=" + options.input + "\n";
  const std::string next = "next_frame=";
  const size_t at = note.find(next);
  if (note.rfind(input, 0) != 0 || at == std::string::npos) {
    std::fprintf(stderr,
                 "the resumed map was made from another input: fusing %s from its first frame\n",
                 options.input.c_str());
    return 0;
  }
  return static_cast<size_t>(std::strtoull(note.c_str() + at + next.size(), nullptr, 10));
}

bool fuseFrames(const FuseOptions& options, FrameSource* reader, bool keep_for_trajectory,
                const OutputCadence& cadence, size_t first_frame, MappingSession* session,
                FuseReport* report, std::string* error) {
  const size_t available = reader ? reader->size() : 0;
  const size_t total = options.max_frames ? std::min(options.max_frames, available) : available;
  report->frames_total = total;
  const bool terminal = isatty(STDERR_FILENO);
  const char* line_break = terminal && options.progress ? "\n" : "";
  const bool planning = session->read([](const Mapper& m) { return m.planning() != nullptr; });
  size_t last_decile = 0;
  Timer wall;
  auto skipped = [&](const std::string& message) {
    if (report->skipped_examples.size() < 5) report->skipped_examples.push_back(message);
    std::fprintf(stderr, "%sskipping frame: %s\n", line_break, message.c_str());
  };
  const bool keeps_store = options.config.keepsMapStore();
  // A resumed map counts its frames on from the stored ones: the cadences too.
  const uint64_t cadence_offset =
      first_frame > 0 ? session->read([](const Mapper& m) { return m.framesIntegrated(); }) : 0;
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> frame_log(nullptr, &std::fclose);
  if (!options.frame_log.empty()) {
    frame_log.reset(std::fopen(options.frame_log.c_str(), "a"));
    if (!frame_log) {
      *error = options.frame_log + ": cannot write the frame log";
      return false;
    }
  }
  for (size_t i = first_frame; i < total; ++i) {
    if (keeps_store) session->setCheckpointNote(inputNote(options, i + 1));
    if (options.progress && i > 0)
      showProgress(i, total, wall.elapsedMs() / 1000.0, terminal, &last_decile);
    StereoFrame frame;
    std::string why;
    bool loaded = false;
    try {
      loaded = reader->load(i, &frame, &why);
    } catch (const std::exception& e) {  // e.g. OpenCV on a pathological image
      why = "frame " + std::to_string(i) + ": " + e.what();
    }
    if (!loaded) {
      session->countDrop(RejectReason::kUnreadable);
      skipped(why);
      continue;
    }
    Timer frame_timer;
    // This frame's number, if it is fused.
    const uint64_t n = cadence_offset + session->framesFused() + 1;
    const MeshTiming timing = cadence.meshTiming(n);
    FrameLoader reload;
    if (keep_for_trajectory)
      reload = [reader, i](StereoFrame* again, std::string* why) {
        return reader->load(i, again, why);
      };
    const MappingSession::FrameOutcome out =
        session->fuse(frame, session->arrive(), timing, reload);
    const IntegrationResult& r = out.result;
    if (out.reason == RejectReason::kError) {
      // Out of memory mid-frame: stop cleanly with what we have rather than crash. Set
      // max_blocks to stay within memory.
      const size_t blocks = session->read([](const Mapper& m) { return m.tsdf().blockCount(); });
      *error = "frame " + std::to_string(i) + ": " + out.error + " with " + std::to_string(blocks) +
               " blocks; set max_blocks";
      return false;
    }
    if (out.reason != RejectReason::kNone) {
      skipped("frame " + std::to_string(i) + ": " + out.error);
      continue;
    }
    if (std::isfinite(r.disparity_noise_px))
      report->disparity_noise_px.push_back(r.disparity_noise_px);
    if (r.reanchored) std::fprintf(stderr, "%sframe %zu: %s\n", line_break, i, r.note.c_str());
    FrameStats stats = frameStats(r, timing == MeshTiming::kNow);
    if (planning && cadence.planningAfterFrame(n))
      stats.timings.addPlanningPass(
          session->withMap([](MapAccess& m) { return m.updatePlanning(); }));
    stats.timings.total_ms = frame_timer.elapsedMs();
    report->timings.push_back(stats.timings);
    report->work.push_back(stats.work);
    if (frame_log) {
      const double unix_s =
          std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch())
              .count();
      std::fprintf(frame_log.get(), "%zu %.6f\n", i, unix_s);
      std::fflush(frame_log.get());
    }
  }
  if (options.progress && total > 0)
    showProgress(total, total, wall.elapsedMs() / 1000.0, terminal, &last_decile);
  // The frames since the last meshing pass and planning update, on the last frame's account.
  session->withMap([&](MapAccess& m) {
    StageTimings* last = report->timings.empty() ? nullptr : &report->timings.back();
    if (m.map().blocksAwaitingMesh() > 0) {
      Timer mesh_timer;
      const MeshPass pass = m.updateMesh();
      if (last && !last->meshed) {
        last->addMeshPass(pass);
        last->total_ms += mesh_timer.elapsedMs();
      }
    }
    if (m.map().planning() && last && !last->esdf_updated) {
      last->esdf_ms = m.updatePlanning().esdf_ms;
      last->total_ms += last->esdf_ms;
      last->esdf_updated = true;
    }
  });
  return true;
}

/// Applies the --trajectory file's poses after the last frame: the frames fused again.
bool applyTrajectory(const FuseOptions& options, const std::vector<StampedPose>& trajectory,
                     MappingSession* session, FuseReport* report, std::string* error) {
  if (options.progress)
    std::fprintf(stderr, "applying %s: fusing %zu frames again at their corrected poses\n",
                 options.trajectory.c_str(), report->frames_used);
  // Offline the trajectory comes after every frame: all of them share the drift it removes.
  const std::optional<CorrectionReport> c =
      session->submitTrajectory(trajectory, std::numeric_limits<double>::infinity());
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
    *error = options.trajectory + ": " + (c ? c->message : std::string("not applied")) +
             (c && c->outcome == TrajectoryOutcome::kRejectedNoMatch ? " (poses.txt's / the bag's)"
                                                                     : "");
    return false;
  }
  session->withMap([](MapAccess& m) { m.updatePlanning(); });
  return true;
}

/// The figures of the map at the end: blocks, memory, the dense grid it saves, mesh levels.
void mapFigures(const Mapper& mapper, FuseReport* report) {
  report->blocks = mapper.tsdf().blockCount();
  report->paged_out_blocks = mapper.pagedOutBlocks();
  report->map_memory_bytes = mapper.mapMemoryBytes();
  report->paging = mapper.pagingStats();
  report->checkpoint = mapper.checkpointStats();
  report->blocks_evicted = mapper.blocksEvicted();
  report->memory_bytes = mapper.tsdf().memoryBytes();
  report->bytes_per_block = mapper.tsdf().bytesPerBlock();
  report->memory = mapper.tsdf().memoryUse();
  report->mesh_store_bytes = mapper.mesh().memoryBytes();
  if (!mapper.tsdf().blocks().empty()) {
    BlockKey lo = mapper.tsdf().blocks().front()->key, hi = lo;
    for (const VoxelBlock* b : mapper.tsdf().blocks()) {
      lo = componentMin(lo, b->key);
      hi = componentMax(hi, b->key);
    }
    const double voxels_per_block = static_cast<double>(kFinestSide) * kFinestSide * kFinestSide;
    report->dense_grid_bytes = (hi.x - lo.x + 1.0) * (hi.y - lo.y + 1.0) * (hi.z - lo.z + 1.0) *
                               voxels_per_block * sizeof(Voxel);
  }
  const MeshStates& mesh_states =
      mapper.mesh().states();  // current: the mesh was brought up to date before
  for (const VoxelBlock* b : mapper.tsdf().blocks()) {
    if (b->row >= mesh_states.size()) continue;
    const MeshBlockState& state = mesh_states[*b];
    ++report->blocks_per_level[state.level];
    report->seam_filled_blocks += state.seam_filled;
  }
  report->textured_blocks = mapper.textures().patches().size();
  report->texture_bytes = mapper.textures().memoryBytes();
}

/// map file, mesh.ply (+ mesh.obj), the planning outputs and stats.json.
bool writeOutputs(const FuseOptions& options, MapAccess& access, FuseReport* report,
                  std::string* error) {
  const Mapper& mapper = access.map();
  if (!options.save_map.empty() && !mapper.saveMap(options.save_map, error)) return false;
  {
    // Welded, written and let go: the copy is not kept beside the outputs that follow.
    const TriangleMesh mesh = mapper.extractMesh();
    report->mesh_vertices = mesh.positions.size();
    report->mesh_triangles = mesh.triangles.size();
    report->mesh_output_bytes = mesh.positions.size() * sizeof(mesh.positions[0]) +
                                mesh.normals.size() * sizeof(mesh.normals[0]) +
                                mesh.colors.size() * sizeof(mesh.colors[0]) +
                                mesh.triangles.size() * sizeof(mesh.triangles[0]);
    if (!writePly((fs::path(options.out_dir) / "mesh.ply").string(), mesh, error)) return false;
  }
  mapFigures(mapper, report);
  if (options.config.texture == TextureMode::kPatches) {
    ObjExportInfo info;
    // A paged map's submeshes and patches are read back beside those in memory.
    const Mapper::PagedMeshParts all = mapper.wholeMesh();
    if (!writeTexturedObj((fs::path(options.out_dir) / "mesh.obj").string(), all.submeshes,
                          all.patches, ObjExportOptions{}, &info, error))
      return false;
    report->atlas_count = info.files.size() - 2;  // besides the .obj and the .mtl
  }
  if (!writePlanningOutputs(options.out_dir, access, options.time_planning, &report->planning,
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
}  // namespace

bool runOfflineFusion(const FuseOptions& options, FuseReport* report, std::string* error) {
  *report = FuseReport{};
  std::unique_ptr<FrameSource> reader;
  if (!openInput(options, &reader, error)) return false;
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
  if (!options.load_map.empty()) {
    const MappingSession::LoadOutcome loaded = session.load(options.load_map);
    if (!loaded.success) {
      *error = loaded.message;
      return false;
    }
    report->blocks_loaded = loaded.blocks;
  }
  size_t first_frame = 0;
  if (options.config.keepsMapStore()) {
    if (!options.load_map.empty()) {
      *error = "--load-map and a map store (resume, checkpoint_period_s) exclude each other";
      return false;
    }
    const Mapper::StoreOpening opened = session.openMapStore();
    if (!opened.ok) {
      *error = opened.message;
      return false;
    }
    std::fprintf(stderr, "%s\n", opened.message.c_str());
    if (opened.resumed) {
      first_frame = resumedInputFrame(options, opened.owner_note);
      report->resumed_from_frame = first_frame;
      std::fprintf(stderr, "continuing %s at frame %zu\n", options.input.c_str(), first_frame);
    }
  }
  std::error_code ec;
  fs::create_directories(options.out_dir, ec);
  if (ec || !fs::is_directory(options.out_dir)) {
    *error = options.out_dir + ": cannot create the output directory";
    return false;
  }
  const OutputCadence cadence = OutputCadence::everyFrames(
      options.mesh_every, options.esdf_every, options.config.texture == TextureMode::kPatches);
  Timer wall;
  report->start_rss_bytes = readProcessMemory().resident_mb * 1048576.0;
  if (!fuseFrames(options, reader.get(), !trajectory.empty(), cadence, first_frame, &session,
                  report, error))
    return false;
  if (options.config.keepsMapStore()) {
    // The store holds the whole run: a later --set resume=true continues after its last frame.
    session.setCheckpointNote(
        inputNote(options, std::max(report->frames_total, report->resumed_from_frame)));
    std::string message;
    if (!session.checkpoint(&message)) {
      *error = "the last checkpoint: " + message;
      return false;
    }
    std::fprintf(stderr, "%s\n", message.c_str());
  }
  // What the session counted: the frames fused, the pixels they lost, every frame skipped.
  const FusedFrameTotals& totals = session.fusedTotals();
  report->frames_used = session.framesFused();
  report->frames_reanchored = totals.reanchored;
  report->pixels_rejected.speckle_pixels = totals.speckle_pixels;
  report->pixels_rejected.edge_pixels = totals.edge_pixels;
  report->pixels_contradicting = totals.contradicting_pixels;
  session.drops().forEach([&](const RejectReasonInfo& info, uint64_t n) {
    if (n > 0) report->skipped[info.key] = n;
  });
  // Once, at the end: what the data say against what was configured.
  const std::string warning =
      session.read([](const Mapper& m) { return m.disparityNoiseWarning(); });
  if (!warning.empty()) std::fprintf(stderr, "warning: %s\n", warning.c_str());
  if (!trajectory.empty() && report->frames_used > 0 &&
      !applyTrajectory(options, trajectory, &session, report, error))
    return false;
  report->wall_time_s = wall.elapsedMs() / 1000.0;
  return session.withMap([&](MapAccess& m) { return writeOutputs(options, m, report, error); });
}

}  // namespace stereo_fusion
