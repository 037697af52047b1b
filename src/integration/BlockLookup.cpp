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

BlockLookup::BlockLookup(const MapperConfig& config, ThreadPool* pool, bool allow_simd)
    : config_(config), pool_(pool), use_avx2_(allow_simd && avx2Supported()) {}

BlockLookup::PixelGeometry BlockLookup::pixelGeometry(const StereoFrame& frame,
                                                      const BlockOctree& octree) const {
  PixelGeometry g;
  g.R_world_camera = frame.T_world_camera.linear();
  g.t_world_camera = frame.T_world_camera.translation();
  const StereoCamera& cam = frame.camera;
  g.fb = cam.fx() * cam.baseline();
  g.inv_fb = 1.0 / g.fb;
  g.cx = cam.cx();
  g.cy = cam.cy();
  g.inv_fx = 1.0 / cam.fx();
  g.inv_fy = 1.0 / cam.fy();
  g.inv_block_size = 1.0 / octree.blockSize();
  g.min_depth_m = config_.min_depth_m;
  g.max_depth_m = config_.max_depth_m;
  g.levels = config_.levels;
  const TruncationBand band = config_.truncationBand();
  for (int level = 0; level < kNumLevels; ++level) {
    g.band_m[level] = band.measurementM(level);
    g.band_blocks[level] = g.band_m[level] * g.inv_block_size;
  }
  // A voxel centre that fusion reads at a pixel projects within half a pixel of its centre on
  // each image axis: within 0.5·√2 pixel footprints of the pixel's ray (0.75 for margin).
  g.lateral_blocks_per_m = kLateralMarginPx / std::min(cam.fx(), cam.fy()) * g.inv_block_size;
  g.bands_non_negative = true;
  for (double b : g.band_blocks) g.bands_non_negative = g.bands_non_negative && b >= 0.0;
  return g;
}

