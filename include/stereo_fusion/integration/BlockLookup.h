#pragma once
#include <cstdint>
#include <vector>

#include "stereo_fusion/MapperConfig.h"
#include "stereo_fusion/integration/MeasurementImage.h"
#include "stereo_fusion/integration/StereoFrame.h"
#include "stereo_fusion/map/BlockKeyBitmap.h"
#include "stereo_fusion/map/BlockKeySet.h"
#include "stereo_fusion/map/BlockOctree.h"
#include "stereo_fusion/util/ThreadPool.h"

namespace stereo_fusion {

/// Counts of one lookup pass.
/// What BlockLookup reads (from the parameter table: StageConfigs): the band of each pixel and
/// Algorithm 1 / 2 with its histogram filter.
struct LookupConfig {
  double voxel_size_m = MapperConfig{}.voxel_size_m;
  double truncation_vox = MapperConfig{}.truncation_vox;
  LookupMode lookup_mode = MapperConfig{}.lookup_mode;
  int lookup_region_px = MapperConfig{}.lookup_region_px;
  int histogram_min_points = MapperConfig{}.histogram_min_points;
  int max_lookup_blocks_per_frame = MapperConfig{}.max_lookup_blocks_per_frame;

  /// Φ by level, as MapperConfig::truncationBand() gives it.
  TruncationBand truncationBand() const { return TruncationBand(voxel_size_m, truncation_vox); }
};

struct LookupStats {
  uint64_t valid_points = 0;      ///< pixels with a usable disparity
  uint64_t octree_searches = 0;   ///< find/findOrAllocate calls made by the lookup
  uint64_t blocks_queued = 0;     ///< distinct blocks the frame's bands reach (queued or missing)
  uint64_t blocks_allocated = 0;  ///< of those, allocated by the lookup (only when run() allocates)
  uint64_t blocks_missing = 0;    ///< of those, not in the map and left to fusion to create
  uint64_t blocks_filtered = 0;   ///< (region, block) pairs dropped by the histogram filter
  /// The lookup's work: blocks spanned by the distinct band boxes of each region (naive: by
  /// every pixel's box), counted before any block is visited.
  uint64_t box_blocks = 0;
  /// box_blocks exceeded max_lookup_blocks_per_frame: nothing was visited or queued.
  bool over_work_bound = false;
};

/// Stage 1 of the pipeline (thesis §3.4): turns a frame's depths into the queue of voxel blocks
/// to update. Each pixel with a depth (MeasurementImage: the same validity and depth as fusion
/// uses) contributes the blocks that its truncation band reaches: the segment of its ray within
/// ±Φ of the measured surface (Φ of the level its depth selects, eq. 3.2, TruncationBand;
/// bounded as ±Φ·p/z, up to 1.2× longer off-axis), widened by the voxels that project onto the
/// pixel (kLateralMarginPx). Those are the blocks holding a voxel that this pixel's measurement
/// puts within its band (|sdf| ≤ Φ); voxels farther in front (fused clamped to −Φ) and the wider
/// band a near measurement leaves in coarse levels are fused where some band brings their block.
/// So the queue follows the surface, not the volume of a ±Φ cube around each point (a cube
/// queues ~25× the blocks at far range, where Φ spans several blocks). The histogram filter,
/// when on, drops per image region the blocks reached by fewer than `histogram_min_points` points,
/// scaled by the share of the region's pixels that hold a measurement (regionMinPoints()).
///
/// Per pixel the box is float arithmetic relative to the block holding the camera (so its
/// precision does not depend on how far the camera is from the world origin): the ray
/// direction per pixel column plus one per row, times the depth. The scalar path is the
/// reference; the AVX2 path does the same float operations eight pixels at a time.
///
/// Naive (Algorithm 1) searches the octree for every (pixel, band block) pair; accelerated
/// (Algorithm 2) first gathers the distinct blocks of each region (and its histogram), then
/// searches each distinct block of the whole frame once.
/// Both produce the same queue. Regions run in parallel on the pool.
class BlockLookup {
 public:
  /// `allow_simd` = false keeps to the scalar per-pixel path even where the CPU has AVX2 (the
  /// vector path gives identical results; tests compare the two).
  BlockLookup(const LookupConfig& config, ThreadPool* pool, bool allow_simd = true);

