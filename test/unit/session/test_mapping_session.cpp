// MappingSession without a master: frames from before a clear, epochs (reset, load), every
// trajectory accounted for, a correction's swap and its catch-up in the live order.
#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <thread>

#include "SessionTestSupport.h"
#include "stereo_fusion/session/MappingSession.h"

using namespace stereo_fusion;
using namespace stereo_fusion::test;

namespace {

const MapRegion kBall = MapRegion::sphere({0.05, 0.1, 1.2}, 0.3);

SessionConfig keepAll(bool background) {
  SessionConfig s;
  s.loop_closure_max_frames = 100;
  s.background_corrections = background;
  return s;
}

bool waitFor(const std::function<bool()>& done, double seconds) {
  const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  while (!done()) {
    if (std::chrono::steady_clock::now() > until) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return true;
}

MapSnapshot mapOf(MappingSession& session) {
  return session.read([](const Mapper& m) { return snapshot(m.tsdf()); });
}

}  // namespace

TEST(MappingSession, AFrameThatArrivedBeforeAClearDoesNotRefillIt) {
  MappingSession session(sessionTestConfig(), keepAll(false));
  ASSERT_EQ(session.fuse(driftingFrame(0), session.arrive(), MeshTiming::kNow).reason,
            RejectReason::kNone);
  const FrameTicket waited = session.arrive();  // frame 1 arrives, waits for tf...
  const MappingSession::ClearOutcome cleared = session.clear(kBall, 0.5);  // stamped before frame 1
  ASSERT_TRUE(cleared.success) << cleared.message;
  EXPECT_GT(cleared.result.voxels_cleared, 0u);
  const MappingSession::FrameOutcome late =
      session.fuse(driftingFrame(1), waited, MeshTiming::kNow);
  EXPECT_EQ(late.reason, RejectReason::kNone);
  EXPECT_TRUE(late.recleared)
      << "it arrived before the clear: the region is cleared again after it";
  EXPECT_EQ(session.framesRecleared(), 1u);
  // A frame that arrives after the clear, stamped after it, refills the region.
  const MappingSession::FrameOutcome newer =
      session.fuse(driftingFrame(2), session.arrive(), MeshTiming::kNow);
  EXPECT_FALSE(newer.recleared);
  EXPECT_EQ(session.kept().pending_clears, 0u) << "the clear is settled";
  // An invalid region is refused and changes nothing.
  const MapSnapshot before = mapOf(session);
  const MappingSession::ClearOutcome invalid =
      session.clear(MapRegion::sphere({0, 0, 0}, -1.0), 9.0);
  EXPECT_FALSE(invalid.success);
  EXPECT_NE(invalid.message.find("unchanged"), std::string::npos) << invalid.message;
  EXPECT_TRUE(mapOf(session) == before);
  EXPECT_EQ(session.regionsCleared(), 1u);
}

TEST(MappingSession, FramesFromBeforeAResetOrALoadAreSupersededAndCounted) {
  const MapperConfig config = sessionTestConfig();
  MappingSession session(config, keepAll(false));
  std::vector<MapChange> changes;
  session.setMapReplacedListener([&](const MapReplaced& r) { changes.push_back(r.change); });
  ASSERT_EQ(session.fuse(driftingFrame(0), session.arrive(), MeshTiming::kNow).reason,
            RejectReason::kNone);
  const std::string path =
      (std::filesystem::temp_directory_path() / "session_epoch_test.sfmap").string();
  std::string error;
  ASSERT_TRUE(session.read([&](const Mapper& m) { return m.saveMap(path, &error); })) << error;
  const MapSnapshot saved = mapOf(session);

  const FrameTicket before_reset = session.arrive();
  EXPECT_TRUE(session.isCurrent(before_reset));
  session.reset();
  EXPECT_FALSE(session.isCurrent(before_reset));
  EXPECT_EQ(session.fuse(driftingFrame(1), before_reset, MeshTiming::kNow).reason,
            RejectReason::kSuperseded);
  EXPECT_EQ(session.drops()[RejectReason::kSuperseded], 1u);
  EXPECT_EQ(session.read([](const Mapper& m) { return m.tsdf().blockCount(); }), 0u);
  EXPECT_EQ(session.kept().frames, 0u);

  const FrameTicket before_load = session.arrive();
  const MappingSession::LoadOutcome loaded = session.load(path);
  ASSERT_TRUE(loaded.success) << loaded.message;
  EXPECT_TRUE(mapOf(session) == saved);
  EXPECT_EQ(session.fuse(driftingFrame(2), before_load, MeshTiming::kNow).reason,
            RejectReason::kSuperseded);
  EXPECT_EQ(session.drops()[RejectReason::kSuperseded], 2u);
  // A broken file leaves the map as it was.
  const MappingSession::LoadOutcome missing = session.load(path + ".missing");
  EXPECT_FALSE(missing.success);
  EXPECT_EQ(missing.blocks, 0u) << "LoadMap.srv: blocks loaded";
  EXPECT_NE(missing.message.find("unchanged"), std::string::npos);
  EXPECT_NE(missing.message.find("No such file or directory"), std::string::npos)
      << missing.message;
  EXPECT_TRUE(mapOf(session) == saved);
  EXPECT_EQ(changes, (std::vector<MapChange>{MapChange::kReset, MapChange::kLoaded}));
  std::filesystem::remove(path);
}

TEST(MappingSession, ACorrectionSwapsInTheMapOfTheKeptFramesAtTheirCorrectedPoses) {
  const MapperConfig config = sessionTestConfig();
  MappingSession session(config, keepAll(false));
  std::vector<BlockKey> removed_on_swap;
  int swaps = 0;
  session.setMapReplacedListener([&](const MapReplaced& r) {
    if (r.change != MapChange::kCorrected) return;
    ++swaps;
    removed_on_swap = r.removed;
    EXPECT_FALSE(r.correction.empty());
  });
  std::vector<StereoFrame> frames;
  for (int i = 0; i < kFrames; ++i) {
    frames.push_back(driftingFrame(i));
    ASSERT_EQ(session.fuse(frames.back(), session.arrive(), MeshTiming::kNow).reason,
              RejectReason::kNone);
  }
  const std::optional<CorrectionReport> report = session.submitTrajectory(keyframes());
  ASSERT_TRUE(report);
  EXPECT_EQ(report->outcome, TrajectoryOutcome::kApplied) << report->message;
  EXPECT_EQ(report->frames_refused, static_cast<size_t>(kFrames));
  EXPECT_EQ(report->matched_poses, 4u);
  EXPECT_EQ(swaps, 1);
  std::vector<StampedPose> originals;
  for (const StereoFrame& f : frames) originals.push_back({f.timestamp_s, f.T_world_camera});
  const PoseCorrection correction(originals, keyframes(), frames.back().timestamp_s);
  Mapper reference(config);
  for (StereoFrame f : frames) {
    f.T_world_camera = correction.corrected(f.timestamp_s, f.T_world_camera);
    ASSERT_TRUE(reference.integrate(f).accepted);
  }
  EXPECT_TRUE(mapOf(session) == snapshot(reference.tsdf()));
  session.read([&](const Mapper& m) {
    EXPECT_TRUE(triangleSets(m.mesh()) == triangleSets(reference.mesh()));
  });
  EXPECT_EQ(session.trajectories()[TrajectoryOutcome::kApplied], 1u);
  // The same trajectory again moves nothing: taken without re-fusion, counted as such.
  const std::optional<CorrectionReport> again = session.submitTrajectory(keyframes());
  ASSERT_TRUE(again);
  EXPECT_EQ(again->outcome, TrajectoryOutcome::kApplied)
      << "poses are corrected from the originals";
  // Stamps near no kept frame: rejected, counted.
  const std::optional<CorrectionReport> far =
      session.submitTrajectory({{500.0, Eigen::Isometry3d::Identity()}});
  ASSERT_TRUE(far);
  EXPECT_EQ(far->outcome, TrajectoryOutcome::kRejectedNoMatch);
  EXPECT_EQ(session.trajectories().rejected(), 1u);
}

TEST(MappingSession, EveryTrajectoryIsAccountedForWhenTheyComeFasterThanTheyAreApplied) {
  MappingSession session(sessionTestConfig(), keepAll(true));
  for (int i = 0; i < kFrames; ++i)
    ASSERT_EQ(session.fuse(driftingFrame(i), session.arrive(), MeshTiming::kDeferred).reason,
              RejectReason::kNone);
  // Three back to back: the newest wins; the others are superseded, waiting or while fused
  // again, and counted either way (a replaced waiting trajectory used to vanish uncounted).
  for (int k = 0; k < 3; ++k) EXPECT_FALSE(session.submitTrajectory(keyframes()).has_value());
  const TrajectoryCounters& t = session.trajectories();
  ASSERT_TRUE(waitFor(
      [&] {
        return t[TrajectoryOutcome::kApplied] + t[TrajectoryOutcome::kSuperseded] == 3 &&
               !session.correcting();
      },
      120.0))
      << t[TrajectoryOutcome::kApplied] << " applied, " << t[TrajectoryOutcome::kSuperseded]
      << " superseded";
  EXPECT_GE(t[TrajectoryOutcome::kApplied], 1u);
  // Nothing kept: refused at once.
  MappingSession none(sessionTestConfig(), SessionConfig{});
  const std::optional<CorrectionReport> refused = none.submitTrajectory(keyframes());
  ASSERT_TRUE(refused);
  EXPECT_EQ(refused->outcome, TrajectoryOutcome::kRejectedNothingKept);
}

TEST(MappingSession, AResetDropsAWaitingTrajectoryAndCountsIt) {
  MappingSession session(sessionTestConfig(), keepAll(true));
  for (int i = 0; i < kFrames; ++i)
    ASSERT_EQ(session.fuse(driftingFrame(i), session.arrive(), MeshTiming::kDeferred).reason,
              RejectReason::kNone);
  session.submitTrajectory(keyframes());
  session.reset();
  const TrajectoryCounters& t = session.trajectories();
  ASSERT_TRUE(waitFor(
      [&] {
        return !session.correcting() && t[TrajectoryOutcome::kApplied] +
                                                t[TrajectoryOutcome::kDroppedByReset] +
                                                t[TrajectoryOutcome::kSuperseded] ==
                                            1;
      },
      60.0));
  // Whatever it reached, the map after the reset holds nothing from before it.
  ASSERT_TRUE(waitFor([&] { return !session.correcting(); }, 60.0));
  if (t[TrajectoryOutcome::kApplied] == 0)
    EXPECT_EQ(session.read([](const Mapper& m) { return m.tsdf().blockCount(); }), 0u);
}

TEST(MappingSession, ACatchUpReplaysAClearAndTheFramesAfterItInTheirOrder) {
  // The live order: frames 0–3, then (while a correction re-fuses from its snapshot) a clear
  // and frames 4–7 that refill the region. The catch-up must replay the clear before them.
  const MapperConfig config = sessionTestConfig();
  EditTimeline timeline(config, 100);
  uint64_t ticket = 1;
  std::vector<StereoFrame> frames;
  for (int i = 0; i < kFrames; ++i) frames.push_back(driftingFrame(i));
  for (int i = 0; i < 4; ++i) timeline.append(frameEdit(frames[i], ticket++));
  const EditTimeline::Snapshot snap = timeline.snapshot();
  timeline.pin(snap.end_position);
  timeline.append(clearEdit(kBall, ticket++, 4.5));
  for (int i = 4; i < kFrames; ++i) timeline.append(frameEdit(frames[i], ticket++));

  std::string error;
  std::unique_ptr<Mapper> rebuilt = mapperFromBase(config, snap.base_bytes, &error);
  EditReplay replay(snap.base_pending);
  RefusionProgress progress;
  ASSERT_EQ(
      replayEdits(snap.edits, PoseCorrection(), rebuilt.get(), &replay, {}, &progress, &error),
      RefusionStatus::kDone);
  ASSERT_EQ(replayEdits(timeline.editsFrom(snap.end_position), PoseCorrection(), rebuilt.get(),
                        &replay, {}, &progress, &error),
            RefusionStatus::kDone);
  EXPECT_EQ(progress.frames, static_cast<size_t>(kFrames));
  Mapper live(config);
  for (int i = 0; i < kFrames; ++i) {
    if (i == 4) ASSERT_TRUE(live.clearRegion(kBall, MeshTiming::kDeferred).accepted);
    ASSERT_TRUE(live.integrate(frames[i], MeshTiming::kDeferred).accepted);
  }
  EXPECT_TRUE(snapshot(rebuilt->tsdf()) == snapshot(live.tsdf()));
  Mapper clears_last(config);  // what the catch-up did before: the frames, then the clears
  for (int i = 0; i < kFrames; ++i)
    ASSERT_TRUE(clears_last.integrate(frames[i], MeshTiming::kDeferred).accepted);
  ASSERT_TRUE(clears_last.clearRegion(kBall, MeshTiming::kDeferred).accepted);
  EXPECT_FALSE(snapshot(clears_last.tsdf()) == snapshot(live.tsdf()));
}

TEST(MappingSession, NoClearIsLostToABoundAndTooManyPendingClearsAreRefusedNotDropped) {
  const MapperConfig config = sessionTestConfig();
  MappingSession session(config, keepAll(false));
  std::vector<StereoFrame> frames;
  for (int i = 0; i < 4; ++i) {
    frames.push_back(driftingFrame(i));
    ASSERT_EQ(session.fuse(frames.back(), session.arrive(), MeshTiming::kDeferred).reason,
              RejectReason::kNone);
  }
  // 300 clears (more than the old log's 256) of small balls along the floor, then four frames.
  std::vector<MapRegion> balls;
  for (int k = 0; k < 300; ++k)
    balls.push_back(MapRegion::sphere({-0.6 + 0.004 * k, 0.3, 1.0 + 0.002 * k}, 0.05));
  for (const MapRegion& ball : balls) ASSERT_TRUE(session.clear(ball, 4.5).success);
  for (int i = 4; i < kFrames; ++i) {
    frames.push_back(driftingFrame(i));
    ASSERT_EQ(session.fuse(frames.back(), session.arrive(), MeshTiming::kDeferred).reason,
              RejectReason::kNone);
  }
  EXPECT_EQ(session.kept().clears, 300u);
  const std::optional<CorrectionReport> report = session.submitTrajectory(keyframes());
  ASSERT_TRUE(report && report->outcome == TrajectoryOutcome::kApplied);
  std::vector<StampedPose> originals;
  for (const StereoFrame& f : frames) originals.push_back({f.timestamp_s, f.T_world_camera});
  const PoseCorrection correction(originals, keyframes(), frames.back().timestamp_s);
  Mapper reference(config);
  for (int i = 0; i < kFrames; ++i) {
    if (i == 4)
      for (const MapRegion& ball : balls)
        ASSERT_TRUE(reference.clearRegion(ball, MeshTiming::kDeferred).accepted);
    StereoFrame f = frames[i];
    f.T_world_camera = correction.corrected(f.timestamp_s, f.T_world_camera);
    ASSERT_TRUE(reference.integrate(f, MeshTiming::kDeferred).accepted);
  }
  EXPECT_TRUE(mapOf(session) == snapshot(reference.tsdf()));

  // Clears a later frame may predate wait in the session: past kMaxPendingClears the next one
  // is refused (counted), never silently forgotten.
  MappingSession crowded(config, SessionConfig{});
  ASSERT_EQ(crowded.fuse(driftingFrame(0), crowded.arrive(), MeshTiming::kDeferred).reason,
            RejectReason::kNone);
  crowded.arrive();  // a frame that arrived and never came: every clear stays pending
  for (size_t k = 0; k < MappingSession::kMaxPendingClears; ++k)
    ASSERT_TRUE(crowded.clear(MapRegion::sphere({0, 0, 5.0 + k}, 0.01), 1e9).success);
  const MappingSession::ClearOutcome refused = crowded.clear(kBall, 1e9);
  EXPECT_FALSE(refused.success);
  EXPECT_EQ(crowded.clearsRefused(), 1u);
  EXPECT_NE(refused.message.find("unchanged"), std::string::npos) << refused.message;
}

TEST(MappingSession, OfflineFramesAreReadAgainForACorrectionAndAnUnreadableOneLeavesTheMap) {
  const MapperConfig config = sessionTestConfig();
  SessionConfig offline = keepAll(false);
  offline.loop_closure_max_frames = std::numeric_limits<size_t>::max();
  MappingSession session(config, offline);
  bool fail_reads = false;
  for (int i = 0; i < kFrames; ++i) {
    FrameLoader reload = [i, &fail_reads](StereoFrame* f, std::string* error) {
      if (fail_reads) {
        *error = "frame " + std::to_string(i) + " is gone";
        return false;
      }
      *f = driftingFrame(i);
      return true;
    };
    ASSERT_EQ(
        session.fuse(driftingFrame(i), session.arrive(), MeshTiming::kDeferred, reload).reason,
        RejectReason::kNone);
  }
  EXPECT_EQ(session.kept().frames, static_cast<size_t>(kFrames));
  EXPECT_EQ(session.kept().bytes, 0u) << "offline, only stamps and poses are kept";
  fail_reads = true;
  const MapSnapshot before = mapOf(session);
  const std::optional<CorrectionReport> failed = session.submitTrajectory(keyframes(), 1e9);
  ASSERT_TRUE(failed);
  EXPECT_EQ(failed->outcome, TrajectoryOutcome::kFailed);
  EXPECT_NE(failed->message.find("is gone"), std::string::npos) << failed->message;
  EXPECT_TRUE(mapOf(session) == before);
  fail_reads = false;
  const std::optional<CorrectionReport> applied = session.submitTrajectory(keyframes(), 1e9);
  ASSERT_TRUE(applied);
  EXPECT_EQ(applied->outcome, TrajectoryOutcome::kApplied) << applied->message;
  EXPECT_FALSE(mapOf(session) == before);
}

TEST(MappingSession, ARequestFindingTheMapBusyAnswersBusyInBoundedTimeAndChangesNothing) {
  SessionConfig config = keepAll(false);
  config.max_request_wait_s = 0.2;
  MappingSession session(sessionTestConfig(), config);
  ASSERT_EQ(session.fuse(driftingFrame(0), session.arrive(), MeshTiming::kNow).reason,
            RejectReason::kNone);
  const MapSnapshot before = mapOf(session);
  std::atomic<bool> holding{false}, release{false};
  std::thread holder([&] {
    session.read([&](const Mapper&) {  // a long frame or meshing pass
      holding = true;
      while (!release) std::this_thread::sleep_for(std::chrono::milliseconds(1));
    });
  });
  ASSERT_TRUE(waitFor([&] { return holding.load(); }, 10.0));
  const auto start = std::chrono::steady_clock::now();
  const MappingSession::ClearOutcome clear = session.clear(kBall, 100.0);
  EXPECT_FALSE(clear.success);
  EXPECT_NE(clear.message.find("busy"), std::string::npos) << clear.message;
  EXPECT_FALSE(session.reset());
  EXPECT_FALSE(session.load("/nonexistent.sfmap").success);
  EXPECT_FALSE(session.tryWithMap([](MapAccess&) {}));
  EXPECT_FALSE(session.tryStatus(0.05).has_value());
  const double waited_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_LT(waited_s, 30.0)
      << "four requests of 0.2 s each";  // bounded, however loaded the machine
  EXPECT_GE(waited_s, 0.6);              // each waited its bound, none gave up at once
  release = true;
  holder.join();
  EXPECT_TRUE(mapOf(session) == before);
  EXPECT_EQ(session.regionsCleared(), 0u);
  EXPECT_TRUE(session.clear(kBall, 100.0).success) << "free again";
  EXPECT_TRUE(session.tryStatus(1.0).has_value());
}

// The planning update holds the map lock only while it reads the TSDF: while its topics are
// copied, frames are fused and requests answered (from other threads: `then` must not call the
// session), and a reset waits for its end (the layer it reads must live until then).
TEST(MappingSession, ThePlanningUpdateLetsFramesInAndHoldsOffAReplacement) {
  SessionConfig config = keepAll(false);
  config.max_request_wait_s = 0.05;
  MappingSession session(sessionTestConfig(), config);
  ASSERT_EQ(session.fuse(driftingFrame(0), session.arrive(), MeshTiming::kNow).reason,
            RejectReason::kNone);
  std::atomic<bool> reset_done{false};
  std::thread resetter;
  bool ran = false;
  session.updatePlanning([&](const PlanningMap& layer, const PlanningPass& pass) {
    ran = true;
    EXPECT_GT(pass.stats.tsdf_blocks, 0u);
    std::thread frames([&] {
      EXPECT_TRUE(session.tryWithMap([](MapAccess&) {})) << "the map lock is free";
      EXPECT_EQ(session.fuse(driftingFrame(1), session.arrive(), MeshTiming::kNow).reason,
                RejectReason::kNone);
    });
    frames.join();
    resetter = std::thread([&] {
      EXPECT_TRUE(session.reset());
      reset_done = true;
    });
    // Once the reset holds the map lock it waits for this update; then it must not be done.
    std::thread probe([&] {
      EXPECT_TRUE(waitFor([&] { return !session.tryWithMap([](MapAccess&) {}); }, 60.0));
    });
    probe.join();
    EXPECT_FALSE(reset_done.load()) << "a reset waits for the update's end";
    EXPECT_GT(layer.blockCount(), 0u);
  });
  EXPECT_TRUE(ran);
  if (resetter.joinable()) resetter.join();
  EXPECT_TRUE(reset_done.load());
  session.read([](const Mapper& m) { EXPECT_EQ(m.planning()->blockCount(), 0u); });
  EXPECT_EQ(session.framesFused(), 2u);
}

// The map is lent only for a call: a subscriber of the mesh's changes and every read reach the
// map a correction swapped in, not the one it replaced.
TEST(MappingSession, AfterACorrectionSwapSubscribersAndReadersReachTheLiveMap) {
  MappingSession session(sessionTestConfig(), keepAll(false));
  const MeshSubscription publisher = session.subscribeToMeshChanges("test publisher");
  size_t taken_on_swap = 0;
  session.setMapReplacedListener([&](const MapReplaced& r) {
    if (r.change != MapChange::kCorrected) return;
    // A full update replaces what was pending: the subscriber starts afresh on the new map.
    taken_on_swap = r.map.takeMeshChanges(publisher).updated.size();
    EXPECT_GT(r.map.map().mesh().submeshes().size(), 0u);
  });
  for (int i = 0; i < kFrames - 1; ++i)
    ASSERT_EQ(session.fuse(driftingFrame(i), session.arrive(), MeshTiming::kNow).reason,
              RejectReason::kNone);
  EXPECT_GT(session.withMap([&](MapAccess& m) { return m.pendingMeshChanges(publisher); }), 0u);
  const Mapper* before = session.read([](const Mapper& m) { return &m; });
  const std::optional<CorrectionReport> report = session.submitTrajectory(keyframes());
  ASSERT_TRUE(report);
  ASSERT_EQ(report->outcome, TrajectoryOutcome::kApplied) << report->message;
  EXPECT_NE(session.read([](const Mapper& m) { return &m; }), before) << "a new Mapper";
  EXPECT_EQ(taken_on_swap, 0u) << "subscribed on the new map at the swap, nothing old pending";
  EXPECT_EQ(session.withMap([&](MapAccess& m) { return m.pendingMeshChanges(publisher); }), 0u);

  // A frame after the swap: its changes reach the same subscriber, and they are the live map's.
  ASSERT_EQ(
      session.fuse(driftingFrame(kFrames - 1), session.arrive(), MeshTiming::kDeferred).reason,
      RejectReason::kNone);
  session.withMap([&](MapAccess& m) {
    EXPECT_GT(m.map().blocksAwaitingMesh(), 0u);
    const MeshPass pass = m.updateMesh();
    EXPECT_GT(pass.mesh.blocks_meshed, 0u);
    EXPECT_EQ(m.map().blocksAwaitingMesh(), 0u);
    const BlockChangeLog::Changes changes = m.takeMeshChanges(publisher);
    ASSERT_FALSE(changes.updated.empty());
    for (const BlockKey& key : changes.updated)
      EXPECT_TRUE(m.map().mesh().submeshes().count(key)) << "a submesh of the live map";
    EXPECT_EQ(m.pendingMeshChanges(publisher), 0u);
  });
}
