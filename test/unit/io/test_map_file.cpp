// Map persistence: the versioned, checksummed map file and Mapper::saveMap / loadMap (the
// offline fuser's --save-map / --load-map: test/unit/tools/test_fuser_map_file.cpp).
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>

#include "MeshTestSupport.h"
#include "stereo_fusion/io/MapFile.h"
#include "stereo_fusion/io/PlyWriter.h"
#include "stereo_fusion/util/Crc32.h"

using namespace stereo_fusion;
using namespace stereo_fusion::test;
namespace fs = std::filesystem;

namespace {

std::string tempPath(const std::string& name) {
  return testing::TempDir() + "stereo_fusion_mapfile_" + std::to_string(::getpid()) + "_" + name;
}

/// A tiny hand-made map of three blocks (fast to decode thousands of times).
std::vector<uint8_t> tinyMapFile(const MapperConfig& config) {
  BlockOctree map(config.blockSizeM());
  const BlockKey keys[] = {{0, 0, 0}, {-3, 2, 7}, {1, 0, 0}};
  int n = 0;
  for (const BlockKey& k : keys) {
    VoxelBlock* b = map.findOrAllocate(k);
    for (int v = 0; v < VoxelBlock::kVoxelCount; ++v) {
      b->writableVoxel(v).sdf_m = 0.001f * (v - 300) + n;
      b->writableVoxel(v).weight = static_cast<float>(v % 5);
      b->writableVoxel(v).r = static_cast<uint8_t>(v);
    }
    ++n;
  }
  return encodeMapFile(map, config, 12, [](const VoxelBlock& b) {
    return uint64_t{10} + static_cast<uint64_t>(b.key.x + 3);
  });
}

/// Re-seals a patched file with correct checksums, so the content checks are what fails.
void reseal(std::vector<uint8_t>* bytes) {
  auto put = [&](size_t at, uint32_t v) {
    for (int i = 0; i < 4; ++i) (*bytes)[at + i] = static_cast<uint8_t>(v >> (8 * i));
  };
  const bool v1 = (*bytes)[8] == 1;
  const size_t header_bytes = v1 ? kMapFileV1HeaderBytes : kMapFileHeaderBytes;
  put(v1 ? 64 : 72, crc32(bytes->data() + header_bytes, bytes->size() - header_bytes));
  put(v1 ? 68 : 76, crc32(bytes->data(), v1 ? 68 : 76));
}

std::string decodeError(const std::vector<uint8_t>& bytes, const MapperConfig& config) {
  BlockOctree out(config.blockSizeM());
  MapFileInfo info;
  std::string error;
  if (decodeMapFile(bytes.data(), bytes.size(), config, &out, &info, &error)) return "";
  return error.empty() ? "(empty message)" : error;
}

/// A record of a block with all three levels stored (tinyMapFile()'s blocks).
constexpr size_t kAllLevelsRecordBytes = kMapFileRecordHeadBytes + VoxelBlock::kVoxelCount * 12;

}  // namespace

TEST(Crc32, StandardCheckValue) {
  const std::string text = "123456789";
  EXPECT_EQ(crc32(reinterpret_cast<const uint8_t*>(text.data()), text.size()), 0xCBF43926u);
  EXPECT_EQ(crc32(nullptr, 0), 0u);
  // Continuing over two buffers equals one pass.
  const uint32_t part = crc32(reinterpret_cast<const uint8_t*>(text.data()), 4);
  EXPECT_EQ(crc32(reinterpret_cast<const uint8_t*>(text.data()) + 4, 5, part), 0xCBF43926u);
}

