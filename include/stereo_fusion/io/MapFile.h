#pragma once
#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "stereo_fusion/MapperConfig.h"
#include "stereo_fusion/map/BlockOctree.h"
#include "stereo_fusion/planning/PlanningBlock.h"

namespace stereo_fusion {

/// Map file format, version 3 (all numbers little-endian):
///
///   header, 80 bytes:
///     0  char[8] magic "SFUSEMAP"       8  u32 version (kMapFileVersion)   12 u32 header bytes
///     (80) 16 f64 voxel_size_m               24 f64 truncation_vox 32 f64 scale2_min_depth_m 40
///     f64 scale4_min_depth_m 48 u64 frames integrated          56 u64 block count 64 u64 payload
///     bytes              72 u32 CRC-32 of the payload      76 u32 CRC-32 of header bytes 0..75
///   payload: block count records, sorted by key, each a 24-byte head:
///     i32 x, y, z; u64 last_update_frame (for the eviction order); u8 levels (bit l: level l is
///     stored); u8 0, 0, 0;
///   then the voxels of each stored level, level 0 first, in index order (eq. 3.4), each
///     f32 sdf_m, f32 weight, u8 r, g, b, reserved.
///   So a block seen only at 2³ takes 24 + 96 bytes.
///   then the planning layer's seen-free space: f64 planning cell edge (0: none saved), u64
///     count, and count records sorted by key of 80 bytes: i32 x, y, z, u32 0, u64[8] one bit per
///     cell (PlanningBlock::seen_free). The rest of the planning layer is derived from the TSDF.
///
/// Version 2 (still read): the same without the seen-free section (it loads with its free space
/// unknown).
///
/// Version 1 (still read): a 72-byte header without the payload size (payload CRC at 64,
/// header CRC of bytes 0..67 at 68), and records of all 584 voxels whose head held i8
/// mesh_level (checked < 3) and u8 sign flags (checked ≤ 3) at 20 and 21, both derived data the
/// reader recomputes. Its levels without any observed voxel are not allocated on load.
///
/// voxel_size_m and truncation_vox must equal the loading mapper's: they fix the block grid
/// and the SDF's clamp. The level thresholds are recorded for information only.
constexpr uint32_t kMapFileVersion = 3;
constexpr size_t kMapFileFreeSpaceRecordBytes = 80;

/// The planning layer's seen-free cells as the map file keeps them.
struct SeenFreeSpace {
  double cell_m = 0.0;  ///< 0: the file holds none
  std::vector<std::pair<BlockKey, PlanningBlock::Bits>> blocks;
};
constexpr size_t kMapFileHeaderBytes = 80;
constexpr size_t kMapFileRecordHeadBytes = 24;
constexpr size_t kMapFileV1HeaderBytes = 72;
/// A version-1 record: the head and all 584 voxels.
constexpr size_t kMapFileV1RecordBytes = kMapFileRecordHeadBytes + 584 * 12;

/// What a map file says about itself besides its blocks.
struct MapFileInfo {
  uint32_t version = 0;
  double voxel_size_m = 0;
  double truncation_vox = 0;
  double scale2_min_depth_m = 0;
  double scale4_min_depth_m = 0;
  uint64_t frames_integrated = 0;  ///< of the mapper that saved it
  uint64_t block_count = 0;        ///< as the header announces (a version-1 file's blocks without
                                   ///< observations are not loaded)
  /// Each block's last update frame as the file records it, in key order.
  std::vector<std::pair<BlockKey, uint64_t>> last_update_frames;
  /// Version 3: the seen-free space saved with the map (cell_m 0 for older versions).
  SeenFreeSpace free_space;
};

/// The last update frame the map file records for a block (0: unknown).
using LastUpdateFrameOf = std::function<uint64_t(const VoxelBlock&)>;

/// The file bytes for `map`, built with `config`, after `frames_integrated` frames.
std::vector<uint8_t> encodeMapFile(const BlockOctree& map, const MapperConfig& config,
                                   uint64_t frames_integrated,
                                   const LastUpdateFrameOf& last_update_frame = {},
                                   const SeenFreeSpace& free_space = {});
/// encodeMapFile() without its two checksums (left zero): the part that reads the map, so a
/// caller that locks the map holds the lock only for it. sealMapFile() completes the bytes.
std::vector<uint8_t> encodeMapFileUnsealed(const BlockOctree& map, const MapperConfig& config,
                                           uint64_t frames_integrated,
                                           const LastUpdateFrameOf& last_update_frame = {},
                                           const SeenFreeSpace& free_space = {});
/// The same for `blocks`, sorted by key (a paged map's: some in an octree, some read back).
std::vector<uint8_t> encodeMapFileUnsealed(const std::vector<const VoxelBlock*>& blocks,
                                           const MapperConfig& config, uint64_t frames_integrated,
                                           const LastUpdateFrameOf& last_update_frame = {},
                                           const SeenFreeSpace& free_space = {});
/// The parts of the format one at a time, for a writer that streams the file (writeMapFile()):
/// a block's record (mapFileRecordBytes() bytes), the seen-free section, the header (checksums
/// zero) and its checksums once the payload's CRC-32 is known.
size_t mapFileRecordBytes(const VoxelBlock& block);
void encodeMapFileRecord(const VoxelBlock& block, uint64_t last_update_frame, uint8_t* record);
size_t mapFileFreeSpaceBytes(const SeenFreeSpace& free_space);
void encodeMapFileFreeSpace(const SeenFreeSpace& free_space, uint8_t* out);
void encodeMapFileHeader(const MapperConfig& config, uint64_t frames_integrated,
                         uint64_t block_count, uint64_t payload_bytes, uint8_t* header);
void sealMapFileHeader(uint8_t* header, uint32_t payload_crc);

/// Calls `sink(block, last_update_frame)` for every block of a map in key order; false when a
/// block cannot be read (then `error` says which).
using MapFileBlocks = std::function<bool(
    const std::function<void(const VoxelBlock&, uint64_t)>& sink, std::string* error)>;
/// Writes the map file of `block_count` blocks, streamed from `blocks`, to `path` as
/// writeMapFileBytes() does (a temporary flushed to the disk, renamed into place): the bytes
/// encodeMapFile() would give, without ever holding more than one block's record.
bool writeMapFile(const std::string& path, const MapperConfig& config, uint64_t frames_integrated,
                  uint64_t block_count, const MapFileBlocks& blocks,
                  const SeenFreeSpace& free_space, std::string* error);

/// Fills in both checksums of bytes from encodeMapFileUnsealed() (again, on sealed bytes: the
/// same values).
void sealMapFile(std::vector<uint8_t>* file);

/// Parses and checks file bytes completely (magic, version, sizes, both checksums, parameters
/// against `config`, keys in range and unique, finite voxels with weight ≥ 0) into `out`, which
/// must be empty and have config's block size. False with one sentence in `error` on the first
/// problem; then `out` may hold part of the blocks and must be discarded.
bool decodeMapFile(const uint8_t* data, size_t size, const MapperConfig& config, BlockOctree* out,
                   MapFileInfo* info, std::string* error);

/// Seals (sealMapFile()) bytes encoded earlier by encodeMapFileUnsealed() and writes them to
/// `path` through a temporary `path`.tmp-<pid>-<n> renamed into place, so a crash never leaves
/// a half-written file under the final name. The map need not stay unchanged (or locked) while
/// they are checksummed and reach the disk.
bool writeMapFileBytes(const std::string& path, std::vector<uint8_t>* bytes, std::string* error);
/// Reads `path` and decodeMapFile()s it; errors are prefixed with the path.
bool readMapFile(const std::string& path, const MapperConfig& config, BlockOctree* out,
                 MapFileInfo* info, std::string* error);

}  // namespace stereo_fusion
