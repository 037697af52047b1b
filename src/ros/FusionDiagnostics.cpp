#include "stereo_fusion/ros/FusionDiagnostics.h"

#include <algorithm>
#include <chrono>

#include "stereo_fusion/util/Percentile.h"

namespace stereo_fusion {

MeasurementNames MeasurementNames::of(InputMode input) {
  if (input == InputMode::kDepth) return {"depth image", "depth images"};
  return {"disparity", "disparities"};
}

FusionDiagnostics::FusionDiagnostics(ros::NodeHandle& nh, ros::NodeHandle& pnh,
                                     const NodeConfig& node, MappingSession* session,
                                     const FrameInput* frames, const TrajectoryInput* trajectories,
                                     const NodeStats* stats)
    : node_(node),
      session_(session),
      frames_(frames),
      trajectories_(trajectories),
      stats_(stats),
      names_(MeasurementNames::of(node.input)),
      input_health_(InputHealthConfig{node.diagnostics_window_s, node.input_timeout_s, names_.one,
                                      names_.several}) {
  started_ = ros::WallTime::now();
  input_health_.sample(monotonicNowS(), inputTotals(unmatchedDisparities()));  // first baseline
  updater_ = std::make_unique<diagnostic_updater::Updater>(nh, pnh);
  updater_->setHardwareID("stereo_fusion");
  updater_->add("fusion", this, &FusionDiagnostics::diagnose);
  timer_ = nh.createWallTimer(ros::WallDuration(1.0),
                              [this](const ros::WallTimerEvent&) { updater_->force_update(); });
}

double FusionDiagnostics::monotonicNowS() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

uint64_t FusionDiagnostics::unmatchedDisparities() const {
  const uint64_t disparities_in = frames_->disparitiesIn(), matched = frames_->framesMatched();
  const uint64_t refused = frames_->disparitiesRefused();
  return disparities_in > matched + refused ? disparities_in - matched - refused : 0;
}

InputTotals FusionDiagnostics::inputTotals(uint64_t unmatched) const {
  // A disparity whose image has not arrived yet is unmatched for a moment in normal operation:
  // only those beyond what the synchroniser's queue holds are surely lost.
  const uint64_t queue = static_cast<uint64_t>(node_.sync_queue_size);
  const uint64_t lost_in_sync = unmatched > queue ? unmatched - queue : 0;
  return {frames_->disparitiesIn(), frames_->framesMatched(),
          session_->drops().total() + lost_in_sync};
}

void FusionDiagnostics::diagnose(diagnostic_updater::DiagnosticStatusWrapper& status) {
  const double elapsed = std::max(1e-3, (ros::WallTime::now() - started_).toSec());
  const uint64_t unmatched = unmatchedDisparities();
  const InputTotals input = inputTotals(unmatched);
  input_health_.sample(monotonicNowS(), input);
  const InputWindowReport window = input_health_.report();
  const RejectCounters& drops = session_->drops();
  const uint64_t disparities_in = input.disparities, matched = input.frames;
  const uint64_t fused = session_->framesFused();
  // The watchdog: a single operation (a frame, a meshing pass) holding the map this long stalls
  // everything behind it.
  const double busy_s = session_->busySeconds();
  const std::string stage = mapperStageName(session_->stage());
  if (busy_s > kStalledAfterS)
    status.summary(diagnostic_msgs::DiagnosticStatus::ERROR,
                   "the map has been in " + stage + " for " + std::to_string(busy_s) + " s");
  else if (window.stale)
    status.summary(diagnostic_msgs::DiagnosticStatus::ERROR, input_health_.staleMessage());
  else if (matched > 0 && fused == 0)
    status.summary(diagnostic_msgs::DiagnosticStatus::ERROR,
                   "no frame fused yet; see the drop counters");
  else if (window.dropped > 0)  // only recent drops: one early drop does not mark the whole run
    status.summary(diagnostic_msgs::DiagnosticStatus::WARN,
                   std::to_string(window.dropped) + " dropped in the last " +
                       std::to_string(static_cast<int>(window.span_s + 0.5)) +
                       " s; see the counters");
  else if (stats_->grid_windowed.load())
    status.summary(diagnostic_msgs::DiagnosticStatus::WARN,
                   "the occupancy grid is a window around the camera (grid_max_cells)");
  else if (matched == 0)
    status.summary(diagnostic_msgs::DiagnosticStatus::OK, "waiting for the first frame");
  else
    status.summary(diagnostic_msgs::DiagnosticStatus::OK, "fusing");
  // The keys name the measurement the input takes: disparities, or depth images (input: depth).
  // received = frames fused + every "dropped:" counter + frames in the queue / worker.
  status.add(names_.several + " received", disparities_in);
  // Lost before they reached the node (transport queues, the driver): not part of the sum above.
  status.add(names_.several + " missed upstream (header.seq gaps)", frames_->disparitiesMissed());
  status.add("frames received", matched);
  status.add("dropped: not synchronised (no matching image / camera_info yet)", unmatched);
  status.add("frames fused", fused);
  status.add("map busy: stage", stage);
  status.add("map busy: for (s)", busy_s);
  // The input now: over the window (diagnostics_window_s) and since the last frame.
  status.add("window (s)", window.span_s);
  status.add("input rate, window (Hz)", window.frames_per_s);
  status.add(names_.one + " rate, window (Hz)", window.disparities_per_s);
  status.add("frames dropped in the window", window.dropped);
  if (window.first_frame_seen)
    status.add("since the last frame (s)", window.since_last_frame_s);
  else
    status.add("since the last frame (s)", "no frame yet");
  status.add("input rate since start (Hz)", matched / elapsed);
  status.add("frames dropped since start", input.dropped);
  drops.forEach([&](const RejectReasonInfo& info, uint64_t n) { status.add(info.label, n); });
  status.add("ignored: image / camera_info repeating a stamp", frames_->ignoredDuplicateParts());
  const FusedFrameTotals& totals = session_->fusedTotals();
  status.add("pixels rejected: speckles", totals.speckle_pixels.load());
  status.add("pixels rejected: near side of depth edges", totals.edge_pixels.load());
  status.add("pixels rejected: behind a confident surface", totals.contradicting_pixels.load());
  status.add("disparity noise measured (px, median of the last frames)",
             stats_->disparity_noise_measured_px.load());
  status.add("re-anchored (relocalisation or clock reset)", totals.reanchored.load());
  status.add("regions cleared (~clear_box, ~clear_sphere)", session_->regionsCleared());
  // Frames from before a clear whose fusion refilled the region, which was then cleared again.
  status.add("frames fused from before a clear (region cleared again)",
             session_->framesRecleared());
  status.add("clears refused (too many waiting for older frames)", session_->clearsRefused());
  // Read under the map lock, but never waiting long for it: the report must come even while a
  // frame stalls (then the last values it read stand).
  if (const std::optional<MappingSession::MapStatus> now = session_->tryStatus(0.2))
    map_status_ = *now;
  const PagingStats& paging = map_status_.paging;
  if (paging.stopped || paging.pages_unreadable > 0)  // a full disk, a corrupted store
    status.summary(diagnostic_msgs::DiagnosticStatus::ERROR, "paging: " + paging.error);
  if (!map_status_.checkpoint.error.empty())  // a full disk: the store keeps the checkpoint before
    status.summary(diagnostic_msgs::DiagnosticStatus::ERROR,
                   "map store: " + map_status_.checkpoint.error);
  const MappingSession::KeptStatus& kept = map_status_.kept;
  status.add("clears waiting for frames from before them", kept.pending_clears);
  status.add("loop closure: frames kept", kept.frames);
  status.add("loop closure: kept frames (MB)", kept.bytes / 1048576.0);
  // Older frames are fused into the base and no longer moved by a correction.
  status.add("loop closure: frames beyond the window (frozen)", kept.frozen);
  status.add("loop closure: clears kept", kept.clears);
  const CorrectionReport& last = map_status_.last_correction;
  status.add("loop closure: last correction, frames fused again", last.frames_refused);
  status.add("loop closure: last correction (ms)", last.ms);
  status.add("loop closure: last correction, largest move (m)", last.max_shift_m);
  status.add("loop closure: last correction, largest turn (deg)", last.max_rotation_deg);
  status.add("trajectories received", trajectories_->received());
  status.add("trajectories rejected", session_->trajectories().rejected());
  session_->trajectories().forEach(
      [&](const TrajectoryOutcomeInfo& info, uint64_t n) { status.add(info.label, n); });
  const NodeStats::View v = stats_->view();
  status.add("latency p50 (s)", percentile(v.latency_s, 0.5));
  status.add("latency p99 (s)", percentile(v.latency_s, 0.99));
  const char* names[5] = {"lookup", "fusion", "meshing", "texture", "total"};
  for (int k = 0; k < 5; ++k) {
    status.add(std::string(names[k]) + " p50 (ms)", percentile(v.stage_ms[k], 0.5));
    status.add(std::string(names[k]) + " p99 (ms)", percentile(v.stage_ms[k], 0.99));
  }
  status.add("timings", "lookup, fusion, total: per frame; meshing, texture: per meshing pass");
  // The whole frame on the worker (fusion, publishing, meshing when due): above the frame period
  // frames wait in the queue, and a full queue drops them.
  status.add("worker per frame p50 (ms)", percentile(v.worker_ms, 0.5));
  status.add("worker per frame p99 (ms)", percentile(v.worker_ms, 0.99));
  status.add("publishing per frame p50 (ms)", percentile(v.publish_ms, 0.5));
  status.add("publishing per frame p99 (ms)", percentile(v.publish_ms, 0.99));
  status.add("meshing passes", v.mesh_passes);
  status.add("block changes awaiting meshing", map_status_.awaiting_mesh);
  status.add("blocks", map_status_.blocks);
  status.add("blocks evicted", session_->blocksEvicted());
  status.add("memory (MB)", map_status_.memory_bytes / 1048576.0);
  status.add("map memory, all layers (MB)", map_status_.map_memory_bytes / 1048576.0);
  status.add("paging: map memory at its highest, after a frame (MB)",
             paging.map_memory_peak_bytes / 1048576.0);
  status.add("paging: blocks in the store", map_status_.paged_out_blocks);
  status.add("paging: blocks paged out", paging.blocks_paged_out);
  status.add("paging: of them unchanged, not written again", paging.pages_kept);
  status.add("paging: blocks paged in", paging.blocks_paged_in);
  status.add("paging: longest page-in (ms)", paging.page_in_max_ms);
  status.add("paging: pages unreadable (blocks lost)", paging.pages_unreadable);
  status.add("paging: stopped (store full or unwritable)", paging.stopped ? "yes" : "no");
  const CheckpointStats& checkpoint = map_status_.checkpoint;
  if (!checkpoint.file.empty()) {
    status.add("map store", checkpoint.file);
    status.add("map store: checkpoints", checkpoint.checkpoints);
    status.add("map store: frames at the last checkpoint", checkpoint.last_frames_integrated);
    status.add("map store: longest checkpoint (ms)", checkpoint.max_ms);
  }
  // The planning layer: updated at planning_publish_rate_hz (timings of the updates that had work).
  status.add("planning updates", v.planning_updates);
  status.add("planning update p50 (ms)", percentile(v.planning_ms, 0.5));
  status.add("planning update p99 (ms)", percentile(v.planning_ms, 0.99));
  status.add("planning memory: free space (MB)", map_status_.planning_free_space_bytes / 1048576.0);
  status.add("planning memory: ESDF (MB)", map_status_.planning_esdf_bytes / 1048576.0);
  status.add("occupancy grid width (cells)", stats_->grid_width.load());
  status.add("occupancy grid height (cells)", stats_->grid_height.load());
  status.add("occupancy grid windowed", stats_->grid_windowed.load() ? "yes" : "no");
}

}  // namespace stereo_fusion
