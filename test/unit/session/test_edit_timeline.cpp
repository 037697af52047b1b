// EditTimeline, EditReplay and replayEdits(): the kept edits re-fused at corrected poses give
// exactly the map of those edits there; edits that left stay where the base put them; clears
// come back in the order the live map saw them.
#include <gtest/gtest.h>

#include <tuple>

#include "SessionTestSupport.h"
#include "stereo_fusion/io/MapFile.h"

using namespace stereo_fusion;
using namespace stereo_fusion::test;

TEST(EditTimeline, RefusingTheKeptFramesEqualsFusingThemAtTheirCorrectedPoses) {
  const MapperConfig config = sessionTestConfig();
  Mapper live(config);
  EditTimeline timeline(config, 100);
  std::vector<StereoFrame> frames;
  for (int i = 0; i < kFrames; ++i) {
    frames.push_back(driftingFrame(i));
    ASSERT_TRUE(live.integrate(frames.back()).accepted);
    timeline.append(frameEdit(frames.back(), i + 1));
  }
  EXPECT_EQ(timeline.frames(), static_cast<size_t>(kFrames));
  EXPECT_EQ(timeline.framesFrozen(), 0u);
  EXPECT_EQ(timeline.bytes(), kFrames * (320u * 240u * 4u + 320u * 240u * 3u));
  EXPECT_TRUE(timeline.snapshot().base_bytes.empty());
  EXPECT_EQ(timeline.snapshot().edits.size(), static_cast<size_t>(kFrames));

  const PoseCorrection correction(timeline.originalPoses(), keyframes(), frames.back().timestamp_s);
  ASSERT_EQ(correction.corrections().size(), 4u);
  for (int i : {0, 3, 6, 7})  // the keyframes land on their true poses
    EXPECT_TRUE(correction.corrected(frames[i].timestamp_s, frames[i].T_world_camera)
                    .isApprox(floorAndSphereView(i), 1e-9));
  double shift_m = 0, rotation_deg = 0;
  correctionMagnitude(timeline.originalPoses(), correction, &shift_m, &rotation_deg);
  EXPECT_NEAR(rotation_deg, 3.5, 1e-6);  // frame 7: 0.5° per frame
  EXPECT_GT(shift_m, 0.07);

  RefusionProgress progress;
  const std::unique_ptr<Mapper> refused = refuseSnapshot(config, timeline, correction, &progress);
  ASSERT_TRUE(refused);
  EXPECT_EQ(progress.frames, static_cast<size_t>(kFrames));
  EXPECT_EQ(progress.rejected, 0u);
  Mapper reference(config);
  for (StereoFrame f : frames) {
    f.T_world_camera = correction.corrected(f.timestamp_s, f.T_world_camera);
    ASSERT_TRUE(reference.integrate(f).accepted);
  }
  EXPECT_TRUE(snapshot(refused->tsdf()) == snapshot(reference.tsdf()));
  EXPECT_FALSE(snapshot(refused->tsdf()) == snapshot(live.tsdf()))
      << "the correction must move the map";
  EXPECT_TRUE(triangleSets(refused->mesh()) == triangleSets(reference.mesh()));
  expectMeshEqualsRebuild(*refused);
  // The planning layer follows: the same cells, states and distances as the reference's.
  refused->updatePlanning();
  reference.updatePlanning();
  live.updatePlanning();
  auto cells = [](const Mapper& m) {
    std::vector<std::tuple<int, int, int, int, double>> out;
    m.planning()->forEachKnownCell([&](const CellIndex& c, CellState s, double d) {
      out.emplace_back(c.x, c.y, c.z, static_cast<int>(s), d);
    });
    return out;
  };
  const auto refused_cells = cells(*refused);
  EXPECT_FALSE(refused_cells.empty());
  EXPECT_TRUE(refused_cells == cells(reference));
  EXPECT_FALSE(refused_cells == cells(live)) << "the correction must move the planning layer";
}