  /// Whether this lookup uses the AVX2 per-pixel path.
  bool usesSimd() const { return use_avx2_; }

  /// Fills `queue` with the distinct blocks to update, sorted by key (deterministic).
  /// The frame must have passed validateFrame(); `measurements` holds its depths
  /// (MeasurementImage::build(frame, config, …) with this lookup's configuration). With `missing`,
  /// blocks not yet in the octree are not allocated: their keys go to *missing (sorted), for fusion
  /// to create only those it really updates (SurfaceFuser::fuse); without, they are allocated and
  /// queued.
  LookupStats run(const StereoFrame& frame, const MeasurementImage& measurements,
                  BlockOctree* octree, std::vector<VoxelBlock*>* queue,
                  std::vector<BlockKey>* missing = nullptr);

 private:
  /// How far (in pixels) from a pixel's ray a voxel centre that fusion reads at that pixel can
  /// lie: its projection rounds to the pixel, so it is within 0.5 px on each image axis,
  /// ≤ 0.71 px in all; 0.75 leaves room for the roundings of both paths.
  static constexpr double kLateralMarginPx = 0.75;
  /// Largest union of a region's band boxes (in blocks) counted on a dense grid (64 KiB).
  static constexpr int64_t kMaxDenseHistogramCells = 16384;
  struct BandBox {
    BlockKey lo, hi;  // inclusive key range of the blocks a point's band touches
    bool operator==(const BandBox& o) const { return lo == o.lo && hi == o.hi; }
  };
  /// A distinct band box of a region and its number of points, in one 32-byte vector so that
  /// the AVX2 path compares a box with one instruction.
  struct alignas(32) BoxCount {
    BandBox box;
    int32_t count = 0;
    int32_t unused = 0;
  };
  static_assert(sizeof(BandBox) == 6 * sizeof(int32_t), "a BandBox is lo x, y, z, hi x, y, z");
  static_assert(sizeof(BoxCount) == 32, "a BoxCount is one AVX2 vector");
  /// Per-frame constants of the pixel → band box mapping. Positions are in blocks relative to
  /// origin_key (the block holding the camera): the ray of pixel (u, v) at depth z reaches
  /// origin_key + origin_frac + z · (column_dir[u] + row_dir[v]).
  struct PixelGeometry {
    int32_t origin_key[3] = {};
    float origin_frac[3] = {};
    /// Per world axis: R·((u − cx)/fx, 0, 0) per image column u and R·(0, (v − cy)/fy, 1) per
    /// image row v, in blocks per metre of depth.
    std::vector<float> column_dir[3], row_dir[3];
    FloatLevelThresholds levels;    ///< eq. 3.2, the same float compares as fusion
    float band_m[kNumLevels] = {};  ///< Φ of each measurement level
    /// Lateral margin around a pixel's ray, in blocks per metre of depth (kLateralMarginPx).
    float lateral_blocks_per_m = 0.0f;
    /// Every Φ ≥ 0 (so lo ≤ hi in each box), which the AVX2 path's key range test relies on;
    /// a config without it keeps to the scalar path.
    bool bands_non_negative = false;
  };
  /// Boxes reaching beyond this many blocks from the camera's block are refused before their
  /// float coordinates are converted to integers (keys beyond ±kMaxKey are refused anyway).
  static constexpr float kMaxBlocksFromCamera = 1 << 29;
  struct RegionScratch {
    std::vector<BoxCount> boxes;                       // distinct band boxes and their point counts
    BlockKey boxes_lo, boxes_hi;                       // the boxes' union, if there are boxes
    std::vector<std::pair<BlockKey, int>> key_counts;  // naive: histogram, points per block
    std::vector<std::pair<BlockKey, int>> sparse_counts;  // points per block off the dense grid
    std::vector<BlockKey> passing;   // accelerated: blocks that pass the histogram filter
    std::vector<VoxelBlock*> found;  // naive: blocks found, in search order (with repeats)
    std::vector<BlockKey>
        not_found;  // naive without allocation: keys of missing blocks (with repeats)
    LookupStats stats;
  };

