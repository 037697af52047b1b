#include "stereo_fusion/integration/BlockLookup.h"

#include <algorithm>
#include <atomic>
#include <cmath>

#include "stereo_fusion/util/CpuFeatures.h"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#define STEREO_FUSION_HAVE_AVX2_LOOKUP 1
#endif

namespace stereo_fusion {

BlockLookup::BlockLookup(const LookupConfig& config, ThreadPool* pool, bool allow_simd)
    : config_(config), pool_(pool), use_avx2_(allow_simd && avx2Supported()) {}

void BlockLookup::setPixelGeometry(const StereoFrame& frame, const MeasurementImage& measurements,
                                   const BlockOctree& octree) {
  PixelGeometry& g = geometry_;
  const StereoCamera& cam = frame.camera;
  const Eigen::Matrix3d R_world_camera = frame.T_world_camera.linear();
  const double inv_block_size = 1.0 / octree.blockSize();
  // validateFrame() keeps the camera within kMaxKey / 2 blocks of the origin.
  const Eigen::Vector3d camera_blocks = frame.T_world_camera.translation() * inv_block_size;
  for (int i = 0; i < 3; ++i) {
    const double key = std::floor(camera_blocks[i]);
    g.origin_key[i] = static_cast<int32_t>(key);
    g.origin_frac[i] = static_cast<float>(camera_blocks[i] - key);
  }
  for (int i = 0; i < 3; ++i) {
    g.column_dir[i].resize(static_cast<size_t>(frame.disparity_px.cols));
    for (int u = 0; u < frame.disparity_px.cols; ++u)
      g.column_dir[i][u] =
          static_cast<float>(R_world_camera(i, 0) * ((u - cam.cx()) / cam.fx()) * inv_block_size);
    g.row_dir[i].resize(static_cast<size_t>(frame.disparity_px.rows));
    for (int v = 0; v < frame.disparity_px.rows; ++v)
      g.row_dir[i][v] = static_cast<float>(
          (R_world_camera(i, 1) * ((v - cam.cy()) / cam.fy()) + R_world_camera(i, 2)) *
          inv_block_size);
  }
  g.levels = FloatLevelThresholds(measurements.levels());
  const TruncationBand band = config_.truncationBand();
  for (int level = 0; level < kNumLevels; ++level)
    g.band_m[level] = band.measurementM<float>(level);
  // A voxel centre that fusion reads at a pixel projects within half a pixel of its centre on
  // each image axis: within 0.5·√2 pixel footprints of the pixel's ray (0.75 for margin).
  g.lateral_blocks_per_m =
      static_cast<float>(kLateralMarginPx / std::min(cam.fx(), cam.fy()) * inv_block_size);
  g.bands_non_negative = true;
  for (float b : g.band_m) g.bands_non_negative = g.bands_non_negative && b >= 0.0f;
}

// Inline: called for every pixel (a call per pixel cost a fifth of the lookup).
inline bool BlockLookup::bandBoxOfPixel(const float* depth_row, int u, int v, BandBox* box) const {
  const PixelGeometry& g = geometry_;
  const float z = depth_row[u];  // NaN where there is no measurement: every comparison below fails
  // The band along the ray: the surface point ± Φ in the ray's direction, widened by the
  // lateral margin (kLateralMarginPx at the far end). ±Φ along the ray moves the point by
  // Φ·p/‖p‖; Φ·p/z = Φ·dir bounds it (‖p‖ ≥ z) without a square root or a division, at most
  // ‖p‖/z longer: 1.2 at a 640×480 image's corners for f = 576 px, 1 on the optical axis.
  // The float operations and their order are the AVX2 path's (no FMA: see FusionKernels.cpp).
  const float band = g.band_m[g.levels.levelOf(z)];
  const float lateral = (z + band) * g.lateral_blocks_per_m;  // blocks
  int32_t lo[3], hi[3];
  for (int i = 0; i < 3; ++i) {
    const float dir = g.column_dir[i][u] + g.row_dir[i][v];  // blocks per metre of depth
    const float centre = z * dir + g.origin_frac[i];
    const float half = std::fabs(dir) * band + lateral;
    const float lo_blocks = std::floor(centre - half), hi_blocks = std::floor(centre + half);
    if (!(lo_blocks >= -kMaxBlocksFromCamera && hi_blocks <= kMaxBlocksFromCamera)) return false;
    lo[i] = static_cast<int32_t>(lo_blocks) + g.origin_key[i];
    hi[i] = static_cast<int32_t>(hi_blocks) + g.origin_key[i];
  }
  box->lo = BlockKey{lo[0], lo[1], lo[2]};
  box->hi = BlockKey{hi[0], hi[1], hi[2]};
  return BlockOctree::keyInRange(box->lo) && BlockOctree::keyInRange(box->hi);
}

template <typename F>
static void forEachKeyInBox(const BlockKey& lo, const BlockKey& hi, F&& f) {
  for (int32_t z = lo.z; z <= hi.z; ++z)
    for (int32_t y = lo.y; y <= hi.y; ++y)
      for (int32_t x = lo.x; x <= hi.x; ++x) f(BlockKey{x, y, z});
}

// Counts one more point in `box`. Neighbouring pixels almost always share a band box, so a
// comparison with the previous box settles most pixels.
__attribute__((always_inline)) inline void BlockLookup::countBox(const BandBox& box,
                                                                 RegionScratch* s,
                                                                 size_t* last) const {
  ++s->stats.valid_points;
  if (*last < s->boxes.size() && s->boxes[*last].box == box) {
    ++s->boxes[*last].count;
    return;
  }
  *last = countInBoxes(box, s);
}

__attribute__((always_inline)) inline size_t BlockLookup::countInBoxes(const BandBox& box,
                                                                       RegionScratch* s) const {
  // Boxes are distinct, so the search order does not matter; from the newest, since a
  // changed box is most often one just seen (a neighbour in the row or the row above).
  for (size_t i = s->boxes.size(); i-- > 0;) {
    if (s->boxes[i].box == box) {
      ++s->boxes[i].count;
      return i;
    }
  }
  s->boxes.push_back(BoxCount{box, 1});
  return s->boxes.size() - 1;
}

// The reference per-pixel path: every pixel through bandBoxOfPixel().
void BlockLookup::countRegionBoxesScalar(const MeasurementImage& m, const cv::Rect& region,
                                         RegionScratch* s) const {
  size_t last = 0;
  for (int v = region.y; v < region.y + region.height; ++v) {
    const float* depth_row = m.depths() + static_cast<size_t>(v) * m.width();
    for (int u = region.x; u < region.x + region.width; ++u) {
      BandBox box;
      if (bandBoxOfPixel(depth_row, u, v, &box)) countBox(box, s, &last);
    }
  }
}

#ifdef STEREO_FUSION_HAVE_AVX2_LOOKUP
// Bit i set: lane i of `key` (lo x, y, z, hi x, y, z of eight boxes) equals `box` (the same six).
__attribute__((target("avx2"), always_inline)) static inline int lanesInBox(const __m256i key[6],
                                                                            const int32_t box[6]) {
  __m256i equal = _mm256_cmpeq_epi32(key[0], _mm256_set1_epi32(box[0]));
  for (int k = 1; k < 6; ++k)
    equal = _mm256_and_si256(equal, _mm256_cmpeq_epi32(key[k], _mm256_set1_epi32(box[k])));
  return _mm256_movemask_ps(_mm256_castsi256_ps(equal));
}

// Eight pixels at a time: the same float operations as bandBoxOfPixel() in the same order
// (no FMA: the target is AVX2 only), so the boxes are identical; a row's last width % 8
// pixels go through bandBoxOfPixel(). The whole region in one call: a region row is only a
// few groups, too few to pay for setting the constants up per row.
// Needs geometry_.bands_non_negative (see the key range test below).
__attribute__((target("avx2"))) void BlockLookup::countRegionBoxesAvx2(const MeasurementImage& m,
                                                                       const cv::Rect& region,
                                                                       RegionScratch* s) const {
  const PixelGeometry& g = geometry_;
  const __m256 level1_min = _mm256_set1_ps(g.levels.level1_min_depth_m),
               level2_min = _mm256_set1_ps(g.levels.level2_min_depth_m);
  const __m256 band0 = _mm256_set1_ps(g.band_m[0]), band1 = _mm256_set1_ps(g.band_m[1]),
               band2 = _mm256_set1_ps(g.band_m[2]);
  const __m256 lateral_per_m = _mm256_set1_ps(g.lateral_blocks_per_m);
  const __m256 sign_bit = _mm256_set1_ps(-0.0f);
  const __m256 min_blocks = _mm256_set1_ps(-kMaxBlocksFromCamera),
               max_blocks = _mm256_set1_ps(kMaxBlocksFromCamera);
  // keyInRange(): key ≥ −kMaxKey ⇔ key > −kMaxKey − 1, key ≤ kMaxKey ⇔ kMaxKey + 1 > key.
  const __m256i below_min_key = _mm256_set1_epi32(-BlockOctree::kMaxKey - 1),
                above_max_key = _mm256_set1_epi32(BlockOctree::kMaxKey + 1);
  __m256 origin_frac[3];
  __m256i origin_key[3];
  for (int i = 0; i < 3; ++i) {
    origin_frac[i] = _mm256_set1_ps(g.origin_frac[i]);
    origin_key[i] = _mm256_set1_epi32(g.origin_key[i]);
  }
  const int u_end = region.x + region.width, u_vector_end = region.x + (region.width & ~7);

  // countBox()'s previous box (lo x, y, z, hi x, y, z); refreshed whenever countBox() runs.
  // Plain ints: the lambdas are not compiled for AVX2.
  size_t last = 0;
  int32_t last_key[6] = {};
  int* last_count = nullptr;  // nullptr until the region has a box
  auto track_last = [&] {
    BoxCount& entry = s->boxes[last];  // may have moved: boxes can grow
    const BandBox& b = entry.box;
    last_key[0] = b.lo.x, last_key[1] = b.lo.y, last_key[2] = b.lo.z;
    last_key[3] = b.hi.x, last_key[4] = b.hi.y, last_key[5] = b.hi.z;
    last_count = &entry.count;
  };
  auto count_box = [&](const BandBox& box) {
    countBox(box, s, &last);
    track_last();
  };
  // `n` more points in the previous box: what n countBox() calls would do when each box
  // equals the previous one.
  auto repeat_box = [&](int n) {
    *last_count += n;
    s->stats.valid_points += n;
  };

  for (int v = region.y; v < region.y + region.height; ++v) {
    const float* depth_row = m.depths() + static_cast<size_t>(v) * m.width();
    const __m256 row_dir[3] = {_mm256_set1_ps(g.row_dir[0][v]), _mm256_set1_ps(g.row_dir[1][v]),
                               _mm256_set1_ps(g.row_dir[2][v])};
    int u = region.x;
    for (; u < u_vector_end; u += 8) {
      const __m256 z = _mm256_loadu_ps(depth_row + u);
      if (_mm256_movemask_ps(_mm256_cmp_ps(z, z, _CMP_ORD_Q)) == 0)
        continue;  // no depth in any lane
      // Level of eq. 3.2 → band, lane by lane (NaN: level 0, refused below).
      const __m256 band =
          _mm256_blendv_ps(_mm256_blendv_ps(band0, band1, _mm256_cmp_ps(z, level1_min, _CMP_GE_OQ)),
                           band2, _mm256_cmp_ps(z, level2_min, _CMP_GE_OQ));
      const __m256 lateral = _mm256_mul_ps(_mm256_add_ps(z, band), lateral_per_m);
      __m256 valid = _mm256_castsi256_ps(_mm256_set1_epi32(-1));
      __m256i key[6];  // lo x, y, z, hi x, y, z of the eight lanes
      for (int i = 0; i < 3; ++i) {
        const __m256 dir = _mm256_add_ps(_mm256_loadu_ps(g.column_dir[i].data() + u), row_dir[i]);
        const __m256 centre = _mm256_add_ps(_mm256_mul_ps(z, dir), origin_frac[i]);
        const __m256 half =
            _mm256_add_ps(_mm256_mul_ps(_mm256_andnot_ps(sign_bit, dir), band), lateral);
        const __m256 lo_blocks = _mm256_floor_ps(_mm256_sub_ps(centre, half));
        const __m256 hi_blocks = _mm256_floor_ps(_mm256_add_ps(centre, half));
        // With half ≥ 0, lo ≤ hi whenever neither is NaN, so lo ≥ −max and hi ≤ max cover all
        // four bounds (NaN fails both); then both convert exactly, and the same holds for
        // the integer key range test.
        valid =
            _mm256_and_ps(valid, _mm256_and_ps(_mm256_cmp_ps(lo_blocks, min_blocks, _CMP_GE_OQ),
                                               _mm256_cmp_ps(hi_blocks, max_blocks, _CMP_LE_OQ)));
        key[i] = _mm256_add_epi32(_mm256_cvttps_epi32(lo_blocks), origin_key[i]);
        key[3 + i] = _mm256_add_epi32(_mm256_cvttps_epi32(hi_blocks), origin_key[i]);
        valid = _mm256_and_ps(valid, _mm256_castsi256_ps(_mm256_and_si256(
                                         _mm256_cmpgt_epi32(key[i], below_min_key),
                                         _mm256_cmpgt_epi32(above_max_key, key[3 + i]))));
      }
      const int lanes = _mm256_movemask_ps(valid);
      if (lanes == 0) continue;
      // Neighbouring pixels almost always share a box: first the lanes in the previous box
      // (all eight, most often), then the region's boxes from the newest, each taking all
      // the lanes it holds at once, then new boxes in lane order: countBox() per lane would
      // give the same boxes, in the same order, with the same counts.
      int remaining = lanes;
      if (last_count != nullptr) {
        const int in_last = lanesInBox(key, last_key) & remaining;
        if (in_last == 0xFF) {
          repeat_box(8);
          continue;
        }
        *last_count += __builtin_popcount(in_last);
        remaining &= ~in_last;
      }
      s->stats.valid_points += __builtin_popcount(lanes);
      const int last_lane = 1 << (31 - __builtin_clz(static_cast<unsigned>(lanes)));
      for (size_t j = s->boxes.size(); remaining != 0 && j-- > 0;) {
        if (j == last && last_count != nullptr) continue;  // done above
        const int in_box =
            lanesInBox(key, reinterpret_cast<const int32_t*>(&s->boxes[j].box)) & remaining;
        if (in_box == 0) continue;
        s->boxes[j].count += __builtin_popcount(in_box);
        remaining &= ~in_box;
        if (in_box & last_lane) last = j;
      }
      if (remaining != 0) {
        alignas(32) int32_t keys[6][8];
        for (int k = 0; k < 6; ++k) _mm256_store_si256(reinterpret_cast<__m256i*>(keys[k]), key[k]);
        while (remaining != 0) {
          const int lane = __builtin_ctz(static_cast<unsigned>(remaining));
          const int32_t lane_key[6] = {keys[0][lane], keys[1][lane], keys[2][lane],
                                       keys[3][lane], keys[4][lane], keys[5][lane]};
          const int in_box = lanesInBox(key, lane_key) & remaining;
          s->boxes.push_back(BoxCount{
              {{lane_key[0], lane_key[1], lane_key[2]}, {lane_key[3], lane_key[4], lane_key[5]}},
              __builtin_popcount(in_box)});
          remaining &= ~in_box;
          if (in_box & last_lane) last = s->boxes.size() - 1;
        }
      }
      track_last();  // the box of the last valid lane
    }
    for (; u < u_end; ++u) {
      BandBox box;
      if (bandBoxOfPixel(depth_row, u, v, &box)) count_box(box);
    }
  }
}

#else
void BlockLookup::countRegionBoxesAvx2(const MeasurementImage& m, const cv::Rect& region,
                                       RegionScratch* s) const {
  countRegionBoxesScalar(m, region, s);  // not x86: no vector path
}
#endif

void BlockLookup::countRegionBoxes(const MeasurementImage& m, const cv::Rect& region,
                                   RegionScratch* s) const {
  s->boxes.clear();
  if (use_avx2_ && geometry_.bands_non_negative)
    countRegionBoxesAvx2(m, region, s);
  else
    countRegionBoxesScalar(m, region, s);
  if (s->boxes.empty()) return;
  s->boxes_lo = s->boxes.front().box.lo;
  s->boxes_hi = s->boxes.front().box.hi;
  for (const BoxCount& box_count : s->boxes) {
    s->boxes_lo = componentMin(s->boxes_lo, box_count.box.lo);
    s->boxes_hi = componentMax(s->boxes_hi, box_count.box.hi);
  }
}

template <typename Visit>
void BlockLookup::forEachBlockCount(RegionScratch* s, Visit&& visit) const {
  if (s->boxes.empty()) return;
  // Boxes overlap heavily (coarse levels reach 2 blocks either side), so count on a dense
  // grid over their union when it is small, which it is unless the region straddles a large
  // depth jump; otherwise merge keys linearly.
  const BlockKey lo = s->boxes_lo, hi = s->boxes_hi;
  const int64_t nx = int64_t{hi.x} - lo.x + 1, ny = int64_t{hi.y} - lo.y + 1,
                nz = int64_t{hi.z} - lo.z + 1;
  if (nx * ny * nz <= kMaxDenseHistogramCells) {
    // + kDenseRowPadding: a box row of up to 8 cells is added as two runs of four, the cells
    // past its end (the next row's, or this padding) getting + 0.
    constexpr size_t kDenseRowPadding = 8;
    // Per thread, not per region: one grid of up to 64 KiB for each of a frame's ~300 regions
    // stayed allocated between frames (20 MB at 640×480).
    thread_local std::vector<int> dense_counts;
    dense_counts.assign(static_cast<size_t>(nx * ny * nz) + kDenseRowPadding, 0);
    for (const BoxCount& box_count : s->boxes) {
      const BandBox& box = box_count.box;
      const int32_t width = box.hi.x - box.lo.x + 1;
      auto row_of = [&](int32_t y, int32_t z) {
        return &dense_counts[static_cast<size_t>(((z - lo.z) * ny + (y - lo.y)) * nx +
                                                 (box.lo.x - lo.x))];
      };
#if defined(__SSE2__)
      if (width <= 8) {  // always, unless Φ is over 3.5 blocks
        const __m128i lane = _mm_setr_epi32(0, 1, 2, 3), count = _mm_set1_epi32(box_count.count);
        const __m128i add_first =
            _mm_and_si128(count, _mm_cmplt_epi32(lane, _mm_set1_epi32(width)));
        const __m128i add_second =
            _mm_and_si128(count, _mm_cmplt_epi32(lane, _mm_set1_epi32(width - 4)));
        for (int32_t z = box.lo.z; z <= box.hi.z; ++z)
          for (int32_t y = box.lo.y; y <= box.hi.y; ++y) {
            __m128i* cells = reinterpret_cast<__m128i*>(row_of(y, z));
            _mm_storeu_si128(cells, _mm_add_epi32(_mm_loadu_si128(cells), add_first));
            if (width > 4)
              _mm_storeu_si128(cells + 1, _mm_add_epi32(_mm_loadu_si128(cells + 1), add_second));
          }
        continue;
      }
#endif
      for (int32_t z = box.lo.z; z <= box.hi.z; ++z)
        for (int32_t y = box.lo.y; y <= box.hi.y; ++y) {
          int* row = row_of(y, z);
          for (int32_t x = 0; x < width; ++x) row[x] += box_count.count;
        }
    }
    const int* count = dense_counts.data();
    for (int32_t z = lo.z; z <= hi.z; ++z)
      for (int32_t y = lo.y; y <= hi.y; ++y)
        for (int32_t x = lo.x; x <= hi.x; ++x, ++count)
          if (*count > 0) visit(BlockKey{x, y, z}, *count);
    return;
  }
  // Every (block, points) pair of every box, sorted by key and summed: O(n log n) in the blocks
  // the boxes span, which the work bound limits (a search per block was quadratic: a 16×12
  // frame with far, widely spread boxes took 0.3 s).
  s->sparse_counts.clear();
  // Not a structured binding: lambdas may capture those only from C++20 (clang refuses).
  for (const BoxCount& box_count : s->boxes) {
    const int count = box_count.count;
    forEachKeyInBox(box_count.box.lo, box_count.box.hi,
                    [&](const BlockKey& key) { s->sparse_counts.emplace_back(key, count); });
  }
  std::sort(s->sparse_counts.begin(), s->sparse_counts.end(),
            [](const auto& a, const auto& b) { return a.first < b.first; });
  for (size_t i = 0; i < s->sparse_counts.size();) {
    const BlockKey key = s->sparse_counts[i].first;
    int count = 0;
    for (; i < s->sparse_counts.size() && s->sparse_counts[i].first == key; ++i)
      count += s->sparse_counts[i].second;
    visit(key, count);
  }
}

uint64_t BlockLookup::boxBlocks(const RegionScratch& s, bool per_point) const {
  // In doubles: a box of an absurd frame may span up to 2^30 blocks per axis.
  double blocks = 0.0;
  for (const BoxCount& b : s.boxes)
    blocks += (double(b.box.hi.x) - b.box.lo.x + 1) * (double(b.box.hi.y) - b.box.lo.y + 1) *
              (double(b.box.hi.z) - b.box.lo.z + 1) * (per_point ? b.count : 1);
  return blocks >= 1.8e19 ? UINT64_MAX : static_cast<uint64_t>(blocks);
}

void BlockLookup::gatherHistogram(RegionScratch* s) const {
  // Points were counted per distinct band box (countRegionBoxes); boxes expand to blocks here.
  s->key_counts.clear();
  forEachBlockCount(
      s, [s](const BlockKey& key, int count) { s->key_counts.emplace_back(key, count); });
}

int BlockLookup::regionMinPoints(const cv::Rect& region, uint64_t valid_points) const {
  // Scaled by the share of the region's pixels that hold a measurement: a dense region keeps
  // the full threshold against its few outliers, while a sparsely matched one (weak texture,
  // far surfaces: 1 pixel in 16 leaves ~4 points per block) keeps its blocks. At least 1.
  const int min_points = config_.histogram_min_points;
  if (min_points <= 0) return 0;
  const uint64_t pixels = static_cast<uint64_t>(region.area());
  return static_cast<int>(std::max<uint64_t>(1, (min_points * valid_points + pixels - 1) / pixels));
}

bool BlockLookup::passesFilter(const RegionScratch& s, const BlockKey& key, int min_points) const {
  if (min_points <= 0) return true;
  for (const auto& [k, count] : s.key_counts)
    if (k == key) return count >= min_points;
  return false;
}

void BlockLookup::runRegionAccelerated(const cv::Rect& region, RegionScratch* s) const {
  // The histogram straight into the filter: no per-block list in between.
  s->passing.clear();
  const int min_points = regionMinPoints(region, s->stats.valid_points);
  forEachBlockCount(s, [s, min_points](const BlockKey& key, int count) {
    if (min_points > 0 && count < min_points) {
      ++s->stats.blocks_filtered;
      return;
    }
    s->passing.push_back(key);
  });
}

void BlockLookup::runRegionNaive(const MeasurementImage& m, const cv::Rect& region,
                                 BlockOctree* octree, bool allocate, RegionScratch* s) const {
  const bool filter = config_.histogram_min_points > 0;
  int min_points = 0;
  if (filter) {
    gatherHistogram(s);
    min_points = regionMinPoints(region, s->stats.valid_points);
    for (const auto& [key, count] : s->key_counts) s->stats.blocks_filtered += count < min_points;
  }
  s->stats.valid_points = 0;  // counted with the boxes; counted again below
  for (int v = region.y; v < region.y + region.height; ++v) {
    const float* depth_row = m.depths() + static_cast<size_t>(v) * m.width();
    for (int u = region.x; u < region.x + region.width; ++u) {
      BandBox box;
      if (!bandBoxOfPixel(depth_row, u, v, &box)) continue;
      ++s->stats.valid_points;
      forEachKeyInBox(box.lo, box.hi, [&](const BlockKey& key) {
        if (filter && !passesFilter(*s, key, min_points)) return;
        bool allocated = false;
        ++s->stats.octree_searches;
        VoxelBlock* block = allocate ? octree->findOrAllocate(key, &allocated) : octree->find(key);
        s->stats.blocks_allocated += allocated;
        if (block != nullptr && (s->found.empty() || s->found.back() != block))
          s->found.push_back(block);
        if (block == nullptr && !allocate && BlockOctree::keyInRange(key) &&
            (s->not_found.empty() || s->not_found.back() != key))
          s->not_found.push_back(key);
      });
    }
  }
}

}  // namespace stereo_fusion