// Inline: called for every pixel (a call per pixel cost a fifth of the lookup).
inline bool BlockLookup::bandBoxOfPixel(float d, int u, int v, BandBox* box) const {
  const PixelGeometry& g = geometry_;
  if (!(d > 0.0f) || !std::isfinite(d)) return false;
  const double z = g.fb / d;
  if (!(z >= g.min_depth_m && z <= g.max_depth_m)) return false;
  const double p_camera[3] = {(u - g.cx) * z * g.inv_fx, (v - g.cy) * z * g.inv_fy, z};
  // The band along the ray: the surface point ± Φ in the ray's direction, widened by the
  // lateral margin (kLateralMarginPx at the far end). All sums spelled out in the AVX2 path's order:
  // Eigen's R·p adds the z row as a0 + (a1 + a2) but the x and y rows as (a0 + a1) + a2, and
  // a point within an ulp of a block face would land in a different block on each path.
  const int level = levelForDepth(z, g.levels);
  // ±Φ along the ray moves the point by Φ·p/‖p‖; Φ·p/z bounds it (‖p‖ ≥ z) without a square
  // root or a division per pixel (1/z = d/(f·b)), at most ‖p‖/z longer: 1.2 at a 640×480
  // image's corners for f = 576 px, 1 on the optical axis.
  const double along = g.band_blocks[level] * (static_cast<double>(d) * g.inv_fb);  // blocks per metre of R·p
  const double lateral = (z + g.band_m[level]) * g.lateral_blocks_per_m;  // blocks
  const Eigen::Matrix3d& R = g.R_world_camera;
  Eigen::Vector3d lo, hi;
  for (int i = 0; i < 3; ++i) {
    const double ray = (R(i, 0) * p_camera[0] + R(i, 1) * p_camera[1]) + R(i, 2) * p_camera[2];  // world − camera centre
    const double centre = (ray + g.t_world_camera[i]) * g.inv_block_size;
    const double half = std::fabs(ray * along) + lateral;
    lo[i] = centre - half;
    hi[i] = centre + half;
  }
  box->lo = BlockOctree::keyForBlockCoordinates(lo);
  box->hi = BlockOctree::keyForBlockCoordinates(hi);
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
__attribute__((always_inline)) inline void BlockLookup::countBox(const BandBox& box, RegionScratch* s, size_t* last) const {
  ++s->stats.valid_points;
  if (*last < s->boxes.size() && s->boxes[*last].first == box) {
    ++s->boxes[*last].second;
    return;
  }
  *last = countInBoxes(box, s);
}

__attribute__((always_inline)) inline size_t BlockLookup::countInBoxes(const BandBox& box, RegionScratch* s) const {
  // Boxes are distinct, so the search order does not matter; from the newest, since a
  // changed box is most often one just seen (a neighbour in the row or the row above).
  for (size_t i = s->boxes.size(); i-- > 0;) {
    if (s->boxes[i].first == box) {
      ++s->boxes[i].second;
      return i;
    }
  }
  s->boxes.emplace_back(box, 1);
  return s->boxes.size() - 1;
}

// The reference per-pixel path: every pixel through bandBoxOfPixel().
void BlockLookup::countRegionBoxesScalar(const StereoFrame& frame, const cv::Rect& region, RegionScratch* s) const {
  size_t last = 0;
  for (int v = region.y; v < region.y + region.height; ++v) {
    const float* disparity_row = frame.disparity_px.ptr<float>(v);
    for (int u = region.x; u < region.x + region.width; ++u) {
      BandBox box;
      if (bandBoxOfPixel(disparity_row[u], u, v, &box)) countBox(box, s, &last);
    }
  }
}

#ifdef STEREO_FUSION_HAVE_AVX2_LOOKUP
// Four pixels at a time: the same double operations as bandBoxOfPixel() in the same order
// (no FMA: the target is AVX2 only), so the boxes are identical; a row's last width % 4
// pixels go through bandBoxOfPixel(). The whole region in one call: a region row is only a
// few groups, too few to pay for setting the constants up per row.
// Needs geometry_.bands_non_negative (see the key range test below).
__attribute__((target("avx2"))) void BlockLookup::countRegionBoxesAvx2(const StereoFrame& frame,
                                                                       const cv::Rect& region,
                                                                       RegionScratch* s) const {
  const PixelGeometry& g = geometry_;
  const __m256d zero = _mm256_setzero_pd(), infinity = _mm256_set1_pd(HUGE_VAL);
  const __m256d inv_fb = _mm256_set1_pd(g.inv_fb);
  const __m256d fb = _mm256_set1_pd(g.fb), min_z = _mm256_set1_pd(g.min_depth_m), max_z = _mm256_set1_pd(g.max_depth_m);
  const __m256d cx = _mm256_set1_pd(g.cx);
  const __m256d inv_fx = _mm256_set1_pd(g.inv_fx), inv_fy = _mm256_set1_pd(g.inv_fy);
  const __m256d scale2 = _mm256_set1_pd(g.levels.scale2_min_depth_m), scale4 = _mm256_set1_pd(g.levels.scale4_min_depth_m);
  const __m256d band0 = _mm256_set1_pd(g.band_blocks[0]), band1 = _mm256_set1_pd(g.band_blocks[1]),
                band2 = _mm256_set1_pd(g.band_blocks[2]);
  const __m256d band0_m = _mm256_set1_pd(g.band_m[0]), band1_m = _mm256_set1_pd(g.band_m[1]),
                band2_m = _mm256_set1_pd(g.band_m[2]);
  const __m256d lateral_per_m = _mm256_set1_pd(g.lateral_blocks_per_m);
  const __m256d sign_bit = _mm256_set1_pd(-0.0);
  const __m256d max_key = _mm256_set1_pd(BlockOctree::kMaxKey), min_key = _mm256_set1_pd(-BlockOctree::kMaxKey);
  __m256d r[3][3], t[3];
  for (int i = 0; i < 3; ++i) {
    for (int k = 0; k < 3; ++k) r[i][k] = _mm256_set1_pd(g.R_world_camera(i, k));
    t[i] = _mm256_set1_pd(g.t_world_camera[i]);
  }
  const __m256d inv_block = _mm256_set1_pd(g.inv_block_size);
  // Small integers are exact in double, so stepping u by 4.0 gives the converted int exactly.
  const __m256d four = _mm256_set1_pd(4.0);
  const __m256d u_first = _mm256_add_pd(_mm256_set1_pd(region.x), _mm256_setr_pd(0.0, 1.0, 2.0, 3.0));
  const int u_end = region.x + region.width, u_vector_end = region.x + (region.width & ~3);

  // countBox()'s previous box, broadcast to all lanes; refreshed whenever countBox() runs.
  size_t last = 0;
  __m128i last_key[6] = {_mm_setzero_si128(), _mm_setzero_si128(), _mm_setzero_si128(),
                         _mm_setzero_si128(), _mm_setzero_si128(), _mm_setzero_si128()};
  int* last_count = nullptr;  // nullptr until the region has a box
  auto track_last = [&] {
    std::pair<BandBox, int>& entry = s->boxes[last];  // may have moved: boxes can grow
    const BandBox& b = entry.first;
    last_key[0] = _mm_set1_epi32(b.lo.x), last_key[1] = _mm_set1_epi32(b.lo.y), last_key[2] = _mm_set1_epi32(b.lo.z);
    last_key[3] = _mm_set1_epi32(b.hi.x), last_key[4] = _mm_set1_epi32(b.hi.y), last_key[5] = _mm_set1_epi32(b.hi.z);
    last_count = &entry.second;
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
    const float* disparity_row = frame.disparity_px.ptr<float>(v);
    const __m256d y_offset = _mm256_set1_pd(v - g.cy);
    __m256d u_px = u_first;
    int u = region.x;
    for (; u < u_vector_end; u += 4, u_px = _mm256_add_pd(u_px, four)) {
      const __m256d d = _mm256_cvtps_pd(_mm_loadu_ps(disparity_row + u));
      // d > 0 and finite (NaN fails both ordered comparisons).
      __m256d valid = _mm256_and_pd(_mm256_cmp_pd(d, zero, _CMP_GT_OQ), _mm256_cmp_pd(d, infinity, _CMP_LT_OQ));
      if (_mm256_movemask_pd(valid) == 0) continue;
      const __m256d z = _mm256_div_pd(fb, d);
      valid = _mm256_and_pd(valid, _mm256_and_pd(_mm256_cmp_pd(z, min_z, _CMP_GE_OQ), _mm256_cmp_pd(z, max_z, _CMP_LE_OQ)));
      const __m256d p[3] = {_mm256_mul_pd(_mm256_mul_pd(_mm256_sub_pd(u_px, cx), z), inv_fx),
                            _mm256_mul_pd(_mm256_mul_pd(y_offset, z), inv_fy), z};
      // Level of eq. 3.2 → band, lane by lane.
      const __m256d at_least_2 = _mm256_cmp_pd(z, scale2, _CMP_GE_OQ), at_least_4 = _mm256_cmp_pd(z, scale4, _CMP_GE_OQ);
      const __m256d band = _mm256_blendv_pd(_mm256_blendv_pd(band0, band1, at_least_2), band2, at_least_4);
      const __m256d band_m = _mm256_blendv_pd(_mm256_blendv_pd(band0_m, band1_m, at_least_2), band2_m, at_least_4);
      // bandBoxOfPixel()'s ray segment ± Φ and lateral margin, in its operation order.
      const __m256d along = _mm256_mul_pd(band, _mm256_mul_pd(d, inv_fb));
      const __m256d lateral = _mm256_mul_pd(_mm256_add_pd(z, band_m), lateral_per_m);
      __m128i key[6];  // lo x, y, z, hi x, y, z of the four lanes
      for (int i = 0; i < 3; ++i) {
        const __m256d ray = _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(r[i][0], p[0]), _mm256_mul_pd(r[i][1], p[1])),
                                          _mm256_mul_pd(r[i][2], p[2]));
        const __m256d centre = _mm256_mul_pd(_mm256_add_pd(ray, t[i]), inv_block);
        const __m256d half = _mm256_add_pd(_mm256_andnot_pd(sign_bit, _mm256_mul_pd(ray, along)), lateral);
        const __m256d lo_d = _mm256_floor_pd(_mm256_sub_pd(centre, half));
        const __m256d hi_d = _mm256_floor_pd(_mm256_add_pd(centre, half));
        // keyInRange() of lo and hi, i.e. |key| ≤ kMaxKey with NaN failing: with half ≥ 0,
        // lo ≤ hi whenever neither is NaN, so lo ≥ -kMaxKey and hi ≤ kMaxKey cover all four bounds.
        valid = _mm256_and_pd(valid, _mm256_and_pd(_mm256_cmp_pd(lo_d, min_key, _CMP_GE_OQ),
                                                   _mm256_cmp_pd(hi_d, max_key, _CMP_LE_OQ)));
        key[i] = _mm256_cvttpd_epi32(lo_d);
        key[3 + i] = _mm256_cvttpd_epi32(hi_d);
      }
      const int lanes = _mm256_movemask_pd(valid);
      if (lanes == 0) continue;
      // Bit i: lane i's box equals lane i-1's (lane 0: the previous box's). Neighbouring
      // pixels almost always share a box, so most groups are counted at once and most others
      // call countBox() only where the box changes.
      __m128i same = _mm_set1_epi32(-1);
      for (int k = 0; k < 6; ++k)
        same = _mm_and_si128(same, _mm_cmpeq_epi32(key[k], _mm_alignr_epi8(key[k], last_key[k], 12)));
      int repeats = _mm_movemask_ps(_mm_castsi128_ps(same));
      if (last_count == nullptr) repeats &= ~1;  // lane 0 has no previous box to repeat
      if (lanes == 15 && repeats == 15) {
        repeat_box(4);
        continue;
      }
      alignas(16) int32_t keys[6][4];
      for (int k = 0; k < 6; ++k) _mm_store_si128(reinterpret_cast<__m128i*>(keys[k]), key[k]);
      auto box_of_lane = [&](int lane) {
        return BandBox{{keys[0][lane], keys[1][lane], keys[2][lane]}, {keys[3][lane], keys[4][lane], keys[5][lane]}};
      };
      if (lanes == 15) {
        // Only the lanes where the box changes search the boxes; the runs between them
        // repeat the previous box (lane 0 only if there is one: see above).
        int counted = 0;  // lanes before this one are counted
        for (int changes = ~repeats & 15; changes != 0; changes &= changes - 1) {
          const int lane = __builtin_ctz(changes);
          if (lane > counted) repeat_box(lane - counted);
          // The box differs from its predecessor, boxes[last]: countBox() would search.
          ++s->stats.valid_points;
          last = countInBoxes(box_of_lane(lane), s);
          last_count = &s->boxes[last].second;
          counted = lane + 1;
        }
        if (counted < 4) repeat_box(4 - counted);
        track_last();
        continue;
      }
      // Some lanes invalid: a lane's predecessor is the previous valid lane, so compare lane by lane.
      for (int lane = 0; lane < 4; ++lane)
        if ((lanes >> lane) & 1) count_box(box_of_lane(lane));
    }
    for (; u < u_end; ++u) {
      BandBox box;
      if (bandBoxOfPixel(disparity_row[u], u, v, &box)) count_box(box);
    }
  }
}

