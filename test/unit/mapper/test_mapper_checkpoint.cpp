// The map store (checkpoint_period_s, resume): a map resumed from its last checkpoint and fed
// the frames after it gives every output byte for byte as the run that was never interrupted;
// a process killed at any instant leaves a store that reopens at one of its checkpoints; a
// store that cannot be read is refused and left as it is.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <thread>

#include "MeshTestSupport.h"
#include "PagingTestSupport.h"
#include "QuickMode.h"

using namespace stereo_fusion;
using namespace stereo_fusion::test;

namespace {

Mapper::StoreOpening open(Mapper* mapper, bool resume) {
  Mapper::StoreOpening opened = mapper->openMapStore(resume);
  EXPECT_TRUE(opened.ok) << opened.message;
  return opened;
}

}  // namespace

TEST(MapperCheckpoint, AResumedMapContinuesAsTheUninterruptedRun) {
  const int runs = quickMode() ? 3 : 6;
  for (int run = 0; run < runs; ++run) {
    Scratch scratch;
    std::mt19937 rng(300 + run);
    const int frames = quickMode() ? 20 : 32;
    HallSession session;
    session.seed = run;
    session.poses = walk(&rng, frames);
    session.mesh_every = std::uniform_int_distribution<int>(1, 3)(rng);
    session.plan_every = std::uniform_int_distribution<int>(1, 5)(rng);
    session.clear_at = std::uniform_int_distribution<int>(2, frames - 2)(rng);
    if (run % 3 == 2) session.reset_at = std::uniform_int_distribution<int>(3, frames / 2)(rng);
    MapperConfig config = hallConfig();
    config.map_store_path = (scratch.path / "store").string();
    config.checkpoint_period_s = 1.0;  // what the owner reads; the test checkpoints itself
    if (run % 2 == 1) config.max_map_memory_mb = 0.8;  // paged: some blocks are on disk only
    const std::string what = "run " + std::to_string(run) + (run % 2 == 1 ? " (paged)" : "") +
                             (session.reset_at >= 0 ? " (reset)" : "");

    // The run never interrupted, without any store.
    MapperConfig plain = hallConfig();
    Mapper uninterrupted(plain);
    for (int f = 0; f < frames; ++f) session.frame(&uninterrupted, f);
    const Outputs expected = outputsOf(&uninterrupted, scratch.path);

    // The same frames, checkpointed at random; the frames after the last checkpoint are lost.
    const int last_checkpoint = std::uniform_int_distribution<int>(frames / 3, frames - 3)(rng);
    {
      Mapper interrupted(config);
      const Mapper::StoreOpening opened = open(&interrupted, /*resume=*/false);
      ASSERT_FALSE(opened.resumed);
      std::string error;
      for (int f = 0; f <= last_checkpoint + 2; ++f) {
        session.frame(&interrupted, f);
        const bool now =
            f == last_checkpoint || (f < last_checkpoint && std::bernoulli_distribution(0.3)(rng));
        if (now) {
          ASSERT_TRUE(interrupted.checkpoint("frame " + std::to_string(f), &error)) << error;
        }
      }
      interrupted.flushCheckpoints();
      EXPECT_EQ(interrupted.checkpointStats().error, "") << what;
      EXPECT_GE(interrupted.checkpointStats().checkpoints, 1u) << what;
    }
    Mapper resumed(config);
    const Mapper::StoreOpening opened = open(&resumed, /*resume=*/true);
    ASSERT_TRUE(opened.resumed) << what << ": " << opened.message;
    EXPECT_EQ(opened.owner_note, "frame " + std::to_string(last_checkpoint)) << what;
    const int reset_before =
        session.reset_at >= 0 && session.reset_at <= last_checkpoint ? session.reset_at + 1 : 0;
    EXPECT_EQ(resumed.framesIntegrated(), static_cast<uint64_t>(last_checkpoint + 1 - reset_before))
        << what;
    for (int f = last_checkpoint + 1; f < frames; ++f) session.frame(&resumed, f);
    expectSameOutputs(outputsOf(&resumed, scratch.path), expected, what);
  }
}

