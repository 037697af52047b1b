#pragma once
#include <cstdint>
#include <utility>
#include <vector>

#include "stereo_fusion/integration/MeasurementImage.h"
#include "stereo_fusion/integration/StereoFrame.h"
#include "stereo_fusion/map/TruncationBand.h"
#include "stereo_fusion/planning/PlanningBlock.h"
#include "stereo_fusion/util/ThreadPool.h"

namespace stereo_fusion {

struct FreeSpaceStats {
  uint64_t nodes_visited = 0;    ///< octree nodes of the frustum tested (all sizes)
  uint64_t cells_seen_free = 0;  ///< cells this frame saw empty (newly or again)
};

/// The space one frame saw empty, as planning cells (the free half of "free vs unknown").
///
/// A pixel with a usable depth z says the space along its ray up to z − Φ (the band of the
/// measurement's level, TruncationBand::measurementM()) is empty; a pixel without one says
/// nothing, or with `unmeasured_range_m` > 0 that its ray is empty up to that range. A cell is
/// seen free when every pixel of its footprint that says something says it is empty at least to
/// the cell's far side: per image tile (8 px, and a min/max pyramid of them) the smallest and
/// largest such "free depth", a tile whose pixels say nothing blocking it (unknown stays unknown
/// where the matcher found no texture).
///
/// The test runs on an octree of the frustum's cells, from 32³-cell nodes down to cells: a node
/// whose footprint is free beyond its far side is free whole, one whose footprint is free
/// nowhere as far as its near side is skipped whole, the rest split. A node is skipped too when
/// it starts beyond every finest tile's smallest free depth in its footprint: each of its parts
/// sees one of those tiles, so none can be free (the band of a ground seen at a grazing angle
/// would otherwise be visited cell by cell). So the cost follows the surfaces in view, not the
/// volume or the pixel count: coarse where far or uniform.
class FreeSpaceRecorder {
 public:
  struct Params {
    double cell_m = 0.08;
    double unmeasured_range_m = 0.0;
    TruncationBand band{0.02, 4.0};
    /// false: without the skip past the tiles' smallest free depths (the same cells, more
    /// nodes visited), the reference the tests compare with.
    bool skip_past_tile_minima = true;
  };
  FreeSpaceRecorder(const Params& params, ThreadPool* pool) : params_(params), pool_(pool) {}

  /// The cells `frame` saw empty, per planning block (only blocks with some), sorted by key.
  FreeSpaceStats record(const StereoFrame& frame, const MeasurementImage& measurements,
                        std::vector<std::pair<BlockKey, PlanningBlock::Bits>>* seen_free);

 private:
  struct TileLevel {
    int tile_shift = 0;  // tiles are 2^tile_shift px square (pixel >> shift: its tile)
    int tiles_x = 0, tiles_y = 0;
    // Per tile: the smallest and largest free depth of its pixels, and the largest of its
    // finest tiles' smallest ones; together, as the walk reads them.
    struct Bounds {
      float min_free_m, max_free_m, max_min_free_m;
    };
    std::vector<Bounds> bounds;
  };
  void buildTiles(const MeasurementImage& measurements);

  Params params_;
  ThreadPool* pool_;
  std::vector<TileLevel> pyramid_;
};

}  // namespace stereo_fusion