// The file layout of io/MapFile.h, byte by byte, for one block: holds the encoder (which copies
// whole voxel arrays on little-endian hosts) to the documented little-endian records.
TEST(MapFile, OneBlockEncodesToTheDocumentedBytesHandWorked) {
  const MapperConfig config;
  BlockOctree map(config.blockSizeM());
  VoxelBlock* block = map.findOrAllocate({1, -2, 3});
  ASSERT_NE(block, nullptr);
  // Levels 0 and 2 allocated, level 1 not: the record holds 512 + 8 voxels.
  block->writableVoxel(0) = Voxel{0.5f, 2.0f, 10, 20, 30, 0};   // 0x3f000000, 0x40000000
  block->writableVoxel(583) = Voxel{-0.25f, 1.0f, 1, 2, 3, 0};  // 0xbe800000, 0x3f800000
  const std::vector<uint8_t> file =
      encodeMapFile(map, config, 12, [](const VoxelBlock&) { return 0x0102030405060708ull; });
  const size_t record_bytes = 24 + (512 + 8) * 12;
  ASSERT_EQ(file.size(), kMapFileHeaderBytes + record_bytes + 16);  // + an empty seen-free section
  auto bytes = [&](size_t offset, std::initializer_list<int> want) {
    size_t k = offset;
    for (int b : want) EXPECT_EQ(file[k++], b) << "byte " << k - 1;
  };
  bytes(0, {'S', 'F', 'U', 'S', 'E', 'M', 'A', 'P', 3, 0, 0, 0, 80, 0, 0, 0});
  // No seen-free space: cell edge 0.0 and count 0.
  bytes(kMapFileHeaderBytes + record_bytes, {0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0});
  bytes(48, {12, 0, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 0});  // frames, block count
  const size_t payload_bytes = record_bytes + 16;
  bytes(64,
        {int(payload_bytes & 0xff), int(payload_bytes >> 8), 0, 0, 0, 0, 0, 0});  // payload bytes
  const size_t record = kMapFileHeaderBytes;
  bytes(record, {1, 0, 0, 0, 0xfe, 0xff, 0xff, 0xff, 3, 0, 0, 0});  // key
  bytes(record + 12,
        {8, 7, 6, 5, 4, 3, 2, 1, 5, 0, 0, 0});  // last update frame, levels 0 and 2, 0, 0, 0
  bytes(record + 24, {0, 0, 0, 0x3f, 0, 0, 0, 0x40, 10, 20, 30, 0});  // first voxel of level 0
  bytes(record + 24 + 512 * 12 + 7 * 12,
        {0, 0, 0x80, 0xbe, 0, 0, 0x80, 0x3f, 1, 2, 3, 0});   // last of level 2
  bytes(record + 36, {0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0});  // an untouched voxel
  // Both checksums as documented: payload at 72, header bytes 0..75 at 76.
  const uint32_t payload_crc = crc32(file.data() + record, payload_bytes);
  const uint32_t header_crc = crc32(file.data(), 76);
  bytes(72, {int(payload_crc & 0xff), int(payload_crc >> 8 & 0xff), int(payload_crc >> 16 & 0xff),
             int(payload_crc >> 24)});
  bytes(76, {int(header_crc & 0xff), int(header_crc >> 8 & 0xff), int(header_crc >> 16 & 0xff),
             int(header_crc >> 24)});
}

// A version-1 file (72-byte header, all 584 voxels per block) as the previous release wrote it.
std::vector<uint8_t> versionOneFile(const BlockOctree& map, const MapperConfig& config,
                                    uint64_t frames) {
  const std::vector<VoxelBlock*> blocks = map.blocksSortedByKey();
  std::vector<uint8_t> file(kMapFileV1HeaderBytes + blocks.size() * kMapFileV1RecordBytes, 0);
  auto put = [&](size_t at, const void* value, size_t n) {
    std::memcpy(file.data() + at, value, n);
  };
  const uint32_t version = 1, header_bytes = 72;
  const uint64_t count = blocks.size();
  put(0, "SFUSEMAP", 8);
  put(8, &version, 4);
  put(12, &header_bytes, 4);
  put(16, &config.voxel_size_m, 8);
  put(24, &config.truncation_vox, 8);
  put(32, &config.levels.scale2_min_depth_m, 8);
  put(40, &config.levels.scale4_min_depth_m, 8);
  put(48, &frames, 8);
  put(56, &count, 8);
  size_t at = kMapFileV1HeaderBytes;
  for (const VoxelBlock* b : blocks) {
    put(at, &b->key, 12);
    const uint64_t last_update =
        40 + static_cast<uint64_t>(b->key.z & 7);  // any: v1 stored the frame here
    put(at + 12, &last_update, 8);
    file[at + 20] = 2;  // v1's mesh level: derived data the reader checks (< 3) and ignores
    for (int v = 0; v < VoxelBlock::kVoxelCount; ++v) put(at + 24 + 12 * v, &b->voxel(v), 12);
    at += kMapFileV1RecordBytes;
  }
  reseal(&file);
  return file;
}

