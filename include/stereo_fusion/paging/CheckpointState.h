#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "stereo_fusion/io/MapFile.h"
#include "stereo_fusion/map/BlockKey.h"

namespace stereo_fusion {

/// What a checkpoint of the map store keeps beside the blocks' pages (one record, written in
/// the checkpoint's transaction):
///   u32 magic "SFCK", u32 version; u64 frames integrated; f64 seen-free cell edge (0: none),
///   u64 count and count records of i32 x, y, z, u64[8] seen-free bits; u64 count of the map
///   log's consumers, each with u64 bytes + its name, u64 count + the keys (i32 x, y, z) it had
///   not taken as updated, u64 count + those as erased; u64 bytes and the owner's note (the
///   offline fuser: where in its input it was).
struct CheckpointState {
  uint64_t frames_integrated = 0;
  SeenFreeSpace free_space;
  /// The TSDF changes each consumer of the map log (eviction, the mesh, ...) had not taken.
  struct Pending {
    std::string consumer;
    std::vector<BlockKey> updated, erased;  ///< sorted
  };
  std::vector<Pending> pending;
  std::string owner_note;
};

constexpr uint32_t kCheckpointMagic = 0x4b434653u;  // "SFCK"
constexpr uint32_t kCheckpointVersion = 1;

std::vector<uint8_t> encodeCheckpointState(const CheckpointState& state);
/// False with a sentence in `error` when `bytes` is not a whole checkpoint record.
bool decodeCheckpointState(const std::vector<uint8_t>& bytes, CheckpointState* state,
                           std::string* error);

/// What the map store's checkpoints did since the store was opened.
struct CheckpointStats {
  std::string file;                     ///< the store; empty: no map store
  bool resumed = false;                 ///< the map came from the store
  uint64_t checkpoints = 0;             ///< committed
  uint64_t last_frames_integrated = 0;  ///< the map's frames at the last committed checkpoint
  uint64_t blocks_written = 0;          ///< pages written by checkpoints
  uint64_t blocks_erased = 0;           ///< pages removed by checkpoints (blocks gone from the map)
  uint64_t bytes_written = 0;
  double last_ms = 0.0;  ///< the last checkpoint's time on the caller's thread
  double max_ms = 0.0;
  /// The last committed checkpoint's time from its start to the first frame after its commit:
  /// a checkpoint starts this much before its period ends, so a kill loses at most the period.
  double last_commit_s = 0.0;
  std::string error;  ///< why the last checkpoint failed; empty when none did
};

}  // namespace stereo_fusion