#else
void BlockLookup::countRegionBoxesAvx2(const StereoFrame& frame, const cv::Rect& region, RegionScratch* s) const {
  countRegionBoxesScalar(frame, region, s);  // not x86: no vector path
}
#endif

void BlockLookup::countRegionBoxes(const StereoFrame& frame, const cv::Rect& region, RegionScratch* s) const {
  s->boxes.clear();
  if (use_avx2_ && geometry_.bands_non_negative)
    countRegionBoxesAvx2(frame, region, s);
  else
    countRegionBoxesScalar(frame, region, s);
  if (s->boxes.empty()) return;
  s->boxes_lo = s->boxes.front().first.lo;
  s->boxes_hi = s->boxes.front().first.hi;
  for (const auto& box_count : s->boxes) {
    s->boxes_lo = componentMin(s->boxes_lo, box_count.first.lo);
    s->boxes_hi = componentMax(s->boxes_hi, box_count.first.hi);
  }
}

template <typename Visit>
void BlockLookup::forEachBlockCount(RegionScratch* s, Visit&& visit) const {
  if (s->boxes.empty()) return;
  // Boxes overlap heavily (coarse levels reach 2 blocks either side), so count on a dense
  // grid over their union when it is small, which it is unless the region straddles a large
  // depth jump; otherwise merge keys linearly.
  const BlockKey lo = s->boxes_lo, hi = s->boxes_hi;
  const int64_t nx = int64_t{hi.x} - lo.x + 1, ny = int64_t{hi.y} - lo.y + 1, nz = int64_t{hi.z} - lo.z + 1;
  if (nx * ny * nz <= kMaxDenseHistogramCells) {
    // + kDenseRowPadding: a box row of up to 8 cells is added as two runs of four, the cells
    // past its end (the next row's, or this padding) getting + 0.
    constexpr size_t kDenseRowPadding = 8;
    s->dense_counts.assign(static_cast<size_t>(nx * ny * nz) + kDenseRowPadding, 0);
    for (const auto& box_count : s->boxes) {
      const BandBox& box = box_count.first;
      const int32_t width = box.hi.x - box.lo.x + 1;
      auto row_of = [&](int32_t y, int32_t z) {
        return &s->dense_counts[static_cast<size_t>(((z - lo.z) * ny + (y - lo.y)) * nx + (box.lo.x - lo.x))];
      };
#if defined(__SSE2__)
      if (width <= 8) {  // always, unless Φ is over 3.5 blocks
        const __m128i lane = _mm_setr_epi32(0, 1, 2, 3), count = _mm_set1_epi32(box_count.second);
        const __m128i add_first = _mm_and_si128(count, _mm_cmplt_epi32(lane, _mm_set1_epi32(width)));
        const __m128i add_second = _mm_and_si128(count, _mm_cmplt_epi32(lane, _mm_set1_epi32(width - 4)));
        for (int32_t z = box.lo.z; z <= box.hi.z; ++z)
          for (int32_t y = box.lo.y; y <= box.hi.y; ++y) {
            __m128i* cells = reinterpret_cast<__m128i*>(row_of(y, z));
            _mm_storeu_si128(cells, _mm_add_epi32(_mm_loadu_si128(cells), add_first));
            if (width > 4) _mm_storeu_si128(cells + 1, _mm_add_epi32(_mm_loadu_si128(cells + 1), add_second));
          }
        continue;
      }
#endif
      for (int32_t z = box.lo.z; z <= box.hi.z; ++z)
        for (int32_t y = box.lo.y; y <= box.hi.y; ++y) {
          int* row = row_of(y, z);
          for (int32_t x = 0; x < width; ++x) row[x] += box_count.second;
        }
    }
    const int* count = s->dense_counts.data();
    for (int32_t z = lo.z; z <= hi.z; ++z)
      for (int32_t y = lo.y; y <= hi.y; ++y)
        for (int32_t x = lo.x; x <= hi.x; ++x, ++count)
          if (*count > 0) visit(BlockKey{x, y, z}, *count);
    return;
  }
  s->sparse_counts.clear();
  // Not a structured binding: lambdas may capture those only from C++20 (clang refuses).
  for (const auto& box_count : s->boxes) {
    const auto& box = box_count.first;
    const auto count = box_count.second;
    forEachKeyInBox(box.lo, box.hi, [&](const BlockKey& key) {
      auto it = std::find_if(s->sparse_counts.begin(), s->sparse_counts.end(),
                             [&](const auto& entry) { return entry.first == key; });
      if (it == s->sparse_counts.end())
        s->sparse_counts.emplace_back(key, count);
      else
        it->second += count;
    });
  }
  for (const auto& [key, count] : s->sparse_counts) visit(key, count);
}