TEST(MapFile, VersionOneFilesStillLoadWithOnlyTheirObservedLevels) {
  MapperConfig config;
  const auto original = fusedMapper(3, config);
  // The old lookup allocated every block a band reached, updated or not: a version-1 file holds
  // such blocks, all voxels unobserved. Two of them here, beside the fused blocks.
  BlockOctree with_empty(config.blockSizeM());
  for (const VoxelBlock* b : original->tsdf().blocks()) {
    VoxelBlock* copy = with_empty.findOrAllocate(b->key);
    for (int level = 0; level < kNumLevels; ++level)
      if (b->hasLevel(level)) copy->adoptLevel(level, b->level(level));
  }
  with_empty.findOrAllocate({500, 0, 0});
  with_empty.findOrAllocate({501, 0, 0})->writableLevel(1);  // stored, never observed
  const std::vector<uint8_t> old_file =
      versionOneFile(with_empty, config, original->framesIntegrated());
  BlockOctree loaded(config.blockSizeM());
  MapFileInfo info;
  std::string error;
  ASSERT_TRUE(decodeMapFile(old_file.data(), old_file.size(), config, &loaded, &info, &error))
      << error;
  EXPECT_EQ(info.version, 1u);
  EXPECT_EQ(info.block_count, original->tsdf().blockCount() + 2);
  // The fused blocks and voxels, without the empty ones, and a level is allocated exactly
  // where it holds observations (which is where fusion allocated it).
  EXPECT_TRUE(snapshot(loaded) == snapshot(original->tsdf()));
  EXPECT_EQ(info.last_update_frames.size(), loaded.blockCount());
  size_t blocks_without_level0 = 0;
  for (const VoxelBlock* b : loaded.blocks()) blocks_without_level0 += !b->hasLevel(0);
  EXPECT_GT(blocks_without_level0, 0u);
  // Saved again, it is a current file of the same map.
  BlockOctree again(config.blockSizeM());
  const std::vector<uint8_t> new_file = encodeMapFile(loaded, config, info.frames_integrated);
  ASSERT_TRUE(decodeMapFile(new_file.data(), new_file.size(), config, &again, &info, &error))
      << error;
  EXPECT_EQ(info.version, kMapFileVersion);
  EXPECT_TRUE(snapshot(again) == snapshot(original->tsdf()));
  EXPECT_LT(new_file.size(), old_file.size());
}