  void setPixelGeometry(const StereoFrame& frame, const MeasurementImage& measurements,
                        const BlockOctree& octree);
  /// The band box of pixel (u, v), `depth_row` being row v of the depths; false if the pixel
  /// has no depth or its box leaves the key range.
  bool bandBoxOfPixel(const float* depth_row, int u, int v, BandBox* box) const;
  void countBox(const BandBox& box, RegionScratch* s, size_t* last) const;
  /// One more point in `box`, found among s->boxes or added; returns its index.
  size_t countInBoxes(const BandBox& box, RegionScratch* s) const;
  /// Fill s->boxes and s->stats.valid_points from the region's pixels (the AVX2 path gives
  /// exactly the scalar path's boxes and counts).
  void countRegionBoxesScalar(const MeasurementImage& m, const cv::Rect& region,
                              RegionScratch* s) const;
  void countRegionBoxesAvx2(const MeasurementImage& m, const cv::Rect& region,
                            RegionScratch* s) const;
  /// s->boxes, their union and s->stats.valid_points of the region.
  void countRegionBoxes(const MeasurementImage& m, const cv::Rect& region, RegionScratch* s) const;
  /// Calls visit(key, count) for each block the region's boxes reach, with its number of
  /// points, in z, y, x order (or key order when the union is too large for the grid).
  template <typename Visit>
  void forEachBlockCount(RegionScratch* s, Visit&& visit) const;
  /// The blocks the region's counted boxes span: each distinct box once (accelerated, which
  /// expands each box once) or once per point in it (naive, which expands every pixel's box);
  /// saturates at UINT64_MAX.
  uint64_t boxBlocks(const RegionScratch& s, bool per_point) const;
  /// s->key_counts: the region's histogram, from its counted boxes.
  void gatherHistogram(RegionScratch* s) const;
  /// The histogram filter's threshold in `region` (both lookup modes): histogram_min_points
  /// scaled by the share of its pixels with a measurement, rounded up, at least 1; 0 = off.
  int regionMinPoints(const cv::Rect& region, uint64_t valid_points) const;
  bool passesFilter(const RegionScratch& s, const BlockKey& key, int min_points) const;
  /// The second pass of both modes, after countRegionBoxes() and the work bound.
  void runRegionAccelerated(const cv::Rect& region, RegionScratch* s) const;
  /// frame_keys_ ← the distinct `passing` keys of the first `num_regions` regions, sorted.
  void collectSortedDistinctKeys(size_t num_regions);
  void runRegionNaive(const MeasurementImage& m, const cv::Rect& region, BlockOctree* octree,
                      bool allocate, RegionScratch* s) const;

  LookupConfig config_;
  ThreadPool* pool_;
  bool use_avx2_;
  std::vector<RegionScratch> scratch_;  // one per region, reused across frames
  PixelGeometry geometry_;              // of the frame being looked up
  // Accelerated mode's frame-wide de-duplication, reused across frames.
  BlockKeyBitmap frame_key_bitmap_;  // when the frame's blocks span a small enough box
  BlockKeySet frame_key_set_;        // otherwise
  std::vector<BlockKey> frame_keys_;
  std::vector<VoxelBlock*> frame_blocks_;
  std::vector<uint8_t> frame_allocated_;
};

}  // namespace stereo_fusion