void BlockLookup::gatherHistogram(const StereoFrame& frame, const cv::Rect& region, RegionScratch* s) const {
  // Count points per distinct band box first and expand boxes to blocks after.
  countRegionBoxes(frame, region, s);
  s->key_counts.clear();
  forEachBlockCount(s, [s](const BlockKey& key, int count) { s->key_counts.emplace_back(key, count); });
}

bool BlockLookup::passesFilter(const RegionScratch& s, const BlockKey& key) const {
  if (config_.histogram_min_points <= 0) return true;
  for (const auto& [k, count] : s.key_counts)
    if (k == key) return count >= config_.histogram_min_points;
  return false;
}

void BlockLookup::runRegionAccelerated(const StereoFrame& frame, const cv::Rect& region,
                                       RegionScratch* s) const {
  // The histogram straight into the filter: no per-block list in between.
  countRegionBoxes(frame, region, s);
  s->passing.clear();
  const int min_points = config_.histogram_min_points;
  forEachBlockCount(s, [s, min_points](const BlockKey& key, int count) {
    if (min_points > 0 && count < min_points) {
      ++s->stats.blocks_filtered;
      return;
    }
    s->passing.push_back(key);
  });
}

void BlockLookup::collectSortedDistinctKeys(size_t num_regions) {
  // Neighbouring regions share most of their blocks (≈10 regions per block at 1 cm): one
  // octree search per distinct block of the frame instead of one per (region, block).
  frame_keys_.clear();
  bool any = false;
  BlockKey lo, hi;
  for (size_t r = 0; r < num_regions; ++r) {
    const RegionScratch& s = scratch_[r];
    if (s.passing.empty()) continue;  // else it has boxes, and they hold its keys
    lo = any ? componentMin(lo, s.boxes_lo) : s.boxes_lo;
    hi = any ? componentMax(hi, s.boxes_hi) : s.boxes_hi;
    any = true;
  }
  if (!any) return;
  // The frame's blocks lie in the camera frustum, a small box: a bit per block of it
  // de-duplicates with no hashing and reads back sorted with no sort.
  if (frame_key_bitmap_.reset(lo, hi)) {
    for (size_t r = 0; r < num_regions; ++r)
      for (const BlockKey& key : scratch_[r].passing) frame_key_bitmap_.insert(key);
    frame_key_bitmap_.appendSorted(&frame_keys_);
    return;
  }
  size_t total = 0;
  for (size_t r = 0; r < num_regions; ++r) total += scratch_[r].passing.size();
  frame_key_set_.reset(total);
  for (size_t r = 0; r < num_regions; ++r)
    for (const BlockKey& key : scratch_[r].passing)
      if (frame_key_set_.insert(key)) frame_keys_.push_back(key);
  std::sort(frame_keys_.begin(), frame_keys_.end());
}