TEST(EditTimeline, FramesThatLeftStayWhereTheBaseFusedThem) {
  const MapperConfig config = sessionTestConfig();
  EditTimeline timeline(config, 3);
  std::vector<StereoFrame> frames;
  for (int i = 0; i < kFrames; ++i) {
    frames.push_back(driftingFrame(i));
    timeline.append(frameEdit(frames.back(), i + 1));
  }
  ASSERT_EQ(timeline.frames(), 3u);
  EXPECT_EQ(timeline.framesFrozen(), static_cast<uint64_t>(kFrames - 3));
  EXPECT_FALSE(timeline.snapshot().base_bytes.empty());
  const PoseCorrection correction(timeline.originalPoses(), keyframes(), frames.back().timestamp_s);
  EXPECT_EQ(correction.corrections().size(), 2u);  // keyframes 6 and 7 lie among the kept 5, 6, 7
  const std::unique_ptr<Mapper> refused = refuseSnapshot(config, timeline, correction);
  ASSERT_TRUE(refused);
  // The first five frames at their original poses (no correction was known when they left),
  // the last three at their corrected ones.
  Mapper reference(config);
  for (int i = 0; i < kFrames; ++i) {
    StereoFrame f = frames[i];
    if (i >= kFrames - 3) f.T_world_camera = correction.corrected(f.timestamp_s, f.T_world_camera);
    ASSERT_TRUE(reference.integrate(f).accepted);
  }
  EXPECT_TRUE(snapshot(refused->tsdf()) == snapshot(reference.tsdf()));
}

TEST(EditTimeline, ACorrectionKnownWhenAFrameLeavesIsAppliedToIt) {
  const MapperConfig config = sessionTestConfig();
  EditTimeline timeline(config, 2);
  std::vector<StereoFrame> frames;
  for (int i = 0; i < 3; ++i) frames.push_back(driftingFrame(i));
  timeline.append(frameEdit(frames[0], 1));
  timeline.append(frameEdit(frames[1], 2));
  const PoseCorrection correction(
      timeline.originalPoses(), {{1.0, floorAndSphereView(0)}, {2.0, floorAndSphereView(1)}}, 2.0);
  timeline.setCorrection(correction);
  timeline.append(frameEdit(frames[2], 3));  // frame 0 leaves, at its corrected (true) pose
  Mapper reference(config);
  StereoFrame first = frames[0];
  first.T_world_camera = correction.corrected(first.timestamp_s, first.T_world_camera);
  ASSERT_TRUE(reference.integrate(first).accepted);
  std::string error;
  const std::unique_ptr<Mapper> base =
      mapperFromBase(config, timeline.snapshot().base_bytes, &error);
  ASSERT_TRUE(base) << error;
  EXPECT_TRUE(snapshot(base->tsdf()) == snapshot(reference.tsdf()));
}

TEST(EditTimeline, NothingIsKeptWithZeroFramesAndACancelledReplayStopsAtOnce) {
  const MapperConfig config = sessionTestConfig();
  EditTimeline none(config, 0);
  none.append(frameEdit(driftingFrame(0), 1));
  none.append(clearEdit(MapRegion::sphere({0, 0, 1}, 0.2), 2, 5.0));
  EXPECT_EQ(none.frames(), 0u);
  EXPECT_EQ(none.clears(), 0u);
  EXPECT_EQ(none.bytes(), 0u);
  EXPECT_TRUE(none.snapshot().edits.empty());
  Mapper map(config);
  EditReplay replay;
  RefusionProgress progress;
  std::string error;
  EXPECT_EQ(replayEdits(
                {frameEdit(driftingFrame(0), 1)}, PoseCorrection(), &map, &replay,
                [] { return true; }, &progress, &error),
            RefusionStatus::kCancelled);
  EXPECT_EQ(progress.frames, 0u);
  EXPECT_EQ(map.tsdf().blockCount(), 0u);
}