TEST(MapFile, SaveLoadGivesTheIdenticalMapAndByteIdenticalMesh) {
  MapperConfig config;
  const auto original = fusedMapper(4, config);
  ASSERT_GT(original->tsdf().blockCount(), 50u);
  const std::string map_path = tempPath("roundtrip.sfmap");
  std::string error;
  ASSERT_TRUE(original->saveMap(map_path, &error)) << error;
  size_t voxel_bytes = 0;
  for (const VoxelBlock* b : original->tsdf().blocks()) voxel_bytes += b->voxelBytes();
  const size_t free_space_bytes =
      16 + original->planning()->seenFree().size() * kMapFileFreeSpaceRecordBytes;
  EXPECT_EQ(fs::file_size(map_path), kMapFileHeaderBytes +
                                         original->tsdf().blockCount() * kMapFileRecordHeadBytes +
                                         voxel_bytes + free_space_bytes);

  Mapper loaded(config);
  MeshChanges changes;
  ASSERT_TRUE(loaded.loadMap(map_path, &changes, &error)) << error;
  EXPECT_TRUE(snapshot(loaded.tsdf()) == snapshot(original->tsdf()));
  EXPECT_EQ(loaded.framesIntegrated(), original->framesIntegrated());
  // The eviction order goes with the map.
  for (const VoxelBlock* b : original->tsdf().blocks())
    EXPECT_EQ(loaded.lastUpdateFrame(*loaded.tsdf().find(b->key)), original->lastUpdateFrame(*b))
        << b->key;
  EXPECT_EQ(changes.changed.size(), loaded.mesh().submeshes().size());
  EXPECT_TRUE(changes.removed.empty());
  // Loading allocates block by block and swaps the octree in: the neighbour links the mesher
  // reads must come out equal to searches, and as many as the original map has.
  const LinkCheck links = checkNeighbourLinks(loaded.tsdf()),
                  original_links = checkNeighbourLinks(original->tsdf());
  EXPECT_EQ(links.mismatched, 0u);
  EXPECT_EQ(links.checked, 27 * loaded.tsdf().blockCount());
  EXPECT_EQ(links.linked, original_links.linked);
  EXPECT_GT(links.linked, 4 * loaded.tsdf().blockCount());

  const std::string ply_a = tempPath("a.ply"), ply_b = tempPath("b.ply");
  ASSERT_TRUE(writePly(ply_a, original->extractMesh(), &error)) << error;
  ASSERT_TRUE(writePly(ply_b, loaded.extractMesh(), &error)) << error;
  const std::vector<uint8_t> a = readBytes(ply_a), b = readBytes(ply_b);
  ASSERT_GT(a.size(), 10000u);
  EXPECT_TRUE(a == b) << "the mesh of the loaded map differs from the original's";
  // Saving the loaded map again gives the same file.
  const std::string again = tempPath("again.sfmap");
  ASSERT_TRUE(loaded.saveMap(again, &error)) << error;
  EXPECT_TRUE(readBytes(again) == readBytes(map_path));
  for (const auto& p : {map_path, ply_a, ply_b, again}) fs::remove(p);
}

// The nodelet's split of save_map and load_map (encode under its lock, write after; read
// first, adopt under its lock) gives the same file and the same map as saveMap / loadMap.
TEST(MapFile, EncodeThenWriteAndReadThenAdoptEqualSaveAndLoad) {
  MapperConfig config;
  const auto original = fusedMapper(3, config);
  const std::string saved = tempPath("saved.sfmap"), written = tempPath("written.sfmap");
  std::string error;
  ASSERT_TRUE(original->saveMap(saved, &error)) << error;
  // encodeMap() leaves the checksums to writeMapFileBytes(), which fills them in place.
  std::vector<uint8_t> bytes = original->encodeMap();
  const SeenFreeSpace free_space{original->planning()->grid().cell_m,
                                 original->planning()->seenFree()};
  const std::vector<uint8_t> sealed = encodeMapFile(
      original->tsdf(), config, original->framesIntegrated(),
      [&](const VoxelBlock& block) { return original->lastUpdateFrame(block); }, free_space);
  ASSERT_EQ(bytes.size(), sealed.size());
  EXPECT_TRUE(std::equal(bytes.begin(), bytes.begin() + 72,
                         sealed.begin()));  // header before the checksums
  EXPECT_TRUE(std::equal(bytes.begin() + kMapFileHeaderBytes, bytes.end(),
                         sealed.begin() + kMapFileHeaderBytes));
  EXPECT_TRUE(
      std::all_of(bytes.begin() + 72, bytes.begin() + 80, [](uint8_t b) { return b == 0; }));
  ASSERT_TRUE(writeMapFileBytes(written, &bytes, &error)) << error;
  EXPECT_TRUE(bytes == sealed);
  EXPECT_TRUE(readBytes(written) == readBytes(saved));
  EXPECT_TRUE(sealed == readBytes(saved));

  Mapper by_load(config), by_adopt(config);
  MeshChanges load_changes;
  ASSERT_TRUE(by_load.loadMap(saved, &load_changes, &error)) << error;
  BlockOctree read(config.blockSizeM());
  MapFileInfo info;
  ASSERT_TRUE(readMapFile(written, by_adopt.config(), &read, &info, &error)) << error;
  const MeshChanges adopt_changes = by_adopt.adoptMap(&read, info);
  EXPECT_EQ(read.blockCount(), 0u)
      << "adoptMap leaves the mapper's old (empty) map in its argument";
  EXPECT_TRUE(snapshot(by_adopt.tsdf()) == snapshot(by_load.tsdf()));
  EXPECT_EQ(by_adopt.framesIntegrated(), by_load.framesIntegrated());
  EXPECT_EQ(adopt_changes.changed.size(), load_changes.changed.size());
  EXPECT_EQ(by_adopt.mesh().submeshes().size(), by_load.mesh().submeshes().size());
  // A failed write names the path and leaves no temporary behind.
  EXPECT_FALSE(writeMapFileBytes("/nonexistent_dir/x.sfmap", &bytes, &error));
  EXPECT_NE(error.find("/nonexistent_dir/x.sfmap"), std::string::npos) << error;
  for (const auto& p : {saved, written}) fs::remove(p);
}