void BlockLookup::runRegionNaive(const StereoFrame& frame, const cv::Rect& region, BlockOctree* octree,
                                 bool allocate, RegionScratch* s) const {
  const bool filter = config_.histogram_min_points > 0;
  if (filter) {
    gatherHistogram(frame, region, s);
    for (const auto& [key, count] : s->key_counts)
      s->stats.blocks_filtered += count < config_.histogram_min_points;
    s->stats.valid_points = 0;  // counted again below
  }
  for (int v = region.y; v < region.y + region.height; ++v) {
    const float* disparity_row = frame.disparity_px.ptr<float>(v);
    for (int u = region.x; u < region.x + region.width; ++u) {
      BandBox box;
      if (!bandBoxOfPixel(disparity_row[u], u, v, &box)) continue;
      ++s->stats.valid_points;
      forEachKeyInBox(box.lo, box.hi, [&](const BlockKey& key) {
        if (filter && !passesFilter(*s, key)) return;
        bool allocated = false;
        ++s->stats.octree_searches;
        VoxelBlock* block = allocate ? octree->findOrAllocate(key, &allocated) : octree->find(key);
        s->stats.blocks_allocated += allocated;
        if (block != nullptr && (s->found.empty() || s->found.back() != block)) s->found.push_back(block);
        if (block == nullptr && !allocate && BlockOctree::keyInRange(key) &&
            (s->not_found.empty() || s->not_found.back() != key))
          s->not_found.push_back(key);
      });
    }
  }
}

