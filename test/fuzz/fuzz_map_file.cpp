// libFuzzer target for the map file decoder (io/MapFile.h): any byte string must either decode
// into a consistent octree or fail with a message — never crash, hang, or allocate beyond
// what the input's own size justifies. Each input is tried twice: as it is, and as the crafted
// class — its payload size and both checksums recomputed, as an attacker who edits a key would —
// so that mutations reach the range and order checks instead of stopping at the checksums. A
// file that decodes is then loaded into the planning layer as the node does (its seen-free
// cells, then a rebuild from the TSDF) and projected onto the ground under the smallest
// grid_max_cells, which must bound the grid whatever the keys. Built by the fuzz build (clang,
// -DSTEREO_FUSION_FUZZ=ON).
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <vector>

#include "stereo_fusion/StageConfigs.h"
#include "stereo_fusion/io/MapFile.h"
#include "stereo_fusion/layers/PlanningLayer.h"
#include "stereo_fusion/planning/OccupancyGrid2D.h"
#include "stereo_fusion/planning/PlanningMap.h"
#include "stereo_fusion/util/Crc32.h"
#include "stereo_fusion/util/ThreadPool.h"

namespace {
using namespace stereo_fusion;

void storeU32(uint8_t* p, uint32_t v) {
  for (int i = 0; i < 4; ++i) p[i] = static_cast<uint8_t>(v >> (8 * i));
}
void storeU64(uint8_t* p, uint64_t v) {
  for (int i = 0; i < 8; ++i) p[i] = static_cast<uint8_t>(v >> (8 * i));
}

/// The input with its sizes and checksums made consistent for the version it names (the layout
/// of io/MapFile.h); unchanged where it is too short to hold a header.
std::vector<uint8_t> resealed(const uint8_t* data, size_t size) {
  std::vector<uint8_t> file(data, data + size);
  if (size < kMapFileHeaderBytes) return file;
  const uint32_t version = file[8] | file[9] << 8 | file[10] << 16 | uint32_t{file[11]} << 24;
  if (version == 1) {
    storeU32(file.data() + 12, kMapFileV1HeaderBytes);
    storeU32(file.data() + 64,
             crc32(file.data() + kMapFileV1HeaderBytes, size - kMapFileV1HeaderBytes));
    storeU32(file.data() + 68, crc32(file.data(), 68));
  } else {
    storeU32(file.data() + 12, kMapFileHeaderBytes);
    storeU64(file.data() + 64, size - kMapFileHeaderBytes);
    sealMapFile(&file);
  }
  return file;
}

void checkDecode(const uint8_t* data, size_t size) {
  static ThreadPool pool(1);
  const MapperConfig config;  // voxel_size_m and truncation_vox must match the file's
  BlockOctree map(config.blockSizeM());
  MapFileInfo info;
  std::string error;
  const bool ok = decodeMapFile(data, size, config, &map, &info, &error);
  if (!ok) {
    if (error.empty()) std::abort();  // every failure explains itself
    return;
  }
  // A decoded file is self-consistent: as many blocks as announced (a version-1 file may
  // hold blocks without observations, which are not loaded), one last-update frame per block,
  // and a current file re-encodes to the input's size (one record size per block and levels);
  // a version-1 file re-encodes to a current one that decodes to the same number of blocks.
  const bool current = info.version == kMapFileVersion;
  if (current ? map.blockCount() != info.block_count : map.blockCount() > info.block_count)
    std::abort();
  if (info.last_update_frames.size() != map.blockCount()) std::abort();
  for (const auto& [key, bits] : info.free_space.blocks)
    if (!planningBlockKeyInRange(key)) std::abort();
  const std::vector<uint8_t> again =
      encodeMapFile(map, config, info.frames_integrated, {}, info.free_space);
  if (current && again.size() != size) std::abort();
  if (info.version != kMapFileVersion) {
    BlockOctree reread(config.blockSizeM());
    MapFileInfo reread_info;
    if (!decodeMapFile(again.data(), again.size(), config, &reread, &reread_info, &error))
      std::abort();
    if (reread.blockCount() != map.blockCount()) std::abort();
  }

  // Adopted by the planning layer as Mapper::adoptMap() has it adopt a loaded map, then the grid
  // ~occupancy_grid publishes.
  PlanningLayer layer(stageConfigs(config).planning, &pool);
  layer.adopt(map, info);
  const PlanningMap& planning = layer.map();
  GridWindow window;
  window.max_cells = 10000;  // grid_max_cells' lower bound
  const OccupancyGrid2D grid = projectOccupancy(planning, -1e9, 1e9, window);
  if (static_cast<int64_t>(grid.width) * grid.height > window.max_cells ||
      grid.cells.size() != static_cast<size_t>(grid.width) * grid.height)
    std::abort();
  (void)planning.sample(Eigen::Vector3d::Zero());
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  checkDecode(data, size);
  const std::vector<uint8_t> crafted = resealed(data, size);
  if (crafted != std::vector<uint8_t>(data, data + size))
    checkDecode(crafted.data(), crafted.size());
  return 0;
}