TEST(MapFile, DecodedBlocksAreLinkedToTheirNeighboursHandWorked) {
  // The tiny map: (0,0,0) and (1,0,0) touch by a face, (-3,2,7) touches nothing.
  const MapperConfig config;
  const std::vector<uint8_t> bytes = tinyMapFile(config);
  BlockOctree map(config.blockSizeM());
  MapFileInfo info;
  std::string error;
  ASSERT_TRUE(decodeMapFile(bytes.data(), bytes.size(), config, &map, &info, &error)) << error;
  const VoxelBlock* origin = map.find({0, 0, 0});
  const VoxelBlock* right = map.find({1, 0, 0});
  const VoxelBlock* alone = map.find({-3, 2, 7});
  ASSERT_TRUE(origin && right && alone);
  EXPECT_EQ(map.neighbour(*origin, 1, 0, 0), right);
  EXPECT_EQ(map.neighbour(*right, -1, 0, 0), origin);
  const LinkCheck links = checkNeighbourLinks(map);
  EXPECT_EQ(links.checked, 3u * 27u);
  EXPECT_EQ(links.linked, 3u + 2u);  // each block itself, and the one pair both ways
  EXPECT_EQ(links.mismatched, 0u);
}

TEST(MapFile, FusingOnAfterLoadContinuesTheSameMap) {
  // Fusing frames 0..3 equals fusing 0..1, saving, loading into a new mapper and fusing 2..3.
  MapperConfig config;
  const auto whole = fusedMapper(4, config);
  const auto first = fusedMapper(2, config);
  const std::string path = tempPath("continue.sfmap");
  std::string error;
  ASSERT_TRUE(first->saveMap(path, &error)) << error;
  Mapper resumed(config);
  ASSERT_TRUE(resumed.loadMap(path, nullptr, &error)) << error;
  const sim::AnalyticScene scene = floorAndSphere();
  for (int i = 2; i < 4; ++i) {
    StereoFrame f = renderFrame(scene, qvgaCamera(), floorAndSphereView(i), 0.2, i);
    f.timestamp_s = 1.0 + i;
    ASSERT_TRUE(resumed.integrate(f).accepted);
  }
  EXPECT_TRUE(snapshot(resumed.tsdf()) == snapshot(whole->tsdf()));
  EXPECT_TRUE(triangleSets(resumed.mesh()) == triangleSets(whole->mesh()));
  fs::remove(path);
}

TEST(MapFile, EveryTruncationAndEveryFlippedByteFailsCleanly) {
  const MapperConfig config;
  const std::vector<uint8_t> good = tinyMapFile(config);
  ASSERT_EQ(good.size(), kMapFileHeaderBytes + 3 * kAllLevelsRecordBytes + 16);
  ASSERT_EQ(decodeError(good, config), "");
  for (size_t n = 0; n < good.size(); ++n) {
    const std::vector<uint8_t> cut(good.begin(), good.begin() + n);
    const std::string e = decodeError(cut, config);
    ASSERT_NE(e, "") << "a file truncated to " << n << " bytes was accepted";
    if (n >= kMapFileHeaderBytes) {
      ASSERT_NE(e.find("truncated map file"), std::string::npos) << n << ": " << e;
    }
  }
  for (size_t at = 0; at < good.size(); ++at) {
    std::vector<uint8_t> bad = good;
    bad[at] ^= static_cast<uint8_t>(1u << (at % 8));
    const std::string e = decodeError(bad, config);
    ASSERT_NE(e, "") << "a flipped bit at byte " << at << " was accepted";
    if (at >= kMapFileHeaderBytes) {
      ASSERT_NE(e.find("block data checksum mismatch"), std::string::npos) << at << ": " << e;
    }
  }
  // Appended bytes are corruption too.
  std::vector<uint8_t> longer = good;
  longer.push_back(0);
  EXPECT_NE(decodeError(longer, config).find("corrupted map file"), std::string::npos);
}

