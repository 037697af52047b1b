// A new layer is one class and one registration (Mapper::addLayer()): a toy "hit count" layer,
// written here as a newcomer would, is told of every fused frame, hears every block change once
// (fusion, carving, eviction, clears), is reset, re-derived after a load and adds nothing to the
// map file — without a line of the Mapper, the pipeline or the other layers knowing it.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <map>
#include <set>
#include <unistd.h>

#include "MeshTestSupport.h"

using namespace stereo_fusion;
using namespace stereo_fusion::test;

namespace {

/// How many updates each block of the map received since it was last erased; the layer's
/// whole code.
class HitCountLayer final : public MapLayer {
 public:
  const char* name() const override { return "hit count"; }
  void onFrame(const LayerFrame& frame) override {
    ++frames_seen;
    last_frame_index = frame.frames_integrated;
    measured_pixels_seen = frame.measurements.width() * frame.measurements.height();
  }
  void update(const BlockOctree&, const BlockChangeLog::Changes& changes) override {
    for (const BlockKey& key : changes.updated) ++hits[key];
    for (const BlockKey& key : changes.erased) hits.erase(key);
    ++updates;
  }
  void rebuild(const BlockOctree& map) override {
    hits.clear();
    for (const VoxelBlock* block : map.blocks()) hits[block->key] = 1;
    ++rebuilds;
  }
  void clearRegion(const MapRegion&) override { ++clears; }
  void reset() override {
    hits.clear();
    ++resets;
  }

  std::map<BlockKey, int> hits;
  int frames_seen = 0, updates = 0, rebuilds = 0, clears = 0, resets = 0;
  uint64_t last_frame_index = 0;
  int measured_pixels_seen = 0;
};

StereoFrame noisyFrame(int i) {
  StereoFrame f = renderFrame(floorAndSphere(), qvgaCamera(), floorAndSphereView(i), 0.2, i);
  f.timestamp_s = 1.0 + i;
  return f;
}

std::set<BlockKey> keysOf(const std::map<BlockKey, int>& hits) {
  std::set<BlockKey> keys;
  for (const auto& [key, n] : hits) keys.insert(key);
  return keys;
}

std::set<BlockKey> keysOf(const BlockOctree& map) {
  std::set<BlockKey> keys;
  for (const VoxelBlock* block : map.blocks()) keys.insert(block->key);
  return keys;
}

}  // namespace

TEST(MapLayer, AToyHitCountLayerHearsEveryFrameAndEveryBlockChangeOnce) {
  Mapper mapper(MapperConfig{});
  HitCountLayer& layer = mapper.addLayer(std::make_unique<HitCountLayer>());
  std::map<BlockKey, int> expected;  // from the frames' own reports
  for (int i = 0; i < 4; ++i) {
    const IntegrationResult r = mapper.integrate(noisyFrame(i));
    ASSERT_TRUE(r.accepted) << r.error;
    for (const BlockKey& key : r.updated_blocks) ++expected[key];
    mapper.updateLayer(layer);
  }
  EXPECT_EQ(layer.frames_seen, 4);
  EXPECT_EQ(layer.last_frame_index, 4u);
  EXPECT_EQ(layer.measured_pixels_seen, 320 * 240);
  EXPECT_EQ(layer.updates, 4);
  EXPECT_EQ(layer.rebuilds, 0) << "registered on an empty map";
  ASSERT_GT(expected.size(), 20u);
  EXPECT_EQ(layer.hits, expected);
  EXPECT_EQ(keysOf(layer.hits), keysOf(mapper.tsdf()));
  EXPECT_GT(std::max_element(expected.begin(), expected.end(),
                             [](const auto& a, const auto& b) { return a.second < b.second; })
                ->second,
            1)
      << "some block is seen by several frames";

  // A rejected frame (the same stamp again) is not the layer's business.
  const IntegrationResult repeated = mapper.integrate(noisyFrame(3));
  ASSERT_FALSE(repeated.accepted);
  EXPECT_EQ(layer.frames_seen, 4);

  // Changes wait in the log until the layer's caller updates it, each block once per frame.
  ASSERT_TRUE(mapper.integrate(noisyFrame(4)).accepted);
  ASSERT_TRUE(mapper.integrate(noisyFrame(5)).accepted);
  mapper.updateLayer(layer);
  EXPECT_EQ(layer.updates, 5);
  EXPECT_EQ(keysOf(layer.hits), keysOf(mapper.tsdf()));

  // A clear tells the layer first; the blocks it empties reach it as erased.
  const ClearResult cleared = mapper.clearRegion(MapRegion::sphere({0.05, 0.1, 1.2}, 0.35));
  ASSERT_TRUE(cleared.accepted);
  ASSERT_GT(cleared.blocks_erased, 0u);
  EXPECT_EQ(layer.clears, 1);
  mapper.updateLayer(layer);
  EXPECT_EQ(keysOf(layer.hits), keysOf(mapper.tsdf()));

  mapper.reset();
  EXPECT_EQ(layer.resets, 1);
  EXPECT_TRUE(layer.hits.empty());
  mapper.updateLayer(layer);
  EXPECT_TRUE(layer.hits.empty()) << "a reset leaves no change pending";
}

TEST(MapLayer, ALayerAddedLaterIsRederivedFromTheMapAndAfterALoad) {
  const std::unique_ptr<Mapper> mapper = fusedMapper(3);
  HitCountLayer& layer = mapper->addLayer(std::make_unique<HitCountLayer>());
  EXPECT_EQ(layer.rebuilds, 1);
  EXPECT_EQ(keysOf(layer.hits), keysOf(mapper->tsdf())) << "the map so far";

  // A layer that saves nothing leaves the map file as it was.
  const std::unique_ptr<Mapper> plain = fusedMapper(3);
  EXPECT_EQ(mapper->encodeMap(), plain->encodeMap());

  // Loading rebuilds it (the default adopt()) from the loaded map.
  const std::string path =
      ::testing::TempDir() + "/hit_count_layer_" + std::to_string(::getpid()) + ".sfmap";
  std::string error;
  const std::unique_ptr<Mapper> larger = fusedMapper(5);
  ASSERT_TRUE(larger->saveMap(path, &error)) << error;
  ASSERT_TRUE(mapper->loadMap(path, nullptr, &error)) << error;
  std::remove(path.c_str());
  EXPECT_EQ(layer.rebuilds, 2);
  EXPECT_EQ(keysOf(layer.hits), keysOf(larger->tsdf()));
  mapper->updateLayer(layer);
  EXPECT_EQ(keysOf(layer.hits), keysOf(mapper->tsdf())) << "a load leaves no change pending";
}

TEST(MapLayer, UpdatingALayerThatIsNotRegisteredIsRefused) {
  Mapper mapper(MapperConfig{});
  HitCountLayer stranger;
  EXPECT_THROW(mapper.updateLayer(stranger), std::logic_error);
}