TEST(EditReplay, AFrameFromBeforeAClearIsClearedAgainAndTheClearSettlesOnANewerFrame) {
  const MapperConfig config = sessionTestConfig();
  const MapRegion ball = MapRegion::sphere({0.05, 0.1, 1.2}, 0.3);
  Mapper map(config);
  EditReplay replay;
  ASSERT_TRUE(replay.frame(&map, driftingFrame(0), frameEdit(driftingFrame(0), 1), MeshTiming::kNow)
                  .result.accepted);
  ASSERT_GT(replay.clear(&map, clearEdit(ball, 3, 10.0), MeshTiming::kNow).voxels_cleared, 0u);
  EXPECT_EQ(replay.pending().size(), 1u);
  const MapSnapshot cleared = snapshot(map.tsdf());
  // Ticket 2 arrived before the clear (ticket 3): it saw the ball as it was, and is cleared again.
  const StereoFrame late = driftingFrame(1);  // stamped 2 s, before the clear's 10 s
  EXPECT_TRUE(replay.frame(&map, late, frameEdit(late, 2), MeshTiming::kNow).recleared);
  EXPECT_EQ(replay.pending().size(), 1u);
  // A frame that arrived after the clear but was taken before it (stamp 3 s < 10 s): cleared again
  // too.
  const StereoFrame taken_before = driftingFrame(2);
  EXPECT_TRUE(
      replay.frame(&map, taken_before, frameEdit(taken_before, 4), MeshTiming::kNow).recleared);
  // A frame that arrived after it and was taken after it refills the ball, and settles the clear.
  StereoFrame newer = driftingFrame(3);
  newer.timestamp_s = 11.0;
  const EditReplay::FrameApplied refill =
      replay.frame(&map, newer, frameEdit(newer, 5), MeshTiming::kNow);
  EXPECT_TRUE(refill.result.accepted);
  EXPECT_FALSE(refill.recleared);
  EXPECT_TRUE(replay.pending().empty());
  EXPECT_FALSE(snapshot(map.tsdf()) == cleared);
  // An invalid region is refused by the map and not kept.
  EXPECT_FALSE(
      replay.clear(&map, clearEdit(MapRegion::sphere({0, 0, 0}, -1.0), 6, 12.0), MeshTiming::kNow)
          .accepted);
  EXPECT_TRUE(replay.pending().empty());
}

TEST(EditTimeline, AClearComesBackInTheOrderTheLiveMapSawIt) {
  const MapperConfig config = sessionTestConfig();
  const MapRegion ball = MapRegion::sphere({0.05, 0.1, 1.2}, 0.3);
  EditTimeline timeline(config, 100);
  Mapper live(config);
  EditReplay live_replay;
  std::vector<StereoFrame> frames;
  uint64_t ticket = 1;
  for (int i = 0; i < kFrames; ++i) {
    frames.push_back(driftingFrame(i));  // stamped 1 + i
    const Edit f = frameEdit(frames.back(), ticket++);
    ASSERT_TRUE(live_replay.frame(&live, frames.back(), f, MeshTiming::kDeferred).result.accepted);
    timeline.append(f);
    if (i == 3) {
      const Edit c = clearEdit(ball, ticket++, 4.5);
      ASSERT_TRUE(live_replay.clear(&live, c, MeshTiming::kDeferred).accepted);
      timeline.append(c);
    }
  }
  ASSERT_EQ(timeline.clears(), 1u);
  // Re-fused at the original poses, the replay is the live map, bit for bit.
  EXPECT_TRUE(snapshot(refuseSnapshot(config, timeline, PoseCorrection())->tsdf()) ==
              snapshot(live.tsdf()));
  const PoseCorrection correction(timeline.originalPoses(), keyframes(), frames.back().timestamp_s);
  const std::unique_ptr<Mapper> refused = refuseSnapshot(config, timeline, correction);
  Mapper reference(config);
  for (int i = 0; i < kFrames; ++i) {
    if (i == 4) {
      ASSERT_TRUE(reference.clearRegion(ball).accepted);
    }
    StereoFrame f = frames[i];
    f.T_world_camera = correction.corrected(f.timestamp_s, f.T_world_camera);
    ASSERT_TRUE(reference.integrate(f).accepted);
  }
  EXPECT_TRUE(snapshot(refused->tsdf()) == snapshot(reference.tsdf()));
  Mapper forgetful(
      config);  // without the clear the maps differ: the test sees a replay that drops it
  for (StereoFrame f : frames) {
    f.T_world_camera = correction.corrected(f.timestamp_s, f.T_world_camera);
    ASSERT_TRUE(forgetful.integrate(f).accepted);
  }
  EXPECT_FALSE(snapshot(forgetful.tsdf()) == snapshot(reference.tsdf()));
  // Once every frame before the clear has left, the clear has gone into the base too.
  for (int i = 0; i < 100; ++i) {
    StereoFrame f = driftingFrame(i % kFrames);
    f.timestamp_s = 100.0 + i;
    timeline.append(frameEdit(f, ticket++));
  }
  EXPECT_EQ(timeline.clears(), 0u);
}