TEST(MapFile, VersionParametersAndContentAreChecked) {
  const MapperConfig config;
  const std::vector<uint8_t> good = tinyMapFile(config);
  std::vector<uint8_t> bad = good;
  bad[8] = 4;  // version 4
  EXPECT_EQ(decodeError(bad, config),
            "map file version 4 is not supported (this build reads versions 1 to 3)");
  bad = good;
  bad[0] = 'X';
  EXPECT_EQ(decodeError(bad, config), "not a stereo_fusion map file (bad magic)");
  EXPECT_EQ(decodeError({}, config), "not a stereo_fusion map file (bad magic)");

  MapperConfig other = config;
  other.voxel_size_m = 0.04;
  EXPECT_NE(decodeError(good, other).find("built with voxel_size_m = 0.02"), std::string::npos)
      << decodeError(good, other);
  other = config;
  other.truncation_vox = 3;
  EXPECT_NE(
      decodeError(good, other).find("this mapper uses voxel_size_m = 0.02, truncation_vox = 3"),
      std::string::npos);

  // Well-sealed files with impossible content.
  bad = good;
  const size_t second = kMapFileHeaderBytes + kAllLevelsRecordBytes;
  std::copy(good.begin() + kMapFileHeaderBytes, good.begin() + kMapFileHeaderBytes + 12,
            bad.begin() + second);
  reseal(&bad);
  EXPECT_NE(decodeError(bad, config).find("appears twice"), std::string::npos)
      << decodeError(bad, config);
  bad = good;
  const float nan = NAN;
  std::memcpy(bad.data() + kMapFileHeaderBytes + 24 + 12 * 5, &nan, 4);
  reseal(&bad);
  EXPECT_NE(decodeError(bad, config).find("non-finite distance or a negative weight"),
            std::string::npos);
  bad = good;
  const float negative = -1.0f;
  std::memcpy(bad.data() + kMapFileHeaderBytes + 24 + 12 * 5 + 4, &negative, 4);
  reseal(&bad);
  EXPECT_NE(decodeError(bad, config).find("negative weight"), std::string::npos);
  bad = good;
  bad[kMapFileHeaderBytes + 20] = 8;  // a level that does not exist
  reseal(&bad);
  EXPECT_NE(decodeError(bad, config).find("has head bytes 8, 0, 0, 0 (levels, 0, 0, 0)"),
            std::string::npos)
      << decodeError(bad, config);
  bad = good;
  bad[kMapFileHeaderBytes + 23] = 1;  // the head's padding must be zero
  reseal(&bad);
  EXPECT_NE(decodeError(bad, config).find("has head bytes 7, 0, 0, 1"), std::string::npos)
      << decodeError(bad, config);
  bad = good;
  const uint32_t far = (1u << 28) + 5;  // beyond kMaxKey
  std::memcpy(bad.data() + kMapFileHeaderBytes, &far, 4);
  reseal(&bad);
  EXPECT_NE(decodeError(bad, config).find("beyond the map's range"), std::string::npos);
  bad = good;
  bad[56] = 0xFF;  // block count 255 + ...: more blocks than the payload holds
  reseal(&bad);
  EXPECT_NE(decodeError(bad, config).find("block 3 of 255 runs past the end"), std::string::npos)
      << decodeError(bad, config);
  bad = good;
  for (size_t v = 0; v < 8; ++v)  // the first block's level 2 (its last 8 voxels) unobserved
    std::memset(bad.data() + kMapFileHeaderBytes + kAllLevelsRecordBytes - 12 * (8 - v) + 4, 0, 4);
  reseal(&bad);
  EXPECT_NE(decodeError(bad, config).find("stores level 2 without an observed voxel"),
            std::string::npos)
      << decodeError(bad, config);
  bad = good;
  bad[64] = 0;  // a payload size other than the file's
  reseal(&bad);
  EXPECT_NE(decodeError(bad, config).find("corrupted map file"), std::string::npos)
      << decodeError(bad, config);
  bad = good;
  bad[kMapFileHeaderBytes + 20] =
      3;  // the first block without its level 2: the records no longer add up
  reseal(&bad);
  EXPECT_NE(decodeError(bad, config).find("invalid map file"), std::string::npos)
      << decodeError(bad, config);
}