LookupStats BlockLookup::run(const StereoFrame& frame, BlockOctree* octree, std::vector<VoxelBlock*>* queue,
                             std::vector<BlockKey>* missing) {
  const bool allocate = missing == nullptr;
  if (missing) missing->clear();
  const int region_px = config_.lookup_region_px;
  const int cols = (frame.disparity_px.cols + region_px - 1) / region_px;
  const int rows = (frame.disparity_px.rows + region_px - 1) / region_px;
  const size_t num_regions = static_cast<size_t>(cols) * rows;
  if (scratch_.size() < num_regions) scratch_.resize(num_regions);
  geometry_ = pixelGeometry(frame, *octree);

  const bool accelerated = config_.lookup_mode == LookupMode::kAccelerated;
  pool_->parallelFor(num_regions, 4, [&](size_t begin, size_t end) {
    for (size_t r = begin; r < end; ++r) {
      RegionScratch& s = scratch_[r];
      s.found.clear();
      s.not_found.clear();
      s.stats = LookupStats{};
      const int x = static_cast<int>(r % cols) * region_px;
      const int y = static_cast<int>(r / cols) * region_px;
      const cv::Rect region(x, y, std::min(region_px, frame.disparity_px.cols - x),
                            std::min(region_px, frame.disparity_px.rows - y));
      if (accelerated)
        runRegionAccelerated(frame, region, &s);
      else
        runRegionNaive(frame, region, octree, allocate, &s);
    }
  });

  LookupStats total;
  for (size_t r = 0; r < num_regions; ++r) {
    const LookupStats& stats = scratch_[r].stats;
    total.valid_points += stats.valid_points;
    total.octree_searches += stats.octree_searches;
    total.blocks_allocated += stats.blocks_allocated;
    total.blocks_filtered += stats.blocks_filtered;
  }
  queue->clear();
  if (accelerated) {
    // The queue goes out in key order: order the keys here, contiguous, rather than the blocks
    // afterwards through a pointer per comparison.
    collectSortedDistinctKeys(num_regions);
    frame_blocks_.resize(frame_keys_.size());
    frame_allocated_.resize(frame_keys_.size());
    // Sorted keys in batches: neighbouring keys share most of their octree path.
    pool_->parallelFor(frame_keys_.size(), 64, [&](size_t begin, size_t end) {
      if (allocate)
        octree->findOrAllocateBatch(&frame_keys_[begin], end - begin, &frame_blocks_[begin], &frame_allocated_[begin]);
      else
        octree->findBatch(&frame_keys_[begin], end - begin, &frame_blocks_[begin]);
    });
    total.octree_searches += frame_keys_.size();
    for (size_t i = 0; i < frame_keys_.size(); ++i) {
      if (allocate) total.blocks_allocated += frame_allocated_[i];
      if (frame_blocks_[i] != nullptr)
        queue->push_back(frame_blocks_[i]);
      else if (!allocate && BlockOctree::keyInRange(frame_keys_[i]))
        missing->push_back(frame_keys_[i]);  // in key order, as frame_keys_
    }
  } else {
    // Regions overlap in blocks: each block once, in key order.
    for (size_t r = 0; r < num_regions; ++r) queue->insert(queue->end(), scratch_[r].found.begin(), scratch_[r].found.end());
    std::sort(queue->begin(), queue->end(),
              [](const VoxelBlock* a, const VoxelBlock* b) { return a->key < b->key; });
    queue->erase(std::unique(queue->begin(), queue->end()), queue->end());
    if (missing) {
      for (size_t r = 0; r < num_regions; ++r)
        missing->insert(missing->end(), scratch_[r].not_found.begin(), scratch_[r].not_found.end());
      std::sort(missing->begin(), missing->end());
      missing->erase(std::unique(missing->begin(), missing->end()), missing->end());
    }
  }
  total.blocks_missing = missing ? missing->size() : 0;
  total.blocks_queued = queue->size() + total.blocks_missing;
  return total;
}

}  // namespace stereo_fusion