TEST(EditTimeline, APinnedEditStaysReadableAfterTheBaseTookIt) {
  const MapperConfig config = sessionTestConfig();
  EditTimeline timeline(config, 2);
  for (int i = 0; i < 2; ++i) timeline.append(frameEdit(driftingFrame(i), i + 1));
  const uint64_t pin = timeline.endPosition();
  timeline.pin(pin);
  for (int i = 2; i < 6; ++i) timeline.append(frameEdit(driftingFrame(i), i + 1));
  EXPECT_EQ(timeline.frames(), 2u);
  // Frames 2..5 were appended after the pin; 2 and 3 went into the base but stay readable.
  std::vector<Edit> newer = timeline.editsFrom(pin);
  ASSERT_EQ(newer.size(), 4u);
  EXPECT_EQ(newer.front().frame.timestamp_s, 3.0);
  EXPECT_FALSE(newer.front().frame.disparity_px.empty());
  timeline.unpin();
  newer = timeline.editsFrom(pin);
  ASSERT_EQ(newer.size(), 2u);  // only the kept ones
  EXPECT_EQ(newer.front().frame.timestamp_s, 5.0);
}

TEST(EditTimeline, ALoadedMapBecomesTheBaseTheNewFramesAreRefusedOver) {
  const MapperConfig config = sessionTestConfig();
  // A map from an earlier session (frames 0–2 at their true poses), loaded; then frames 3–7.
  Mapper earlier(config);
  for (int i = 0; i < 3; ++i) {
    StereoFrame f = renderFrame(floorAndSphere(), qvgaCamera(), floorAndSphereView(i), 0.2, i);
    f.timestamp_s = 0.1 * (i + 1);
    ASSERT_TRUE(earlier.integrate(f).accepted);
  }
  std::vector<uint8_t> bytes = earlier.encodeMap();
  sealMapFile(&bytes);
  EditTimeline timeline(config, 100);
  std::string error;
  ASSERT_TRUE(timeline.clear(bytes, &error)) << error;
  EXPECT_EQ(timeline.frames(), 0u);
  std::vector<StereoFrame> frames;
  for (int i = 3; i < kFrames; ++i) {
    frames.push_back(driftingFrame(i));
    timeline.append(frameEdit(frames.back(), i + 1));
  }
  const PoseCorrection correction(timeline.originalPoses(), keyframes(), frames.back().timestamp_s);
  const std::unique_ptr<Mapper> refused = refuseSnapshot(config, timeline, correction);
  ASSERT_TRUE(refused);
  Mapper reference(config);  // the loaded map, then the new frames at their corrected poses
  BlockOctree loaded(config.blockSizeM());
  MapFileInfo info;
  ASSERT_TRUE(decodeMapFile(bytes.data(), bytes.size(), config, &loaded, &info, &error)) << error;
  reference.adoptMap(&loaded, info);
  for (StereoFrame f : frames) {
    f.T_world_camera = correction.corrected(f.timestamp_s, f.T_world_camera);
    ASSERT_TRUE(reference.integrate(f).accepted);
  }
  EXPECT_TRUE(snapshot(refused->tsdf()) == snapshot(reference.tsdf()));
  // A broken base is reported, and the timeline starts empty.
  bytes.resize(bytes.size() / 2);
  EXPECT_FALSE(timeline.clear(bytes, &error));
  EXPECT_TRUE(timeline.snapshot().base_bytes.empty());
  EXPECT_EQ(mapperFromBase(config, bytes, &error), nullptr);
}