TEST(MapFile, AFailedLoadLeavesTheMapAndMeshUntouched) {
  MapperConfig config;
  config.voxel_size_m = 0.04;  // fewer blocks: the map is compared after every case
  const auto mapper = fusedMapper(3, config);
  const MapSnapshot before = snapshot(mapper->tsdf());
  const auto mesh_before = triangleSets(mapper->mesh());
  const std::string path = tempPath("bad.sfmap");
  std::string error;
  ASSERT_TRUE(mapper->saveMap(path, &error));
  const std::vector<uint8_t> good = readBytes(path);
  struct Case {
    std::vector<uint8_t> bytes;
    const char* message;
  };
  std::vector<uint8_t> flipped = good;
  flipped[good.size() / 2] ^= 0x10;
  const std::vector<Case> cases = {
      {std::vector<uint8_t>(good.begin(), good.begin() + good.size() / 3), "truncated map file"},
      {std::vector<uint8_t>(good.begin(), good.begin() + 40), "truncated map file"},
      {flipped, "checksum mismatch"},
  };
  for (const Case& c : cases) {
    writeBytes(path, c.bytes);
    EXPECT_FALSE(mapper->loadMap(path, nullptr, &error));
    EXPECT_NE(error.find(c.message), std::string::npos) << error;
    EXPECT_NE(error.find(path), std::string::npos) << "the message names the file: " << error;
    EXPECT_TRUE(snapshot(mapper->tsdf()) == before);
    EXPECT_TRUE(triangleSets(mapper->mesh()) == mesh_before);
  }
  fs::remove(path);
  EXPECT_FALSE(mapper->loadMap(path, nullptr, &error));
  EXPECT_NE(error.find("cannot open the map file"), std::string::npos) << error;
  EXPECT_FALSE(mapper->saveMap("/nonexistent_dir/x.sfmap", &error));
  EXPECT_NE(error.find("cannot write"), std::string::npos) << error;
  EXPECT_NE(error.find("No such file or directory"), std::string::npos)
      << "the message says why: " << error;
  // A device is refused before reading (/dev/zero would never end), a directory likewise.
  for (const std::string& not_a_file : {std::string("/dev/zero"), testing::TempDir()}) {
    EXPECT_FALSE(mapper->loadMap(not_a_file, nullptr, &error));
    EXPECT_NE(error.find("not a regular file"), std::string::npos) << error;
  }
  EXPECT_TRUE(snapshot(mapper->tsdf()) == before);
  EXPECT_TRUE(triangleSets(mapper->mesh()) == mesh_before);
}

TEST(MapFile, LoadingReplacesTheMapAndReportsTheOldSubmeshesAsRemoved) {
  MapperConfig config;
  config.voxel_size_m = 0.04;
  const auto small = fusedMapper(1, config);
  Mapper mapper(config);
  // A different map first: a plane far away.
  sim::AnalyticScene elsewhere;
  elsewhere.add(sim::makePlane({0, 0, 5.0}, {0, 0, -1}));
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(30, 0, 0);
  ASSERT_TRUE(mapper.integrate(renderFrame(elsewhere, qvgaCamera(), T)).accepted);
  std::vector<BlockKey> old_keys;
  for (const auto& [k, sub] : mapper.mesh().submeshes()) old_keys.push_back(k);
  std::sort(old_keys.begin(), old_keys.end());
  ASSERT_FALSE(old_keys.empty());
  const std::string path = tempPath("replace.sfmap");
  std::string error;
  ASSERT_TRUE(small->saveMap(path, &error));
  MeshChanges changes;
  ASSERT_TRUE(mapper.loadMap(path, &changes, &error)) << error;
  EXPECT_EQ(changes.removed, old_keys);
  EXPECT_TRUE(triangleSets(mapper.mesh()) == triangleSets(small->mesh()));
  fs::remove(path);
}
