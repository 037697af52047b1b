// libFuzzer target for the map file decoder (io/MapFile.h): any byte string must either decode
// into a consistent octree or fail with a message — never crash, hang, or allocate beyond
// what the input's own size justifies. Built by the fuzz build (clang, -DSTEREO_FUSION_FUZZ=ON).
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "stereo_fusion/io/MapFile.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace stereo_fusion;
  const MapperConfig config;  // voxel_size_m and truncation_vox must match the file's
  BlockOctree map(config.blockSizeM());
  MapFileInfo info;
  std::string error;
  const bool ok = decodeMapFile(data, size, config, &map, &info, &error);
  if (ok) {
    // A decoded file is self-consistent: as many blocks as announced (a version-1 file may
    // hold blocks without observations, which are not loaded), one last-update frame per block,
    // and a current file re-encodes to the input's size (one record size per block and levels);
    // a version-1 file re-encodes to a current one that decodes to the same number of blocks.
    const bool current = info.version == kMapFileVersion;
    if (current ? map.blockCount() != info.block_count : map.blockCount() > info.block_count)
      std::abort();
    if (info.last_update_frames.size() != map.blockCount()) std::abort();
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
  } else if (error.empty()) {
    std::abort();  // every failure explains itself
  }
  return 0;
}