TEST(MapperCheckpoint, ACheckpointWritesOnlyTheBlocksThatChanged) {
  Scratch scratch;
  std::mt19937 rng(11);
  HallSession session;
  session.poses = walk(&rng, 16);
  MapperConfig config = hallConfig();
  config.map_store_path = (scratch.path / "store").string();
  config.checkpoint_period_s = 1.0;
  Mapper mapper(config);
  open(&mapper, false);
  std::string error;
  for (int f = 0; f < 8; ++f) session.frame(&mapper, f);
  ASSERT_TRUE(mapper.checkpoint("", &error)) << error;
  mapper.flushCheckpoints();
  // The first checkpoint writes the whole map (a new map replaces whatever the store held).
  EXPECT_EQ(mapper.checkpointStats().blocks_written, mapper.tsdf().blockCount());
  // Nothing changed: nothing written, and the record still says where the map is.
  ASSERT_TRUE(mapper.checkpoint("", &error)) << error;
  mapper.flushCheckpoints();
  EXPECT_EQ(mapper.checkpointStats().blocks_written, mapper.tsdf().blockCount());
  EXPECT_EQ(mapper.checkpointStats().checkpoints, 2u);
  // One more frame: the blocks it updated and those re-meshed around them, no others.
  const size_t before = mapper.checkpointStats().blocks_written;
  StereoFrame frame = renderFrame(session.scene, qvgaCamera(), session.poses[8], 0.2, 8);
  frame.timestamp_s = 9.0;
  const IntegrationResult r = mapper.integrate(frame);
  ASSERT_TRUE(r.accepted);
  ASSERT_TRUE(mapper.checkpoint("", &error)) << error;
  mapper.flushCheckpoints();
  const size_t written = mapper.checkpointStats().blocks_written - before;
  EXPECT_GE(written, r.updated_blocks.size());
  EXPECT_LT(written, mapper.tsdf().blockCount());
  EXPECT_EQ(mapper.checkpointStats().last_frames_integrated, 9u);
}

TEST(MapperCheckpoint, KilledAtAnyInstantTheStoreReopensAtOneOfItsCheckpoints) {
  const int kills = quickMode() ? 3 : 8;
  const int frames = 24;
  std::mt19937 rng(77);
  HallSession session;
  session.poses = walk(&rng, frames);
  session.mesh_every = 2;
  session.plan_every = 3;
  // The map after each number of frames, as a run that is never killed leaves it.
  std::vector<std::vector<uint8_t>> map_after(frames + 1);
  {
    Mapper reference(hallConfig());
    map_after[0] = reference.encodeMap();
    for (int f = 0; f < frames; ++f) {
      session.frame(&reference, f);
      map_after[f + 1] = reference.encodeMap();
    }
  }
  int reopened_with_map = 0;
  for (int kill = 0; kill < kills; ++kill) {
    Scratch scratch;
    MapperConfig config = hallConfig();
    config.map_store_path = (scratch.path / "store").string();
    config.checkpoint_period_s = 1.0;
    // The child says after every frame how far it is, so the kill lands at a frame of the
    // parent's choosing however busy the machine is, then a random instant after it: within a
    // frame, a checkpoint's encoding or its commit.
    int progress[2];
    ASSERT_EQ(::pipe(progress), 0);
    // The first kill comes once the child has flushed its last checkpoint (its store must hold
    // every frame); the others after a random frame.
    const int kill_after_frame =
        kill == 0 ? frames : std::uniform_int_distribution<int>(0, frames - 1)(rng);
    const int delay_us = std::uniform_int_distribution<int>(0, 60000)(rng);
    const pid_t child = fork();
    ASSERT_GE(child, 0);
    if (child == 0) {
      // Checkpoints after every other frame, until killed (or done).
      ::close(progress[0]);
      Mapper mapper(config);
      if (!mapper.openMapStore(false).ok) _exit(2);
      std::string error;
      for (int f = 0; f < frames; ++f) {
        session.frame(&mapper, f);
        if (f % 2 == 1) mapper.checkpoint("", &error);
        const char done = 1;
        if (::write(progress[1], &done, 1) != 1) _exit(3);
      }
      mapper.flushCheckpoints();
      const char flushed = 1;
      if (::write(progress[1], &flushed, 1) != 1) _exit(3);
      ::pause();  // until killed
      _exit(0);
    }
    ::close(progress[1]);
    char done = 0;
    for (int f = 0; f <= kill_after_frame; ++f)
      if (::read(progress[0], &done, 1) != 1) break;  // the child ended
    std::this_thread::sleep_for(std::chrono::microseconds(delay_us));
    ::kill(child, SIGKILL);
    int status = 0;
    ::waitpid(child, &status, 0);
    ::close(progress[0]);
    Mapper reopened(config);
    const Mapper::StoreOpening opened = reopened.openMapStore(true);
    ASSERT_TRUE(opened.ok) << "kill " << kill << ": " << opened.message;
    // Commits land in order but when the child's writer gets to them: a kill may come before
    // the first one, and loses any still in flight.
    if (!opened.resumed) {
      EXPECT_NE(kill, 0) << "the flushed store holds no map";
      continue;
    }
    ++reopened_with_map;
    if (kill == 0) {
      EXPECT_EQ(reopened.framesIntegrated(), static_cast<uint64_t>(frames));
    }
    const uint64_t n = reopened.framesIntegrated();
    ASSERT_LE(n, static_cast<uint64_t>(frames));
    EXPECT_EQ(n % 2, 0u) << "kill " << kill << ": a checkpoint falls after every other frame";
    reopened.updateMesh();
    EXPECT_TRUE(reopened.encodeMap() == map_after[n])
        << "kill " << kill << ": the store after " << n << " frames is not that run's map";
  }
  EXPECT_GT(reopened_with_map, 0) << "every kill came before the first checkpoint";
}

