#pragma once
#include <cstddef>
#include <cstdint>
#include <string>

namespace stereo_fusion {

/// What the map host's paging reads (from the parameter table: StageConfigs).
struct PagingConfig {
  size_t max_map_memory_bytes = 0;  ///< max_map_memory_mb; 0: no paging, no store
  std::string store_path;           ///< map_store_path; empty: the temporary folder
  double voxel_size_m = 0.0;        ///< the store's identity
  double truncation_vox = 0.0;
  // How far a frame can change the map (FrameReach): its measured depths up to max_depth_m,
  // plus the widest truncation band; free_space_unmeasured_range_m for unmatched pixels.
  double max_depth_m = 0.0;
  double band_m = 0.0;
  double unmeasured_m = 0.0;
  bool enabled() const { return max_map_memory_bytes > 0; }
  /// A page-out pass frees this share of the cap beyond the excess, so passes are not one a frame.
  static constexpr double kHysteresis = 0.1;
  /// Pages handed to the store's writer and not written yet that a page-out lets pile up before
  /// it waits for the writer: a quarter of the cap, at least 4 MiB.
  static size_t maxWriterBacklogBytes(size_t cap_bytes) {
    return cap_bytes / 4 > (size_t{4} << 20) ? cap_bytes / 4 : size_t{4} << 20;
  }
};

/// What paging did since the map was made (or reset, or loaded).
struct PagingStats {
  uint64_t blocks_paged_out = 0;
  uint64_t blocks_paged_in = 0;
  uint64_t page_out_passes = 0;
  /// Page-outs that waited for the store's writer (its backlog over maxWriterBacklogBytes()).
  uint64_t writer_waits = 0;
  /// Blocks paged out unchanged since they came back: the store held their page already.
  uint64_t pages_kept = 0;
  /// The map's memory at its highest (mapMemoryBytes()): right after a frame's fusion and mesh
  /// pass, before the page-out after it — where a frame's blocks put it over the cap.
  size_t map_memory_peak_bytes = 0;
  uint64_t bytes_written = 0;
  uint64_t bytes_read = 0;
  /// Pages that could not be read back (a corrupted store): those blocks are lost, each counted.
  uint64_t pages_unreadable = 0;
  double page_out_ms = 0.0;
  double page_in_ms = 0.0;
  /// The longest single page-in pass (all the blocks one frame or operation brought back).
  double page_in_max_ms = 0.0;
  /// The store refused a write (a full disk): paging stopped, the map stays in memory whole.
  bool stopped = false;
  std::string error;  ///< why paging stopped or a page was lost; empty when neither happened
};

}  // namespace stereo_fusion