TEST(MapperCheckpoint, AStoreThatCannotBeReadIsRefusedAndLeftAsItIs) {
  Scratch scratch;
  MapperConfig config = hallConfig();
  config.map_store_path = (scratch.path / "store").string();
  config.resume = true;
  fs::create_directories(config.map_store_path);
  const fs::path file = fs::path(config.map_store_path) / "map.sqlite";
  // Not a database.
  {
    std::ofstream out(file, std::ios::binary);
    out << std::string(8192, 'x');
  }
  const std::string garbage = fileBytes(file);
  {
    Mapper mapper(config);
    const Mapper::StoreOpening opened = mapper.openMapStore(true);
    EXPECT_FALSE(opened.ok);
    EXPECT_NE(opened.message.find(file.string()), std::string::npos) << opened.message;
    EXPECT_FALSE(mapper.hasMapStore());
  }
  EXPECT_EQ(fileBytes(file), garbage);
  fs::remove(file);

  // A store of another voxel grid.
  std::mt19937 rng(5);
  HallSession session;
  session.poses = walk(&rng, 4);
  {
    Mapper mapper(config);
    open(&mapper, false);
    std::string error;
    for (int f = 0; f < 4; ++f) session.frame(&mapper, f);
    ASSERT_TRUE(mapper.checkpoint("", &error)) << error;
  }
  const std::string saved = fileBytes(file);
  MapperConfig other = config;
  other.voxel_size_m = 0.05;
  {
    Mapper mapper(other);
    const Mapper::StoreOpening opened = mapper.openMapStore(true);
    EXPECT_FALSE(opened.ok);
    EXPECT_NE(opened.message.find("voxel_size_m"), std::string::npos) << opened.message;
  }
  EXPECT_EQ(fileBytes(file), saved);

  // Its pages cut short: the store opens, the resume is refused, nothing is changed.
  {
    Mapper mapper(config);
    const Mapper::StoreOpening opened = mapper.openMapStore(true);
    ASSERT_TRUE(opened.resumed) << opened.message;
  }
  const std::string whole = fileBytes(file);
  fs::resize_file(file, whole.size() / 2);
  const std::string cut = fileBytes(file);
  {
    Mapper mapper(config);
    const Mapper::StoreOpening opened = mapper.openMapStore(true);
    EXPECT_FALSE(opened.ok) << opened.message;
    EXPECT_EQ(mapper.tsdf().blockCount(), 0u);
  }
  EXPECT_EQ(fileBytes(file), cut);
}
